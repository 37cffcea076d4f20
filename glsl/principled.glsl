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

#ifdef SL_SPECULAR_TINT
/* F82-tint's b of a metal of reflectance f0 whose edge is tinted by `tint` (Kutz, Hasan & Edmondson
 * 2021, "Novel aspects of the Adobe Standard Material"; Cycles' fresnel_f82tint_B,
 * kernel/closure/bsdf_util.h): the Schlick curve times the tint at cos = 1/7 (about 82 degrees),
 * solved for b in F = Schlick - b cos (1 - cos)^6; 0 for a white tint. */
vec3 F82_tint_b(vec3 f0, vec3 tint)
{
  const float f = 6.0 / 7.0;
  float f5 = pow5(f);
  return mix(f0, vec3(1.0), f5) * (7.0 / (f5 * f)) * (1.0 - tint);
}

/* The F82-tint Fresnel (Cycles' fresnel_f82): Schlick less b cos (1 - cos)^6, within [0, 1]. */
vec3 F_F82Tint(vec3 f0, vec3 b, float cos_i)
{
  float s = saturate(1.0 - cos_i);
  float s5 = pow5(s);
  return clamp(mix(f0, vec3(1.0), s5) - b * (cos_i * s5 * s), 0.0, 1.0);
}

#endif

/* The Principled BSDF's dielectric Fresnel (Cycles' generalized Schlick with a negative exponent,
 * bsdf_microfacet.h's microfacet_fresnel): from the (tinted) F0 to 1 as the exact Fresnel of eta
 * goes from its own F0 to 1; for a white tint the exact Fresnel, but never below F0 (where an IOR
 * in the hundreds dips towards Brewster's angle: 35 % below at grazing for F0 0.99). (eta's F0 is
 * at most 0.99: surface.glsl's eta from F0 clamps it there, so 1 - F0 never vanishes.) */
vec3 F_DielectricTinted(float eta, vec3 f0_tinted, float cos_i)
{
  float ratio = (eta - 1.0) / (eta + 1.0);
  float f0 = ratio * ratio;
  return mix(f0_tinted, vec3(1.0), saturate((F_Dielectric(eta, cos_i) - f0) / (1.0 - f0)));
}

/* What both lobes' compensation and the layering need, at the view direction (surface.glsl's
 * PrincipledLayers, made once per shading point by make_surface): the metal lobe's compensation
 * (for its F0 = base colour), the dielectric lobe's, and the dielectric layer's albedo estimate
 * E M mix(F0, 1, S) that the Lambert base sits under, its largest channel as Cycles'
 * closure_layering_weight takes it. `tint`: the Specular Tint (SL_SPECULAR_TINT; white else), as
 * Cycles' Principled BSDF applies it (svm_node_closure_bsdf): the dielectric's F0 times it, the
 * metal's F82 edge tint min(tint, 1); each lobe's average Fresnel Fss for its compensation as
 * bsdf_microfacet_setup_fresnel_generalized_schlick and _f82_tint take it. */
PrincipledLayers principled_layers_at(float NoV, float roughness, vec3 base_color, float eta, vec3 tint)
{
  PrincipledLayers p;
  float E_mu = max(ms_albedo(NoV, roughness), 1e-3);
  float Eavg = principled_Eavg(roughness);
  vec3 F0m = min(base_color, vec3(1.0));
  float ratio = (eta - 1.0) / (eta + 1.0);
  vec3 f0 = vec3(ratio * ratio);
  /* the remap's average from the exact Fresnel's (F0 <= 0.99: F_DielectricTinted); Cycles takes it
   * so for every tint (the exact average where it exceeds F0: all but IORs above ~200) */
  float s_avg = saturate((principled_Fss(eta) - f0.x) / (1.0 - f0.x));
#ifdef SL_SPECULAR_TINT
  p.metal_b = F82_tint_b(F0m, min(tint, vec3(1.0)));
  vec3 metal_Fss = mix(F0m, vec3(1.0), 1.0 / 21.0) - p.metal_b / 126.0;
  f0 = clamp(f0 * tint, 0.0, 1.0);
#else
  vec3 metal_Fss = F0m + (1.0 - F0m) / 21.0;
#endif
  p.dielectric_f0 = f0;
  vec3 dielectric_Fss = mix(f0, vec3(1.0), s_avg);
  p.metal_M = principled_M(metal_Fss, E_mu, Eavg);
#ifdef SL_GLOSSY
  /* a constant Fresnel: the colour is its average (bsdf_microfacet_setup_fresnel_constant) */
  p.glossy_M = principled_M(max(base_color, 0.0), E_mu, Eavg);
#endif
  p.dielectric_M = principled_M(dielectric_Fss, E_mu, Eavg);
  p.albedo = eta > 1.0 ? E_mu * p.dielectric_M * mix(f0, vec3(1.0), principled_S(roughness, NoV, sqrt(abs(ratio))))
                       : vec3(0.0);
  p.layer = max(p.albedo.r, max(p.albedo.g, p.albedo.b));
  return p;
}

