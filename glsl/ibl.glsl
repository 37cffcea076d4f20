/* Image-based lighting from the world (addon/reference/environment.py computes what is bound here):
 * - diffuse: irradiance from nine spherical-harmonic coefficients (Ramamoorthi & Hanrahan 2001,
 *   "An Efficient Representation for Irradiance Environment Maps", eq. 7), premultiplied on
 *   the CPU by the cosine kernel's band factors;
 * - specular: Karis 2013's split sum, "Real Shading in Unreal Engine 4": the environment
 *   prefiltered by a GGX lobe per roughness level (an atlas of equirectangular levels), times
 *   the lobe's directional albedo split as F0 (E - B) + F90 B (table split_table: E, B);
 * - multiple scattering (Fdez-Aguera 2019, "A Multiple-Scattering Microfacet Model for
 *   Real-Time Image-based Lighting", eq. 16-18) where the term set compensates.
 * SL_ENV_UNIFORM: a world without images, whose prefiltered radiance is the constant itself. */

/* Prefiltered level k's perceptual roughness: addon/reference/environment.py's PREFILTER_ROUGHNESS (steps
 * of 1/8 up to 0.5, then of 1/4) in closed form, which tests/test_world_light.py holds equal to
 * the table; level 0 is the mirror image, shown as is for the smoothest surfaces. Not the table
 * read from the world's block: read at a level that varies per pixel, a block's value is a
 * gather on the CPU rasteriser (glsl/README.md), and finding the level read it in a loop. */
float env_level_roughness(int k)
{
  return k == 0 ? MIN_PERCEPTUAL_ROUGHNESS : (k <= 4 ? 0.125 * float(k) : 0.25 * float(k - 2));
}

/* The level below perceptual roughness r: the k with env_level_roughness(k) < r <=
 * env_level_roughness(k + 1) (0 at and below level 1's), in closed form; the caller keeps it
 * below the world's last level. */
int env_level_below(float roughness)
{
  return max(roughness <= 0.5 ? int(ceil(8.0 * roughness)) - 1 : int(ceil(4.0 * roughness)) + 1, 0);
}

#if defined(SL_ENV_UNIFORM) || defined(SL_ENV_MAP)

vec3 env_irradiance_sh9(vec3 n)
{
  vec3 e = env.sh[0].rgb * 0.282095;
  e += (env.sh[1].rgb * n.y + env.sh[2].rgb * n.z + env.sh[3].rgb * n.x) * 0.488603;
  e += (env.sh[4].rgb * (n.x * n.y) + env.sh[5].rgb * (n.y * n.z) + env.sh[7].rgb * (n.x * n.z)) * 1.092548;
  e += env.sh[6].rgb * (0.315392 * (3.0 * n.z * n.z - 1.0));
  e += env.sh[8].rgb * (0.546274 * (n.x * n.x - n.y * n.y));
  /* nine bands ring below zero behind a very bright, small source: no negative light */
  return max(e, vec3(0.0));
}

#  ifdef SL_MODEL_PBR
/* E(mu, r) and B(mu, r) of the program's D and V, bilinear on the grid i / (N - 1). At the
 * roughness floor the surface stands for a perfect mirror (as Cycles renders roughness 0):
 * E = 1, B = (1 - n.v)^5, i.e. Schlick's Fresnel at n.v, no masking. */
vec2 env_split_sum(float NoV, float roughness)
{
  if (roughness <= MIN_PERCEPTUAL_ROUGHNESS) {
    return vec2(1.0, pow5(1.0 - NoV));
  }
  float n = float(SL_MS_SIZE);
  vec2 x = clamp(vec2(NoV, roughness) * (n - 1.0), vec2(0.0), vec2(n - 1.0));
  ivec2 i0 = ivec2(floor(x));
  ivec2 i1 = min(i0 + 1, ivec2(SL_MS_SIZE - 1));
  vec2 t = x - vec2(i0);
  vec2 a = mix(texelFetch(split_table, i0, 0).rg, texelFetch(split_table, ivec2(i1.x, i0.y), 0).rg, t.x);
  vec2 b = mix(texelFetch(split_table, ivec2(i0.x, i1.y), 0).rg, texelFetch(split_table, i1, 0).rg, t.x);
  return mix(a, b, t.y);
}
#  endif

