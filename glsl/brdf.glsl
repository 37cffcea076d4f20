/* BRDF terms, one function per term. Each has a numpy twin of the same name in
 * addon/reference/shading.py. The 1/pi of diffuse lobes is inside the Fd_* functions, so radiance is
 * f * E * NoL with E the light's irradiance in W/m^2 (no leading pi, unlike eq. 1.19).
 * Visibility functions return V = G / (4 NoV NoL), the masking-shadowing term with the
 * denominator of eq. 1.10 folded in. Roughness: r is perceptual, alpha = r^2 (Burley 2012). */

/* ---- Fresnel ------------------------------------------------------------------------------ */

/* Schlick 1994, "An Inexpensive BRDF Model for Physically-based Rendering". Eq. 1.11 with
 * F90 = 1. Inside eq. 1.10 the argument is l.h (= v.h), not n.l: the seed's text has it wrong. */
vec3 F_Schlick(vec3 f0, float f90, float LoH)
{
  return f0 + (vec3(f90) - f0) * pow5(1.0 - LoH);
}

/* Lagarde 2012, "Spherical Gaussian approximation for Blinn-Phong, Phong and Fresnel": eq. 1.12,
 * (1 - x)^5 replaced by 2^((-5.55473 x - 6.98316) x), as in Unreal Engine 4 (Karis 2013). */
vec3 F_SchlickSG(vec3 f0, float f90, float LoH)
{
  return f0 + (vec3(f90) - f0) * exp2((-5.55473 * LoH - 6.98316) * LoH);
}

/* Lagarde & de Rousiers 2014, "Moving Frostbite to PBR": eq. 1.13, the generalised Schlick
 * F0 + (F90 - F0) (1 - x)^(1/p); p = 1/5 is eq. 1.11. p is floored on the CPU (p > 0). */
vec3 F_SchlickGeneral(vec3 f0, float f90, float p, float LoH)
{
  return f0 + (vec3(f90) - f0) * pow(max(1.0 - LoH, 0.0), 1.0 / p);
}

/* Exact Fresnel reflectance of a dielectric interface, unpolarised light, relative index eta
 * (Walter et al. 2007, eq. 22). eta <= 1 and grazing angles can give total internal reflection. */
float F_Dielectric(float eta, float cos_i)
{
  float c = abs(cos_i);
  float g2 = eta * eta - 1.0 + c * c;
  if (g2 <= 0.0) {
    /* total internal reflection (eta < 1); eta = 1 (F0 = 0) at c = 0 is no interface at all: it
     * returned 1 there, a specular spike from a material without specular when l.h rounds to 0 */
    return eta < 1.0 ? 1.0 : 0.0;
  }
  float g = sqrt(g2);
  float a = (g - c) / (g + c);
  float b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
  return 0.5 * a * a * (1.0 + b * b);
}

/* Exact Fresnel reflectance of a conductor with complex index n + ik per rgb channel, from air,
 * unpolarised (Pharr, Jakob & Humphreys, PBRT 3rd ed., section 8.2.1, FrConductor). */
vec3 F_Conductor(vec3 n, vec3 k, float cos_i)
{
  float c = clamp(cos_i, 0.0, 1.0);
  float c2 = c * c;
  float s2 = 1.0 - c2;
  vec3 t0 = n * n - k * k - s2;
  vec3 a2b2 = sqrt(t0 * t0 + 4.0 * n * n * k * k);
  vec3 a = sqrt(max(0.5 * (a2b2 + t0), 0.0));
  vec3 t1 = a2b2 + c2;
  vec3 t2 = 2.0 * c * a;
  vec3 rs = (t1 - t2) / max(t1 + t2, vec3(1e-30));
  vec3 t3 = c2 * a2b2 + s2 * s2;
  vec3 t4 = t2 * s2;
  vec3 rp = rs * (t3 - t4) / max(t3 + t4, vec3(1e-30));
  return 0.5 * (rp + rs);
}

/* ---- normal distribution ------------------------------------------------------------------ */

/* Walter et al. 2007 (GGX / Trowbridge-Reitz). Eq. 1.15, rewritten with 1 - NoH^2 = |n x h|^2
 * so that the peak (NoH -> 1) does not cancel catastrophically in float32 (Filament). */
float D_GGX(float NoH, float NxH2, float alpha)
{
  float a = NoH * alpha;
  float k = alpha / (NxH2 + a * a);
  return k * k * INV_PI;
}

/* Beckmann 1963, in Walter et al. 2007's form: eq. 1.14,
 * exp((NoH^2 - 1) / (alpha^2 NoH^2)) / (pi alpha^2 NoH^4), zero for NoH <= 0. The exponent uses
 * -|n x h|^2 for 1 - NoH^2, for the same reason as D_GGX. */
