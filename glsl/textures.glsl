/* Image textures plugged into the Principled BSDF (SL_HAS_*_MAP, per material): base colour,
 * metallic and roughness (their red channel) replace the constant values; a tangent-space normal
 * map (through a Normal Map node) bends the shading normal. The textures come from Blender's own
 * image cache: an sRGB image is decoded to linear on sampling, a Non-Color one is not. */

/* Texel coordinate i of a map n texels wide under the Image Texture node's Extension: 0 repeat,
 * 1 extend (the edge texel), 2 clip (-1: outside, transparent black), 3 mirror. */
int wrap_texel(int i, int n, int extension)
{
  if (extension == 1) {
    return clamp(i, 0, n - 1);
  }
  if (extension == 2) {
    return (i < 0 || i >= n) ? -1 : i;
  }
  if (extension == 3) {
    int period = i - (2 * n) * int(floor(float(i) / float(2 * n)));
    return period < n ? period : 2 * n - 1 - period;
  }
  return i - n * int(floor(float(i) / float(n)));
}

vec4 fetch_wrapped(sampler2D map, ivec2 p, ivec2 size, int extension)
{
  ivec2 q = ivec2(wrap_texel(p.x, size.x, extension), wrap_texel(p.y, size.y, extension));
  return (q.x < 0 || q.y < 0) ? vec4(0.0) : texelFetch(map, q, 0);
}

/* A map's value at uv as Cycles filters it: the nearest texel ("Closest") or the bilinear blend of
 * the four around uv ("Linear", after an sRGB image's decoding), the texels outside the image
 * given by the Extension. */
vec4 sample_map(sampler2D map, vec2 uv, bool closest, int extension)
{
  ivec2 size = textureSize(map, 0);
  vec2 x = uv * vec2(size);
  if (closest) {
    return fetch_wrapped(map, ivec2(floor(x)), size, extension);
  }
  x -= 0.5;
  ivec2 p = ivec2(floor(x));
  vec2 f = x - floor(x);
  vec4 a = mix(fetch_wrapped(map, p, size, extension), fetch_wrapped(map, p + ivec2(1, 0), size, extension), f.x);
  vec4 b = mix(fetch_wrapped(map, p + ivec2(0, 1), size, extension),
               fetch_wrapped(map, p + ivec2(1, 1), size, extension), f.x);
  return mix(a, b, f.y);
}

/* The maps' UVs: the Image Texture node's Vector (a Mapping node on the UV map). */
vec2 map_uv(MaterialData m, vec2 uv)
{
  return vec2(dot(m.uv_x.xy, uv) + m.uv_x.z, dot(m.uv_y.xy, uv) + m.uv_y.z);
}

#define MAP_EXTENSION int(material.uv_x.w + 0.5)
#ifdef SL_BASE_COLOR_MAP_CLOSEST
#  define SAMPLE_BASE_COLOR(uv) sample_map(base_color_map, uv, true, MAP_EXTENSION)
#else
#  define SAMPLE_BASE_COLOR(uv) sample_map(base_color_map, uv, false, MAP_EXTENSION)
#endif
#ifdef SL_METALLIC_MAP_CLOSEST
#  define SAMPLE_METALLIC(uv) sample_map(metallic_map, uv, true, MAP_EXTENSION)
#else
#  define SAMPLE_METALLIC(uv) sample_map(metallic_map, uv, false, MAP_EXTENSION)
#endif
#ifdef SL_ROUGHNESS_MAP_CLOSEST
#  define SAMPLE_ROUGHNESS(uv) sample_map(roughness_map, uv, true, MAP_EXTENSION)
#else
#  define SAMPLE_ROUGHNESS(uv) sample_map(roughness_map, uv, false, MAP_EXTENSION)
#endif
#ifdef SL_NORMAL_MAP_CLOSEST
#  define SAMPLE_NORMAL(uv) sample_map(normal_map, uv, true, MAP_EXTENSION)
#else
#  define SAMPLE_NORMAL(uv) sample_map(normal_map, uv, false, MAP_EXTENSION)
#endif

MaterialData apply_material_maps(MaterialData m, vec2 uv)
{
#ifdef SL_HAS_BASE_COLOR_MAP
  vec4 texel = SAMPLE_BASE_COLOR(uv);
  vec3 base = texel.rgb;
  m.base_color.rgb = base;
#  ifdef SL_ALPHA_FROM_BASE_MAP
  m.emission.w *= texel.a;
#  endif
  /* the empirical models' derived diffuse and ambient colours follow the texture */
  m.diffuse_color.rgb = base * (1.0 - m.params.y);
  m.ambient_color.rgb = m.diffuse_color.rgb;
#endif
#ifdef SL_HAS_METALLIC_MAP
  m.params.y = clamp(SAMPLE_METALLIC(uv).r, 0.0, 1.0);
#endif
#ifdef SL_HAS_ROUGHNESS_MAP
  m.params.x = clamp(SAMPLE_ROUGHNESS(uv).r, 0.0, 1.0);
#endif
  return m;
}

/* Tangent space (T, B = sign (N x T), N) to world, then Blender's Normal Map strength:
 * normalize(mix(N, mapped, strength)). A degenerate tangent leaves the normal as it was. */
vec3 apply_normal_map(vec3 n, vec2 uv, vec4 tangent, float strength)
{
#ifdef SL_HAS_NORMAL_MAP
  vec3 t = tangent.xyz - n * dot(n, tangent.xyz);
  float t2 = dot(t, t);
  if (t2 < 1e-20) {
    return n;
  }
  t *= inversesqrt(t2);
  vec3 b = (tangent.w < 0.0 ? -1.0 : 1.0) * cross(n, t);
  vec3 c = SAMPLE_NORMAL(uv).rgb * 2.0 - 1.0;
  vec3 mapped = t * c.x + b * c.y + n * c.z;
  vec3 mixed = mix(n, mapped, strength);
  float len2 = dot(mixed, mixed);
  return len2 > 1e-20 ? mixed * inversesqrt(len2) : n;
#else
  return n;
#endif
}
