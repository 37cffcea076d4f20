/* Image textures plugged into the Principled BSDF (SL_HAS_*_MAP, per material): base colour,
 * metallic and roughness (their red channel) replace the constant values; a tangent-space normal
 * map (through a Normal Map node) bends the shading normal. The textures come from Blender's own
 * image cache: an sRGB image is decoded to linear on sampling, a Non-Color one is not. */

/* Nearest-texel lookup with repeat (the Image Texture node's "Closest"). */
vec4 texel_closest(sampler2D map, vec2 uv)
{
  ivec2 size = textureSize(map, 0);
  ivec2 p = clamp(ivec2(floor(fract(uv) * vec2(size))), ivec2(0), size - 1);
  return texelFetch(map, p, 0);
}

#ifdef SL_BASE_COLOR_MAP_CLOSEST
#  define SAMPLE_BASE_COLOR(uv) texel_closest(base_color_map, uv)
#else
#  define SAMPLE_BASE_COLOR(uv) texture(base_color_map, uv)
#endif
#ifdef SL_METALLIC_MAP_CLOSEST
#  define SAMPLE_METALLIC(uv) texel_closest(metallic_map, uv)
#else
#  define SAMPLE_METALLIC(uv) texture(metallic_map, uv)
#endif
#ifdef SL_ROUGHNESS_MAP_CLOSEST
#  define SAMPLE_ROUGHNESS(uv) texel_closest(roughness_map, uv)
#else
#  define SAMPLE_ROUGHNESS(uv) texture(roughness_map, uv)
#endif
#ifdef SL_NORMAL_MAP_CLOSEST
#  define SAMPLE_NORMAL(uv) texel_closest(normal_map, uv)
#else
#  define SAMPLE_NORMAL(uv) texture(normal_map, uv)
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
