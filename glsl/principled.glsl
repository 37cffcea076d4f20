/* The "Principled" term set: Blender's Principled BSDF as Cycles 5.0 evaluates it for opaque
 * materials (white specular tint, Multiscatter GGX, Lambert base), so that scenes authored with
 * Principled BSDFs render as in Cycles under direct light. Tables from addon/reference/multiscatter.py:
 * ms_table rows 0..N-1 hold E(mu, r), row N holds Eavg(r); s_table is the 16^3 table S(r, mu, z)
 * laid out as 16 x 256 (y = mu index + 16 z index). */

#ifdef SL_LAYERS
/* The layering estimate (SL_LAYERS: the Principled set, and the LAYERED diffuse of
 * pbr_terms.glsl): Eavg, S, Fss, M and the layer's albedo at the view. */
float principled_Eavg(float roughness)
{
  float n = float(SL_MS_SIZE);
  float x = clamp(roughness * (n - 1.0), 0.0, n - 1.0);
  int i0 = int(floor(x));
  int i1 = min(i0 + 1, SL_MS_SIZE - 1);
  float a = texelFetch(ms_table, ivec2(i0, SL_MS_SIZE), 0).r;
  float b = texelFetch(ms_table, ivec2(i1, SL_MS_SIZE), 0).r;
  return mix(a, b, x - float(i0));
}

float principled_S_texel(int r, int mu, int z)
{
  return texelFetch(s_table, ivec2(r, mu + SL_S_SIZE * z), 0).r;
}

/* Trilinear lookup of S on the grid i / (N - 1), as Cycles' lookup_table_read_3D. */
float principled_S(float roughness, float mu, float z)
{
  float n = float(SL_S_SIZE);
  vec3 x = clamp(vec3(roughness, mu, z) * (n - 1.0), vec3(0.0), vec3(n - 1.0));
  ivec3 i0 = ivec3(floor(x));
  ivec3 i1 = min(i0 + 1, ivec3(SL_S_SIZE - 1));
  vec3 t = x - vec3(i0);
  float c00 = mix(principled_S_texel(i0.x, i0.y, i0.z), principled_S_texel(i1.x, i0.y, i0.z), t.x);
  float c10 = mix(principled_S_texel(i0.x, i1.y, i0.z), principled_S_texel(i1.x, i1.y, i0.z), t.x);
  float c01 = mix(principled_S_texel(i0.x, i0.y, i1.z), principled_S_texel(i1.x, i0.y, i1.z), t.x);
  float c11 = mix(principled_S_texel(i0.x, i1.y, i1.z), principled_S_texel(i1.x, i1.y, i1.z), t.x);
  return mix(mix(c00, c10, t.y), mix(c01, c11, t.y), t.z);
}

/* Kulla & Conty 2017's fit of the hemispherical average of dielectric Fresnel (eta >= 1). */
float principled_Fss(float eta)
{
  return (eta - 1.0) / (4.08567 + 1.00071 * eta);
}

/* Multiple-scattering compensation of a lobe whose average Fresnel is Fss (Kulla & Conty 2017,
 * as Cycles' microfacet_ggx_preserve_energy): 1 + Fms (1 - E) / E. */
vec3 principled_M(vec3 Fss, float E, float Eavg)
{
  vec3 Fms = Fss * Eavg / (1.0 - Fss * (1.0 - Eavg));
  return 1.0 + Fms * (1.0 - E) / E;
}

/* What both lobes' compensation and the layering need, at the view direction (surface.glsl's
 * PrincipledLayers, made once per shading point by make_surface): the metal lobe's compensation
 * (for its F0 = base colour), the dielectric lobe's, and the dielectric layer's albedo estimate
 * E M mix(F0, 1, S) that the Lambert base sits under. */
PrincipledLayers principled_layers_at(float NoV, float roughness, vec3 base_color, float eta)
{
  PrincipledLayers p;
  float E_mu = max(ms_albedo(NoV, roughness), 1e-3);
  float Eavg = principled_Eavg(roughness);
  vec3 F0m = min(base_color, vec3(1.0));
  p.metal_M = principled_M(F0m + (1.0 - F0m) / 21.0, E_mu, Eavg);
  p.dielectric_M = principled_M(vec3(principled_Fss(eta)), E_mu, Eavg).x;
  float ratio = (eta - 1.0) / (eta + 1.0);
  p.layer = eta > 1.0 ? E_mu * p.dielectric_M *
                            mix(ratio * ratio, 1.0, principled_S(roughness, NoV, sqrt(abs(ratio))))
                      : 0.0;
  return p;
}

PrincipledLayers principled_layers(Surface s)
{
  return s.layers;
}
#endif

#ifdef SL_PRINCIPLED

/* f * E * NoL for the Principled set: a metal lobe (F82-tint Fresnel, which is Schlick for a
 * white tint) weighted by metalness, a dielectric lobe with exact Fresnel weighted by
 * 1 - metalness, each with its own compensation, and a Lambert base weighted by
 * 1 - the dielectric layer's albedo. */
vec3 principled_specular_tint(Surface s, float LoH)
{
  PrincipledLayers p = principled_layers(s);
  vec3 metal = p.metal_M * F_Schlick(min(s.base_color, vec3(1.0)), 1.0, LoH);
  float dielectric = p.dielectric_M * F_Dielectric(s.eta, LoH);
  return s.metalness * metal + (1.0 - s.metalness) * dielectric;
}

vec3 principled_direct(Surface s, float NoL, float NoH, float NxH2, float LoH, vec3 E, vec4 factors)
{
  float D = D_GGX(NoH, NxH2, s.alpha);
  float V = V_SmithGGXCorrelated(s.NoV, NoL, s.alpha);
  PrincipledLayers p = principled_layers(s);
  vec3 specular = principled_specular_tint(s, LoH) * (D * V);
  vec3 diffuse = s.base_color * (1.0 - s.metalness) * saturate(1.0 - p.layer) * INV_PI;
  return (diffuse * factors.x + specular * factors.y) * E * NoL;
}

#  ifdef SL_ENV_SAMPLES
vec3 env_sampled_specular(Surface s); /* model_pbr.glsl */
#  endif

#  if defined(SL_ENV_UNIFORM) || defined(SL_ENV_MAP)
/* The world's light for the Principled set: each lobe's split-sum albedo (the metal's Schlick
 * F0 (E - B) + B, the dielectric layer's own estimate) times the prefiltered radiance, and the
 * base under the layer lit by the irradiance. */
vec3 principled_environment(Surface s, vec2 EB, vec3 radiance, vec3 irradiance, vec2 weights)
{
  PrincipledLayers p = principled_layers(s);
#    ifdef SL_ENV_SAMPLES
  vec3 specular = env_sampled_specular(s) * env_occlusion_specular(s.n, reflect(-s.v, s.n), s.alpha);
#    else
  vec3 F0m = min(s.base_color, vec3(1.0));
  vec3 metal = p.metal_M * (F0m * (EB.x - EB.y) + EB.y);
  vec3 specular = (s.metalness * metal + (1.0 - s.metalness) * p.layer) * radiance;
#    endif
  vec3 diffuse = s.base_color * (1.0 - s.metalness) * saturate(1.0 - p.layer) * irradiance * INV_PI;
  return diffuse * weights.x + specular * weights.y;
}
#  endif
#endif
