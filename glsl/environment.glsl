/* The world as a radiance field (addon/blender/extract.py reads it, addon/reference/environment.py is the numpy
 * twin): the constant terms' sum plus up to SL_ENV_IMAGES image terms, each its Background
 * weight times an Environment Texture looked up in a direction, exactly as Cycles does
 * (kernel/camera/projection.h, svm_node_tex_environment). */

/* Cycles' equirectangular mapping: u = (pi - atan2(y, x)) / 2pi, v = 1 - acos(z) / pi: +X at
 * the image centre, +Y a quarter to the left of it, up (+Z) along the top row. */
vec2 equirect_uv(vec3 d)
{
  float len2 = dot(d, d);
  if (len2 <= 0.0) {
    return vec2(0.0);
  }
  float u = (d.x == 0.0 && d.y == 0.0) ? 0.5 : 0.5 - atan(d.y, d.x) * (0.5 * INV_PI);
  return vec2(u, 1.0 - acos_accurate(d.z * inversesqrt(len2)) * INV_PI);
}

/* The unit direction of equirectangular coordinates: the inverse of equirect_uv. */
vec3 equirect_direction(vec2 uv)
{
  float phi = PI - 2.0 * PI * uv.x;
  float theta = PI * (1.0 - uv.y);
  return vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
}

/* Cycles' mirror ball: the image is a chrome ball seen along +Y from -Y (u along +X, v along +Z). */
vec2 mirror_ball_uv(vec3 d)
{
  d = normalize(d);
  d.y -= 1.0;
  float div = 2.0 * sqrt(max(-0.5 * d.y, 0.0));
  if (div > 0.0) {
    d /= div;
  }
  return 0.5 * (d.xz + 1.0);
}

/* Bilinear lookup between texel centres (Cycles' "Linear"), repeating in both directions as
 * Cycles' environment images do (so the last half row at a pole mixes in the opposite edge, as
 * there); "Closest" takes the texel under uv. Done by hand with texelFetch: textures made from
 * Python carry no wrap setting. */
vec4 env_texel(sampler2D map, ivec2 size, int x, int y)
{
  x = x - size.x * int(floor(float(x) / float(size.x)));
  y = y - size.y * int(floor(float(y) / float(size.y)));
  return texelFetch(map, ivec2(x, y), 0);
}

vec4 env_lookup(sampler2D map, vec2 uv, bool closest)
{
  ivec2 size = textureSize(map, 0);
  vec2 p = uv * vec2(size);
  if (closest) {
    return env_texel(map, size, int(floor(p.x)), int(floor(p.y)));
  }
  p -= 0.5;
  vec2 i = floor(p);
  vec2 f = p - i;
  int x = int(i.x), y = int(i.y);
  return mix(mix(env_texel(map, size, x, y), env_texel(map, size, x + 1, y), f.x),
             mix(env_texel(map, size, x, y + 1), env_texel(map, size, x + 1, y + 1), f.x), f.y);
}

/* One image term: the world direction through the Mapping node (lookup), then the projection.
 * For the lighting field, kind.z > 0 clamps the luminance there (keeping the colour): the light
 * above it was split off as suns (addon/reference/environment.py split_suns). */
vec3 env_term(sampler2D map, mat4 lookup, vec4 kind, vec4 weight, vec3 d, bool clamp_bright)
{
  vec3 v = (lookup * vec4(d, 1.0)).xyz;
  vec2 uv = kind.x > 0.5 ? mirror_ball_uv(v) : equirect_uv(v);
  vec3 c = weight.rgb * env_lookup(map, uv, kind.y > 0.5).rgb;
  float y = dot(c, vec3(0.2126, 0.7152, 0.0722));
  return (clamp_bright && kind.z > 0.0 && y > kind.z) ? c * (kind.z / y) : c;
}

/* One equirectangular level, in rectangle rect (x, y, width, height in texels) of a texture of
 * size texels holding several (the chain, the prefiltered atlas), at uv: bilinearly between
 * texel centres by the GPU's filter. The level's border of one texel (addon/reference/environment.py
 * chain_layout) makes it repeat in u and reach the poles' values at v = 0 and 1
 * (bordered_level_pole), and keeps the filter off its neighbours. */
vec3 bordered_level(sampler2D map, vec4 rect, vec2 size, vec2 uv)
{
  vec2 p = rect.xy + vec2(fract(uv.x), clamp(uv.y, 0.0, 1.0)) * rect.zw;
  return textureLod(map, p / size, 0.0).rgb;
}

/* The equirectangular uv of the texel a pass draws into a level's rectangle rect (drawn with
 * its border): a border texel gets the uv of the opposite column at the sides and of the edge
 * row above and below (where the pass writes 2 P - that row's value: bordered_level_pole). */