#  ifdef SL_ENV_MAP
/* Level k of the atlas at equirectangular uv (environment.glsl's bordered_level). */
vec3 env_level_uv(int k, vec2 uv)
{
  return bordered_level(env_atlas, env.rect[k], env.info.zw, uv);
}

vec3 env_level(int k, vec3 d)
{
  return env_level_uv(k, equirect_uv(d));
}

/* The specular weight of the suns split off the world: 0 for surfaces smooth enough to see the
 * world's brightest texels in their prefiltered levels (which keep them: a sun without a shape
 * would be a pin-point there), 1 from the first level without them, ramping between the two
 * levels' roughness so that the light passes from one to the other without gain or loss. */
float world_sun_specular(float roughness)
{
  int k = int(env.info.y);
  if (k >= int(env.info.x)) {
    return 1.0;
  }
  float r0 = env_level_roughness(k - 1), r1 = env_level_roughness(k);
  return clamp((roughness - r0) / (r1 - r0), 0.0, 1.0);
}

/* The environment through a GGX lobe of perceptual roughness r: the two levels around it, mixed
 * linearly in roughness (image worlds' forward shading 0.92-0.97x with the level in closed form,
 * not found in a loop over the block's table: world preset, fenced minima/medians). */
vec3 env_prefiltered(vec3 d, float roughness)
{
  int k = min(env_level_below(roughness), int(env.info.x) - 2);
  float r0 = env_level_roughness(k), r1 = env_level_roughness(k + 1);
  float t = clamp((roughness - r0) / (r1 - r0), 0.0, 1.0);
  vec2 uv = equirect_uv(d);
  vec3 a = env_level_uv(k, uv);
  return t > 0.0 ? mix(a, env_level_uv(k + 1, uv), t) : a;
}

/* The irradiance: the exactly convolved map (the atlas' last rectangle), or the nine spherical
 * harmonics (SL_ENV_DIFFUSE_SH9: cheaper, smoother, wrong where a small bright source rules). */
vec3 env_irradiance(vec3 n)
{
#    ifdef SL_ENV_DIFFUSE_SH9
  return env_irradiance_sh9(n);
#    else
  return env_level(7, n);
#    endif
}
#  else
vec3 env_prefiltered(vec3 d, float roughness)
{
  return env.uniform_radiance.rgb;
}

float world_sun_specular(float roughness)
{
  return 1.0;
}

vec3 env_irradiance(vec3 n)
{
  return env_irradiance_sh9(n);  /* exact for a constant */
}
#  endif

/* The perceptual roughness of the prefiltered world whose GGX lobe covers one sample's share of a lobe
 * sampled `count` times, 1 / (count pdf) sr (Krivanek & Colbert 2008's filtered importance sampling, on the
 * prefiltered levels: a lobe of alpha covers ~4 pi alpha^2 sr about its peak), within [floor_roughness, 1]
 * (a far tail's pdf underflowing to 0 in float32 takes the roughest). */
float env_footprint_roughness(float pdf, int count, float floor_roughness)
{
  return clamp(sqrt(sqrt(1.0 / (4.0 * PI * float(count) * max(pdf, 1e-30)))), floor_roughness, 1.0);
}

/* The smoothest perceptual roughness whose prefiltered world holds none of the suns split off it (a lobe
 * the suns light as lights, at full weight, reads no smoother): the first level made from the clamped
 * world, the floor where the world has no suns. */
