/* Physically based: f = f_spec (eq. 1.10) + f_diff, metal/dielectric workflow, HDR.
 * f_spec = F(l.h) D(h) G(l, v, h) / (4 |n.v| |n.l|) = F D V with the variants of pbr_terms.glsl;
 * the default program is Schlick F, GGX D, Smith height-correlated G and Lambert (1 - F) rho / pi.
 * F0 = mix(dielectric F0, base colour, metalness); F90 = saturate(50 F0) unless the material sets
 * it: 1 for any real material (F0 >= 0.02), fading the Fresnel tail out as F0 -> 0 so that "no
 * specular" (F0 = 0) means none at grazing angles either (Schueler 2012, used by Filament). */

vec3 shade_direct(Surface s, vec3 l, vec3 E, vec4 factors)
{
  float NoL = dot(s.n, l);
  if (NoL <= 0.0) {
    return vec3(0.0);
  }
  vec3 h = half_vector(l, s.v, s.n);
  float NoH = saturate(dot(s.n, h));
  vec3 NxH = cross(s.n, h);
  float LoH = saturate(dot(l, h));
  float LoV = dot(l, s.v);
#ifdef SL_PRINCIPLED
  return principled_direct(s, NoL, NoH, dot(NxH, NxH), LoH, E, factors);
#endif
  vec3 F = pbr_fresnel(s, LoH);
  float D = pbr_distribution(NoH, dot(NxH, NxH), s.alpha);
  float V = pbr_visibility(s.NoV, NoL, NoH, LoH, s.alpha);
  vec3 specular = F * (D * V) * specular_energy_compensation(s);  /* eq. 1.10 */
  vec3 diffuse = pbr_diffuse(s, F, s.NoV, NoL, NoH, LoH, LoV);
  return (diffuse * factors.x + specular * factors.y) * E * NoL;
}

#if defined(SL_ENV_UNIFORM) || defined(SL_ENV_MAP)
/* The world's light (glsl/ibl.glsl): the split-sum specular lobe, the prefiltered radiance read
 * where the lobe's energy peaks, and the diffuse lobe lit by the irradiance, weighted by the
 * energy the specular lobe did not take (1 - F0 (E - B) - F90 B: Lambert's 1 - F over the
 * hemisphere; every diffuse variant is lit this way). */
vec3 shade_environment(Surface s, vec2 weights)
{
  vec2 EB = env_split_sum(s.NoV, s.roughness);
  vec3 radiance = env_prefiltered(env_dominant_direction(s.n, reflect(-s.v, s.n), s.alpha), s.roughness);
  vec3 irradiance = env_irradiance(s.n);
#  ifdef SL_PRINCIPLED
  return principled_environment(s, EB, radiance, irradiance, weights);
#  else
  vec3 albedo = s.f0 * (EB.x - EB.y) + s.f90 * EB.y;
  vec3 specular = albedo * radiance;
#    ifdef SL_MULTISCATTER
  /* light scattered more than once between microfacets leaves like a rough diffuse lobe
   * (Fdez-Aguera 2019, eq. 16-18): Fms Ems of the irradiance */
  float Ems = 1.0 - EB.x;
  vec3 Favg = s.f0 + (1.0 - s.f0) / 21.0;
  vec3 Fms_Ems = albedo * Favg * Ems / (1.0 - Ems * Favg);
  specular += Fms_Ems * irradiance * INV_PI;
  albedo += Fms_Ems;
#    endif
  vec3 diffuse = s.base_color * (1.0 - s.metalness) * clamp(1.0 - albedo, 0.0, 1.0) * irradiance * INV_PI;
  return diffuse * weights.x + specular * weights.y;
#  endif
}
#else
vec3 shade_environment(Surface s, vec2 weights)
{
  return vec3(0.0);
}
#endif

/* The PBR model takes no ambient constant: indirect light comes from the world. */
vec3 shade_ambient(Surface s, vec3 x)
{
  return vec3(0.0);
}

/* HDR: radiance leaves unclamped (W / (m^2 sr)); tone mapping happens downstream. */
vec3 shade_finish(vec3 c)
{
  return c;
}
