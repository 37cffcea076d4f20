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

/* The PBR model takes no ambient constant: indirect light comes from the world (not yet). */
vec3 shade_ambient(Surface s, vec3 x)
{
  return vec3(0.0);
}

/* HDR: radiance leaves unclamped (W / (m^2 sr)); tone mapping happens downstream. */
vec3 shade_finish(vec3 c)
{
  return c;
}
