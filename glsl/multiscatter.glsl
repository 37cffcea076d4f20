/* Specular multiple-scattering energy compensation (Turquin 2019, "Practical multiple scattering
 * compensation for microfacet models"; Fdez-Aguera 2019): single-scatter microfacet lobes lose
 * the energy of light that bounces more than once between microfacets, 1 - E(mu) of it for a
 * white surface. Scaling f_spec by 1 + F0 (1 / E(mu_o) - 1) restores it, with E the directional
 * albedo of the chosen D and V with F = 1, tabulated by addon/reference/multiscatter.py over
 * (mu = n.v, perceptual roughness) on the grid i / (N - 1), ends included, and interpolated
 * bilinearly here (texelFetch, so that the numpy twin interpolates identically). */

#if defined(SL_MULTISCATTER) || defined(SL_LAYERS) || defined(SL_LTC)
/* The table whose rows start at `first_row` (the program's own at 0; glossy_albedo's after it). */
float ms_albedo_rows(float NoV, float roughness, int first_row)
{
  float n = float(SL_MS_SIZE);
  vec2 x = clamp(vec2(NoV, roughness) * (n - 1.0), vec2(0.0), vec2(n - 1.0));
  ivec2 i0 = ivec2(floor(x));
  ivec2 i1 = min(i0 + 1, ivec2(SL_MS_SIZE - 1));
  vec2 t = x - vec2(i0);
  float e00 = texelFetch(ms_table, ivec2(i0.x, first_row + i0.y), 0).r;
  float e10 = texelFetch(ms_table, ivec2(i1.x, first_row + i0.y), 0).r;
  float e01 = texelFetch(ms_table, ivec2(i0.x, first_row + i1.y), 0).r;
  float e11 = texelFetch(ms_table, ivec2(i1.x, first_row + i1.y), 0).r;
  return mix(mix(e00, e10, t.x), mix(e01, e11, t.x), t.y);
}

float ms_albedo(float NoV, float roughness)
{
  return ms_albedo_rows(NoV, roughness, 0);
}

#endif

#ifdef SL_MULTISCATTER
vec3 ms_compensation_at(float NoV, float roughness, vec3 f0)
{
  float E = max(ms_albedo(NoV, roughness), 1e-3);
  return 1.0 + f0 * (1.0 / E - 1.0);
}

/* Made once per shading point by make_surface (surface.glsl). */
vec3 specular_energy_compensation(Surface s)
{
  return s.ms_compensation;
}
#else
vec3 specular_energy_compensation(Surface s)
{
  return vec3(1.0);
}
#endif