float env_sunless_roughness()
{
#  ifdef SL_ENV_MAP
  int clamped = int(env.info.y);
  return clamped < int(env.info.x) ? env_level_roughness(clamped) : MIN_PERCEPTUAL_ROUGHNESS;
#  else
  return MIN_PERCEPTUAL_ROUGHNESS;
#  endif
}

/* Where a GGX lobe's reflected energy peaks: off the mirror direction towards the normal as the
 * surface roughens (Lagarde & de Rousiers 2014, "Moving Frostbite to PBR", listing 22). */
vec3 env_dominant_direction(vec3 n, vec3 r, float alpha)
{
  float smoothness = 1.0 - alpha;
  return normalize(mix(n, r, smoothness * (sqrt(smoothness) + alpha)));
}
#else
float world_sun_specular(float roughness)
{
  return 1.0;  /* no world light, no suns split off it */
}
#endif

/* Occlusion of the world's light by geometry (SL_ENV_OCCLUSION: the screen-space pass,
 * glsl/gtao.frag.glsl): the visible fraction of the hemisphere at this pixel for the diffuse
 * lobe, and the bent normal, the mean direction of the visible part. */
vec4 env_occlusion()
{
#ifdef SL_ENV_OCCLUSION
  return texelFetch(env_occlusion_map, ivec2(gl_FragCoord.xy), 0);
#else
  return vec4(0.0, 0.0, 0.0, 1.0);
#endif
}

float env_occlusion_diffuse()
{
  return env_occlusion().a;
}

/* Where the unoccluded light comes from: the bent normal, or n where nothing occludes. The
 * irradiance read there lights an occluded point better than the irradiance around n (a sphere
 * on a ground under the forest world, against Cycles: 3.1 % -> 2.2 %). */
vec3 env_bent_normal(vec3 n)
{
  vec3 bent = env_occlusion().xyz;
  float len2 = dot(bent, bent);
  return len2 > 1e-12 ? bent * inversesqrt(len2) : n;
}

/* The solid angle two cones share, their half-angles a1, a2 and their axes d apart: all of the
 * smaller one inside the larger, nothing once they part, and a smooth step between (Oat &
 * Sander 2007, "Ambient aperture lighting", as in Jimenez et al. 2016's specular occlusion). */
float cone_intersection(float a1, float a2, float d)
{
  float smaller = 2.0 * PI * (1.0 - cos(min(a1, a2)));
  float inner = abs(a1 - a2);
  return smaller * (1.0 - smoothstep(inner, a1 + a2, d));
}

/* Specular occlusion (Jimenez et al. 2016, sec. 6, "GTSO"): the visible directions as a cone
 * around the bent normal whose cosine-weighted solid angle is the diffuse visibility (its
 * half-angle's sine squared), the reflection lobe as a cone around r holding 90 % of GGX's
 * half-vector distribution (tan theta_h = 3 alpha, twice the angle for the reflection: on metal
 * spheres resting on a ground, against Cycles, alpha and 6 alpha did worse); the visible part of
 * the lobe is the cones' intersection over the lobe's intersection with the unoccluded
 * hemisphere, so that nothing occluded means exactly 1. A mirror reflecting the ground a sphere
 * rests on sees nothing of the world there, as Cycles' direct light shows. */
float env_occlusion_specular(vec3 n, vec3 r, float alpha)
{
#ifdef SL_ENV_OCCLUSION
  float visible = acos_accurate(sqrt(clamp(1.0 - env_occlusion_diffuse(), 0.0, 1.0)));
  vec3 bent = env_bent_normal(n);
  float lobe = min(2.0 * atan(3.0 * alpha), 0.5 * PI);
  float seen = cone_intersection(visible, lobe, acos_accurate(dot(bent, r)));
  float open = cone_intersection(0.5 * PI, lobe, acos_accurate(dot(n, r)));
  return open > 1e-8 ? clamp(seen / open, 0.0, 1.0) : 1.0;
#else
  return 1.0;
#endif
}