float D_Beckmann(float NoH, float NxH2, float alpha)
{
  /* Below n.h = 0.1, D <= exp(-99) / (pi 1e-4) = 3e-40 even at alpha = 1: under float32's normal
   * range, while pi alpha^2 NoH^4 underflows to 0 and made 0 / 0 (NaN) in tests/test_stability.py. */
  if (NoH < 0.1) {
    return 0.0;
  }
  float a2 = alpha * alpha;
  float c2 = NoH * NoH;
  return exp(-NxH2 / (a2 * c2)) / (PI * a2 * c2 * c2);
}

/* ---- masking-shadowing, as visibility V = G / (4 NoV NoL) --------------------------------- */

/* Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs": Smith
 * height-correlated G of eqs. 1.16-1.17 for GGX, with 1 / (4 NoV NoL) folded in algebraically. */
float V_SmithGGXCorrelated(float NoV, float NoL, float alpha)
{
  float a2 = alpha * alpha;
  float lambda_v = NoL * sqrt(NoV * NoV * (1.0 - a2) + a2);
  float lambda_l = NoV * sqrt(NoL * NoL * (1.0 - a2) + a2);
  return 0.5 / (lambda_v + lambda_l);
}

/* Smith separable (uncorrelated) G = G1(v) G1(l) for GGX (Walter et al. 2007, eq. 34):
 * G1 = 2 NoX / (NoX + sqrt(alpha^2 + (1 - alpha^2) NoX^2)); the 2 x 2 cancels the 4. */
float V_SmithGGXSeparable(float NoV, float NoL, float alpha)
{
  float a2 = alpha * alpha;
  float gv = NoV + sqrt(a2 + (1.0 - a2) * NoV * NoV);
  float gl = NoL + sqrt(a2 + (1.0 - a2) * NoL * NoL);
  return 1.0 / (gv * gl);
}

/* Smith Lambda for Beckmann: Walter et al. 2007's rational approximation (eq. 27), with
 * a = NoX / (alpha sqrt(1 - NoX^2)); exact to within 0.35 % and used by Mitsuba and PBRT. */
float Lambda_Beckmann(float NoX, float alpha)
{
  float s2 = max(1.0 - NoX * NoX, 0.0);
  if (s2 <= 0.0) {
    return 0.0;
  }
  /* a -> 0 at grazing: Lambda -> 1 / (3.535 a) -> Inf; a floor of 1e-7 keeps it finite (G -> 0) */
  float a = max(NoX / (alpha * sqrt(s2)), 1e-7);
  if (a >= 1.6) {
    return 0.0;
  }
  return (1.0 - 1.259 * a + 0.396 * a * a) / (3.535 * a + 2.181 * a * a);
}

/* Smith height-correlated G for Beckmann (eq. 1.16 with Beckmann's Lambda). */
float V_SmithBeckmannCorrelated(float NoV, float NoL, float alpha)
{
  float G = 1.0 / (1.0 + Lambda_Beckmann(NoV, alpha) + Lambda_Beckmann(NoL, alpha));
  return G / (4.0 * NoV * NoL);
}

/* Smith separable G1(v) G1(l) for Beckmann. */
float V_SmithBeckmannSeparable(float NoV, float NoL, float alpha)
{
  float G = 1.0 / ((1.0 + Lambda_Beckmann(NoV, alpha)) * (1.0 + Lambda_Beckmann(NoL, alpha)));
  return G / (4.0 * NoV * NoL);
}

/* The V-cavity model of Torrance & Sparrow 1967 in Cook & Torrance 1982's form:
 * G = min(1, 2 NoH NoV / VoH, 2 NoH NoL / VoH), independent of the NDF. */
float V_CookTorrance(float NoV, float NoL, float NoH, float VoH)
{
  float G = min(1.0, 2.0 * NoH * min(NoV, NoL) / max(VoH, MIN_COS));
  return G / (4.0 * NoV * NoL);
}

/* Hammon 2017, "PBR Diffuse Lighting for GGX+Smith Microsurfaces": a cheap fit of the
 * height-correlated GGX visibility, 0.5 / mix(2 NoL NoV, NoL + NoV, alpha). */
float V_SmithGGXHammon(float NoV, float NoL, float alpha)
{
  return 0.5 / mix(2.0 * NoL * NoV, NoL + NoV, alpha);
}

/* Schlick 1994's approximation of Smith G1 for Beckmann, k = alpha sqrt(2 / pi):
 * G1 = NoX / (NoX (1 - k) + k). The cheap option matched to the Beckmann NDF. */
float V_SchlickBeckmann(float NoV, float NoL, float alpha)
{
  float k = alpha * 0.7978845608;
  float gv = NoV * (1.0 - k) + k;
  float gl = NoL * (1.0 - k) + k;
  return 0.25 / (gv * gl);
}

/* ---- diffuse (rho: the diffuse albedo; each returns f_d without the n.l of the light) --------- */