PrincipledLayers principled_layers(Surface s)
{
  return s.layers;
}
#endif

#ifdef SL_COAT
/* The coat at the view (surface.glsl's CoatLayer), from MaterialData's coat (weight, roughness,
 * IOR) and the coat's own normal (0: the surface's n), as Cycles' svm_node_closure_bsdf sets its
 * coat up: a GGX dielectric of the coat's IOR (bsdf_microfacet_setup_fresnel_dielectric), its
 * compensation from the exact Fresnel's average and its albedo estimate E M mix(F0, 1, S) those of
 * principled_layers_at for a black dielectric. The roughness floored as the base's (a mirror coat:
 * MIN_PERCEPTUAL_ROUGHNESS). */
CoatLayer coat_at(vec3 n, vec3 v, vec4 coat, vec3 coat_normal)
{
  CoatLayer c;
  c.weight = max(coat.x, 0.0);
  float len2 = dot(coat_normal, coat_normal);
  c.n = len2 > 1e-20 ? coat_normal * inversesqrt(len2) : n;
  c.NoV = max(dot(c.n, v), MIN_COS);
  c.roughness = max(saturate(coat.y), MIN_PERCEPTUAL_ROUGHNESS);
  c.eta = max(coat.z, 1.0);
  c.layers = principled_layers_at(c.NoV, c.roughness, vec3(0.0), c.eta, vec3(1.0));
#  ifdef SL_LTC
  c.ltc = ltc_frame_at(c.n, v, c.NoV, c.roughness);
#  endif
  return c;
}

/* What the coat leaves the layers below at the view (Cycles' svm_node_closure_bsdf): the base's
 * weight times 1 - the coat's albedo (weight x its largest channel: closure_layering_weight), and
 * the tint's absorption along the view's path refracted into the coat, Beer's law normalised to
 * normal incidence (a coat of unit thickness): tint^(1 / cos theta_t), mixed in by the weight.
 * As Cycles', along the view alone (not the light's path). */
vec3 coat_transmittance(CoatLayer c, vec3 tint)
{
  float below = saturate(1.0 - c.weight * c.layers.layer);
  float sin2_t = (1.0 - c.NoV * c.NoV) / (c.eta * c.eta);
  /* eta >= 1: the refracted cosine is at least sqrt(1 - 1 / eta^2) > 0, or n.v (>= MIN_COS) at
   * eta = 1; a coat of IOR 1 seen at grazing absorbs along a path up to 1e4 long */
  float depth = inversesqrt(max(1.0 - sin2_t, MIN_COS * MIN_COS));
  return below * mix(vec3(1.0), pow(tint, vec3(depth)), c.weight);
}

/* The coat as a Surface the lights' and the world's paths shade (light_shading.glsl's shade_light,
 * model_pbr.glsl's shade_environment): a black dielectric of the coat's normal, roughness, IOR,
 * compensation and LTC frame, so that every light kind's and the world's specular lobe serves it. */