vec2 bordered_level_uv(vec4 rect)
{
  vec2 uv = (gl_FragCoord.xy - rect.xy) / rect.zw;
  return vec2(fract(uv.x), clamp(uv.y, 0.5 / rect.w, 1.0 - 0.5 / rect.w));
}

/* Which pole the texel a pass draws into a level's rectangle lies beyond: 1 in the border row
 * above the level (north, +z), -1 below it, 0 within. Those rows hold 2 P - T, T the edge row's
 * texel in that column and P the level's value at the pole, so that the filter runs from each
 * edge texel to P at the pole itself: a level 32 texels wide has its edge rows 5.6 degrees from
 * the poles, and a floor (n = +z) read the edge texel of its longitude instead of the pole's
 * value (measured: 2.5-4 % on a rough metal floor under the sunset world). */
float bordered_level_pole(vec4 rect)
{
  float y = gl_FragCoord.y - rect.y;
  return y < 0.0 ? -1.0 : (y > rect.w ? 1.0 : 0.0);
}

#ifdef SL_CHAIN
/* Filtered importance sampling (Krivanek & Colbert 2008, "Real-time Shading with Filtered
 * Importance Sampling") over the downsampled environment (all levels in one texture,
 * rectangles in chain.rect): a sample standing for the solid angle 1 / (N pdf) reads the level
 * whose texels cover that much (plus a bias: per prefiltered level addon/reference/environment.py
 * PREFILTER_BIAS, none per pixel), trilinearly -- a bright small source spreads over the lobe
 * instead of sparkling. */

/* The Van der Corput radical inverse in base 2 (the second Hammersley coordinate). */
float radical_inverse(uint bits)
{
  bits = (bits << 16u) | (bits >> 16u);
  bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
  bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
  bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
  bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
  return float(bits) * 2.3283064365386963e-10;
}

/* Level k of the chain at equirectangular uv (bordered_level). */
vec3 chain_level(sampler2D map, int k, vec2 uv)
{
  return bordered_level(map, chain.rect[k], chain.info.yz, uv);
}

/* The chain at equirectangular uv, between levels floor(lod) and the next. */
vec3 chain_lookup_uv(sampler2D map, vec2 uv, float lod)
{
  lod = clamp(lod, 0.0, chain.info.x - 1.0);
  int k = int(floor(lod));
  int k1 = min(k + 1, int(chain.info.x) - 1);
  return mix(chain_level(map, k, uv), chain_level(map, k1, uv), lod - float(k));
}

vec3 chain_lookup(sampler2D map, vec3 d, float lod)
{
  return chain_lookup_uv(map, equirect_uv(d), lod);
}

/* The level of detail for a sample of probability density pdf (per steradian) out of n, plus
 * bias levels (Krivanek & Colbert use 1: each sample also averages its neighbourhood): the level
 * whose texels at the equator cover the sample's solid angle, at every latitude. Towards the
 * poles a texel's solid angle shrinks with sin(theta) but its extent in latitude does not: a
 * level chosen by the texel's solid angle there read texels many times taller than the sample's
 * footprint (measured: prefiltered levels against their lobe means, roughness 0.25: 0.77 ->
 * 0.23 %; sampled world specular against Cycles, city world, metal: up to 2.9 -> 2.0 %). */
float chain_lod(float pdf, int n, float bias)
{
  vec2 base = chain.rect[0].zw;  /* level 0: an equator texel spans (2 pi / w)(pi / h) */
  float omega_s = 1.0 / (float(n) * pdf);
  float omega_p = 2.0 * PI * PI / (base.x * base.y);
  return 0.5 * log2(omega_s / omega_p) + bias;
}
#endif

#ifdef SL_ENV_IMAGES
vec3 world_radiance(vec3 d, bool clamp_bright)
{
  vec3 c = world.constant_radiance.rgb;
#if SL_ENV_IMAGES > 0
  c += env_term(env_image_0, world.lookup[0], world.kind[0], world.weight[0], d, clamp_bright);
#endif
#if SL_ENV_IMAGES > 1
  c += env_term(env_image_1, world.lookup[1], world.kind[1], world.weight[1], d, clamp_bright);
#endif
#if SL_ENV_IMAGES > 2
  c += env_term(env_image_2, world.lookup[2], world.kind[2], world.weight[2], d, clamp_bright);
#endif
#if SL_ENV_IMAGES > 3
  c += env_term(env_image_3, world.lookup[3], world.kind[3], world.weight[3], d, clamp_bright);
#endif
  return c;
}
#endif