/* Lambertian diffuse lobe, eq. 1.18 without its (1 - F) weight (the model applies it). */
float Fd_Lambert()
{
  return INV_PI;
}

/* Burley 2012, "Physically-Based Shading at Disney": the retro-reflective diffuse with
 * F_D90 = 0.5 + 2 r LoH^2. Not energy conserving: its white albedo reaches 1.40 at r = 1 and
 * 85 degrees (1 + 1/28 at normal incidence), measured in tests/test_reference.py. */
float Fd_Burley(float NoV, float NoL, float LoH, float roughness)
{
  float f90 = 0.5 + 2.0 * roughness * LoH * LoH;
  float light_scatter = 1.0 + (f90 - 1.0) * pow5(1.0 - NoL);
  float view_scatter = 1.0 + (f90 - 1.0) * pow5(1.0 - NoV);
  return light_scatter * view_scatter * INV_PI;
}

/* Lagarde & de Rousiers 2014, "Moving Frostbite to PBR", listing 1: Burley's diffuse with the
 * energy bias mix(0, 0.5, r) and factor mix(1, 1 / 1.51, r), so that it stays below 1. */
float Fd_BurleyRenormalized(float NoV, float NoL, float LoH, float roughness)
{
  float energy_bias = mix(0.0, 0.5, roughness);
  float energy_factor = mix(1.0, 1.0 / 1.51, roughness);
  float f90 = energy_bias + 2.0 * LoH * LoH * roughness;
  float light_scatter = 1.0 + (f90 - 1.0) * pow5(1.0 - NoL);
  float view_scatter = 1.0 + (f90 - 1.0) * pow5(1.0 - NoV);
  return light_scatter * view_scatter * energy_factor * INV_PI;
}

/* Oren & Nayar 1994, "Generalization of Lambert's Reflectance Model": the full model, the
 * direct term L1 with its coefficients C1, C2, C3 and the interreflection term L2 (quadratic in
 * rho), sigma = r radians. cos_phi is the cosine of the azimuth between l and v projected on the
 * surface. Returns f_d including rho. */
vec3 Fd_OrenNayar(vec3 rho, float NoV, float NoL, float cos_phi, float roughness)
{
  float s2 = roughness * roughness;
  float theta_i = acos_accurate(NoL);
  float theta_r = acos_accurate(NoV);
  float alpha = max(theta_i, theta_r);
  float beta = min(theta_i, theta_r);
  float C1 = 1.0 - 0.5 * s2 / (s2 + 0.33);
  float C2 = 0.45 * s2 / (s2 + 0.09);
  if (cos_phi >= 0.0) {
    C2 *= sin(alpha);
  }
  else {
    float t = 2.0 * beta / PI;
    C2 *= sin(alpha) - t * t * t;
  }
  float t2 = 4.0 * alpha * beta / (PI * PI);
  float C3 = 0.125 * (s2 / (s2 + 0.09)) * t2 * t2;
  float tan_beta = tan(min(beta, 1.5));
  float tan_half = tan(min(0.5 * (alpha + beta), 1.5));
  float L1 = C1 + cos_phi * C2 * tan_beta + (1.0 - abs(cos_phi)) * C3 * tan_half;
  float b = 2.0 * beta / PI;
  float L2 = 0.17 * s2 / (s2 + 0.13) * (1.0 - cos_phi * b * b);
  return (rho * L1 + rho * rho * L2) * INV_PI;
}

/* Hammon 2017, "PBR Diffuse Lighting for GGX+Smith Microsurfaces": a fit of the diffuse
 * reflection of a GGX + Smith microsurface of Lambertian facets, single + multiple scattering,
 * including its own Fresnel-like falloff (so no (1 - F) weight). */
vec3 Fd_GGXHammon(vec3 rho, float NoV, float NoL, float NoH, float LoV, float alpha)
{
  float facing = 0.5 + 0.5 * LoV;
  float rough = facing * (0.9 - 0.4 * facing) * ((0.5 + NoH) / max(NoH, MIN_COS));
  float smooth_ = 1.05 * (1.0 - pow5(1.0 - NoL)) * (1.0 - pow5(1.0 - NoV));
  float single = mix(smooth_, rough, alpha);
  float multi = 0.1159 * alpha;
  return rho * (single + rho * multi) * INV_PI;
}

/* ---- Blinn-Phong and Phong ----------------------------------------------------------------- */

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

/* The energy-normalised Blinn-Phong lobe (Akenine-Moeller et al., Real-Time Rendering 4th ed.,
 * eq. 9.39 family): (s + 8) / (8 pi) ((n.h)+)^s is a BRDF whose albedo stays near 1 at normal
 * incidence for every s, unlike the seed's unnormalised ((n.h)+)^s. */
float S_BlinnPhongNormalized(float NoH, float shininess)
{
  return (shininess + 8.0) / (8.0 * PI) * pow(max(NoH, 0.0), shininess);
}
