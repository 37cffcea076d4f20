/* BRDF terms, one function per term. Each has a numpy twin of the same name in
 * addon/shading.py. The 1/pi of the diffuse lobe is inside Fd_Lambert, so radiance is
 * f * E * NoL with E the light's irradiance in W/m^2 (no leading pi, unlike eq. 1.19). */

/* Fresnel, Schlick 1994, "An Inexpensive BRDF Model for Physically-based Rendering".
 * Eq. 1.11 with F90 = 1, and the F0/F90 form of eq. 1.13 with p = 1/5. Inside eq. 1.10 the
 * argument is l.h (= v.h), not n.l: the seed's text has it wrong (SPEC, "where the seed is wrong"). */
vec3 F_Schlick(vec3 f0, float f90, float LoH)
{
  return f0 + (vec3(f90) - f0) * pow5(1.0 - LoH);
}

/* Normal distribution, Walter et al. 2007, "Microfacet Models for Refraction through Rough
 * Surfaces" (GGX / Trowbridge-Reitz). Eq. 1.15, rewritten with 1 - NoH^2 = |n x h|^2 so that the
 * peak (NoH -> 1) does not cancel catastrophically in float32 (Filament, surface_brdf.fs). */
float D_GGX(float NoH, float NxH2, float alpha)
{
  float a = NoH * alpha;
  float k = alpha / (NxH2 + a * a);
  return k * k * INV_PI;
}

/* Visibility V = G / (4 NoV NoL), Heitz 2014, "Understanding the Masking-Shadowing Function in
 * Microfacet-Based BRDFs": Smith height-correlated G of eqs. 1.16-1.17 for GGX, with the
 * 1 / (4 NoV NoL) of eq. 1.10 folded in algebraically (no division by the cosines). */
float V_SmithGGXCorrelated(float NoV, float NoL, float alpha)
{
  float a2 = alpha * alpha;
  float lambda_v = NoL * sqrt(NoV * NoV * (1.0 - a2) + a2);
  float lambda_l = NoV * sqrt(NoL * NoL * (1.0 - a2) + a2);
  return 0.5 / (lambda_v + lambda_l);
}

/* Lambertian diffuse lobe, eq. 1.18 without its (1 - F) weight (the model applies it). */
float Fd_Lambert()
{
  return INV_PI;
}

/* Blinn 1977, "Models of Light Reflection for Computer Synthesized Pictures": the specular
 * factor ((n.h)+)^shininess of eq. 1.7. Shininess is floored on the CPU (pow(0, 0) is undefined). */
float S_BlinnPhong(float NoH, float shininess)
{
  return pow(max(NoH, 0.0), shininess);
}

/* Phong 1975, "Illumination for Computer Generated Pictures": ((r.v)+)^shininess of eq. 1.2,
 * with r = 2 (n.l) n - l of eq. 1.3. */
float S_Phong(vec3 n, vec3 l, vec3 v, float shininess)
{
  vec3 r = 2.0 * dot(n, l) * n - l;
  return pow(max(dot(r, v), 0.0), shininess);
}