Surface coat_surface(Surface s)
{
  Surface c = s;
  c.n = s.coat.n;
  c.NoV = s.coat.NoV;
  c.roughness = s.coat.roughness;
  c.alpha = c.roughness * c.roughness;
  c.base_color = vec3(0.0);
  c.metalness = 0.0;
  c.eta = s.coat.eta;
  c.layers = s.coat.layers;
#  ifdef SL_GLOSSY
  c.glossy = vec4(0.0); /* the coat is the Principled BSDF's own GGX dielectric */
#  endif
#  ifdef SL_LTC
  c.ltc = s.coat.ltc;
#  endif
#  ifdef SL_THIN_FILM
  c.thin_film.x = 0.0; /* the film lies on the base, under the coat */
#  endif
#  ifdef SL_ANISOTROPY
  c.aniso = anisotropic_none(c.n, c.alpha); /* Cycles' coat is isotropic */
#  endif
#  ifdef SL_TRANSMISSION
  c.transmission.reflection_tint = vec3(1.0); /* a Glass BSDF's Color tints its own lobe, not the coat */
#  endif
  return c;
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
#ifdef SL_SPECULAR_TINT
  vec3 metal = p.metal_M * F_F82Tint(min(s.base_color, vec3(1.0)), p.metal_b, LoH);
  if (s.conductor > 0.0) {
    /* a Physical Conductor's exact Fresnel per channel (Cycles' fresnel_conductor, bsdf_util.h) in its
     * share; its F82 fit (node_closure_bsdfs.glsl) stays the compensation's and the world's */
    metal = mix(metal, p.metal_M * F_Conductor(s.ior_n, s.ior_k, LoH), s.conductor);
  }
#else
  vec3 metal = p.metal_M * F_Schlick(min(s.base_color, vec3(1.0)), 1.0, LoH);
#endif
#ifdef SL_GLOSSY
  /* the Glossy BSDFs' constant Fresnel, the uncompensated distributions (closures.glsl) */
  metal = glossy_metal(s, metal / p.metal_M, p.metal_M, 1.0);
#endif
  vec3 dielectric = p.dielectric_M * F_DielectricTinted(s.eta, p.dielectric_f0, LoH);
#ifdef SL_THIN_FILM
  /* the film's iridescent Fresnel in place of each lobe's own (thin_film.glsl), its compensation as
   * without it (Cycles') */
  if (s.thin_film.x > 0.1 && s.metalness < 1.0) {
    dielectric = p.dielectric_M * F_ThinFilmTinted(s.thin_film, s.eta, p.dielectric_f0, LoH);
  }
  if (thin_film_on_metal(s) && s.metalness > 0.0) {
    metal = p.metal_M * F_ThinFilmMetal(s.thin_film, s.film_metal_n, s.film_metal_k, s.film_metal_g, LoH);
  }
#endif
#ifdef SL_TRANSMISSION
  dielectric *= s.transmission.reflection_tint; /* the Glass BSDF's Color (transmission.glsl) */
#endif
  return s.metalness * metal + (1.0 - s.metalness) * dielectric;
}

/* The Principled set's D V towards l (half vector h): GGX and Smith height-correlated, anisotropic
 * where the program draws an anisotropic lobe (anisotropy.glsl). */
float principled_DV(Surface s, vec3 l, vec3 h, float NoL, float NoH, float NxH2)
{
#ifdef SL_ANISOTROPY
  return anisotropic_DV(s.aniso, s.n, s.v, s.NoV, l, NoL, h);
#else
  return D_GGX(NoH, NxH2, s.alpha) * V_SmithGGXCorrelated(s.NoV, NoL, s.alpha);
#endif
}

