/* Physically based: f = f_spec (eq. 1.10) + f_diff (eq. 1.18), metal/dielectric workflow, HDR.
 * f_spec = F(l.h) D(h) G(l, v, h) / (4 |n.v| |n.l|) with Schlick F, GGX D, Smith
 * height-correlated G (as V = G / (4 n.v n.l)); f_diff = (1 - F) rho / pi, rho = base (1 - metal).
 * F0 = mix(dielectric F0, base colour, metalness); F90 = saturate(50 F0) (Schlick's 1.11 for any
 * real material, F0 >= 0.02; it fades the Fresnel tail out as F0 -> 0 so that "no specular"
 * (F0 = 0) means none at grazing angles either; Schueler 2012, used by Filament). */

vec3 pbr_f0(Surface s)
{
  return mix(vec3(s.f0_dielectric), s.base_color, s.metalness);
}

float pbr_f90(vec3 f0)
{
  return saturate(50.0 * dot(f0, vec3(1.0 / 3.0)));
}

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
  vec3 f0 = pbr_f0(s);
  vec3 F = F_Schlick(f0, pbr_f90(f0), LoH);
  float D = D_GGX(NoH, dot(NxH, NxH), s.alpha);
  float V = V_SmithGGXCorrelated(s.NoV, NoL, s.alpha);
  vec3 specular = F * (D * V);                                             /* eq. 1.10 */
  vec3 diffuse = (vec3(1.0) - F) * s.base_color * (1.0 - s.metalness) * Fd_Lambert(); /* eq. 1.18 */
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