vec3 principled_direct(Surface s, vec3 l, vec3 h, float NoL, float NoH, float NxH2, float LoH, vec3 E,
                       vec4 factors)
{
  float DV = principled_DV(s, l, h, NoL, NoH, NxH2);
#  ifdef SL_GLOSSY
  DV = glossy_lobe(s, DV, NoL, NoH, NxH2, LoH); /* the Glossy BSDFs' distributions (closures.glsl) */
#  endif
  PrincipledLayers p = principled_layers(s);
  vec3 specular = principled_specular_tint(s, LoH) * DV;
#  ifdef SL_DIFFUSE_ROUGHNESS
  /* the Diffuse BSDF's Oren-Nayar in place of Lambert (closures.glsl); l.v = 2 (l.h)^2 - 1 */
  vec3 diffuse = (1.0 - s.metalness) * saturate(1.0 - p.layer) *
                 oren_nayar_diffuse(s, s.base_color, NoL, 2.0 * LoH * LoH - 1.0);
#  else
  vec3 diffuse = s.base_color * (1.0 - s.metalness) * saturate(1.0 - p.layer) * INV_PI;
#  endif
#  ifdef SL_SUBSURFACE
  diffuse *= 1.0 - s.subsurface; /* the rest scatters below the surface (subsurface.glsl) */
#  endif
#  ifdef SL_TRANSMISSION
  diffuse *= 1.0 - s.transmission.share; /* the glass's share transmits instead (transmission.glsl) */
#  endif
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
#    ifdef SL_SPECULAR_TINT
  /* F82-tint's edge term taken at the view, as the split sum takes nothing else (Cycles' own
   * albedo estimate leaves it out: bsdf_microfacet_estimate_albedo) */
  float c6 = pow5(1.0 - s.NoV) * (1.0 - s.NoV);
  metal = max(metal - p.metal_M * p.metal_b * (s.NoV * c6 * EB.x), 0.0);
#    endif
#    ifdef SL_THIN_FILM
  /* under the film the metal's Fresnel at the view times the lobe's albedo, as the dielectric's layer
   * estimate takes it (thin_film_at; no split-sum table holds a film) */
  if (thin_film_on_metal(s)) {
    metal = p.metal_M * F_ThinFilmMetal(s.thin_film, s.film_metal_n, s.film_metal_k, s.film_metal_g, s.NoV) * EB.x;
  }
#    endif
#    ifdef SL_GLOSSY
  /* a constant Fresnel: the lobe's albedo times the colour; Beckmann's and Ashikhmin-Shirley's albedo
   * in their shares (closures.glsl), the metal's split sum scaled by it */
  float E_lobe = glossy_albedo(s, EB.x, s.NoV, s.roughness);
  /* the lobes' albedos' ratio: GGX's floored where it vanishes (n.v -> 0), the split sum's metal with it */
  metal = glossy_metal(s, metal / p.metal_M * (E_lobe / max(EB.x, 1e-4)), p.metal_M, E_lobe);
#    endif
#      ifdef SL_TRANSMISSION
  vec3 specular = (s.metalness * metal + (1.0 - s.metalness) * p.albedo * s.transmission.reflection_tint) *
                  radiance;
#      else
  vec3 specular = (s.metalness * metal + (1.0 - s.metalness) * p.albedo) * radiance;
#      endif
#    endif
#    ifdef SL_DIFFUSE_ROUGHNESS
  vec3 lit = oren_nayar_environment(s, irradiance); /* Oren-Nayar's (closures.glsl) */
#    else
  vec3 lit = s.base_color * irradiance;
#    endif
#    ifdef SL_SUBSURFACE
  /* the subsurface's share a Lambert base (the walk leaves by one) times the walk's reflectance over it
   * (subsurface.glsl's subsurface_walk_at) */
  lit = lit * (1.0 - s.subsurface) + s.base_color * irradiance * (s.subsurface * s.subsurface_walk);
#    endif
  vec3 diffuse = lit * ((1.0 - s.metalness) * saturate(1.0 - p.layer) * INV_PI);
#    ifdef SL_TRANSMISSION
  diffuse *= 1.0 - s.transmission.share;
#    endif
  return diffuse * weights.x + specular * weights.y;
}
#  endif
#endif

#ifdef SL_SHEEN
/* The sheen's LTC at (n.v, roughness) from sheen_table (RGBA32F, SL_SHEEN_SIZE square: texel (i, j)
 * at n.v = i / (N - 1), roughness j / (N - 1), bilinear as Cycles' lookup_table_read_2D): a and b
 * of M^-1 = [[a, 0, b], [0, a, 0], [0, 0, 1]] in the frame (tangent towards v, n x it, n), and the
 * lobe's directional albedo (addon/reference/sheen.py fits them to Cycles' Sheen BSDF). */
vec3 sheen_texel(ivec2 i)
{
  return texelFetch(sheen_table, i, 0).rgb;
}

vec3 sheen_lookup(float NoV, float roughness)
{
  float n = float(SL_SHEEN_SIZE - 1);
  vec2 x = clamp(vec2(NoV, roughness), 0.0, 1.0) * n;
  ivec2 i0 = ivec2(floor(x));
  ivec2 i1 = min(i0 + 1, ivec2(SL_SHEEN_SIZE - 1));
  vec2 f = x - vec2(i0);
  vec3 a = mix(sheen_texel(i0), sheen_texel(ivec2(i1.x, i0.y)), f.x);
  vec3 b = mix(sheen_texel(ivec2(i0.x, i1.y)), sheen_texel(i1), f.x);
  return mix(a, b, f.y);
}

/* The sheen at the view (surface.glsl's SheenLobe), as Cycles' bsdf_sheen_setup: its roughness in
 * [1e-3, 1], its LTC looked up at the view's cosine, the frame's tangent towards v; where the fit
 * has no lobe (|a| or the albedo below 1e-5: smooth sheen seen from above) no sheen at all, neither
 * reflecting nor attenuating what lies below. M^-1's entries as ltc.glsl's (scaled by 1 / a: the
 * density does not depend on M^-1's scale). */
SheenLobe sheen_at(vec3 n, vec3 v, float roughness, vec3 color)
{
  SheenLobe sh;
  sh.n = n;
  float NoV = dot(n, v);
  vec3 fit = sheen_lookup(NoV, clamp(roughness, 1e-3, 1.0));
  bool lobe = abs(fit.x) >= 1e-5 && fit.z >= 1e-5;
  vec3 x_axis = v - n * NoV;
  float x_len2 = dot(x_axis, x_axis);
  vec3 other = abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
  /* v along n: any tangent (the lobe is symmetric about n there) */
  sh.ltc.x_axis = x_len2 > 1e-18 ? x_axis * inversesqrt(x_len2) : normalize(cross(other, n));
  sh.ltc.y_axis = cross(n, sh.ltc.x_axis);
  float a = lobe ? fit.x : 1.0;
  sh.ltc.m = vec4(1.0, fit.y / a, 0.0, 1.0 / a);
  sh.ltc.albedo = lobe ? fit.z : 0.0;
  sh.color = color * sh.ltc.albedo;
  return sh;
}

/* The sheen's f (n.l) towards l per unit irradiance: its colour times the LTC's density (Cycles'
 * bsdf_sheen_eval), 0 below its normal's horizon. */
vec3 sheen_direct(Surface s, vec3 l)
{
  vec3 local = vec3(dot(l, s.sheen.ltc.x_axis), dot(l, s.sheen.ltc.y_axis), dot(l, s.sheen.n));
  return s.sheen.color * ltc_density(s.sheen.ltc.m, local, 0.0);
}

#  if defined(SL_ENV_UNIFORM) || defined(SL_ENV_MAP)
vec3 ltc_direction(vec4 m, vec3 w); /* ltc.glsl */

/* The world's radiance as the sheen's lobe weights it, its colour (which holds its albedo) multiplying it
 * back: SHEEN_WORLD_SAMPLES directions of its linearly transformed cosine (cosine-distributed points,
 * Malley's lift of Vogel's disc, mapped by M: Cycles' bsdf_sheen_sample with fixed points), each reading
 * the prefiltered world at its share of the lobe (env_footprint_roughness; never a level holding the suns
 * split off the world: the sheen takes them as lights, shade_light's diffuse factor). The lobe lies towards
 * the horizon, at a grazing view a ring about n leaning back towards v: the irradiance about n (its albedo
 * times a cosine-weighted mean), which the sheen took before, drew the Microfiber Sheen 14.5 % off Cycles
 * in the forest world (7 % dark, roughness 0.1 / 0.3 quarters 48 / 62 %; tests/test_closure_nodes.py). */
#    define SHEEN_WORLD_SAMPLES 16
vec3 sheen_environment(Surface s)
{
#    ifdef SL_ENV_MAP
  if (max(s.sheen.color.r, max(s.sheen.color.g, s.sheen.color.b)) <= 0.0) {
    return vec3(0.0); /* no sheen here: its colour 0 multiplies whatever this returns */
  }
  float floor_roughness = env_sunless_roughness();
  vec3 sum = vec3(0.0);
  for (int i = 0; i < SHEEN_WORLD_SAMPLES; i++) {
    vec2 d = vogel_disc(i, SHEEN_WORLD_SAMPLES);
    vec3 local = ltc_direction(s.sheen.ltc.m, vec3(d, sqrt(max(1.0 - dot(d, d), 0.0))));
    float pdf = ltc_density(s.sheen.ltc.m, local, 0.0);
    vec3 l = local.x * s.sheen.ltc.x_axis + local.y * s.sheen.ltc.y_axis + local.z * s.sheen.n;
    sum += env_prefiltered(l, env_footprint_roughness(pdf, SHEEN_WORLD_SAMPLES, floor_roughness));
  }
  return sum / float(SHEEN_WORLD_SAMPLES);
#    else
  return env_prefiltered(s.sheen.n, 1.0); /* a uniform world: its radiance in every direction */
#    endif
}
#  endif
#endif
