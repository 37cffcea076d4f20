/* Dispatchers of the physically based model (Filament's surface_brdf.fs pattern): one define per
 * term family picks the variant compiled into the program; only the chosen functions are called.
 *   SL_FRESNEL_{SCHLICK, SCHLICK_SG, SCHLICK_GENERAL, EXACT}
 *   SL_NDF_{GGX, BECKMANN}
 *   SL_VISIBILITY_{SMITH_CORRELATED, SMITH_SEPARABLE, VCAVITY, APPROX}  (matched to the NDF)
 *   SL_DIFFUSE_{LAMBERT, BURLEY, BURLEY_RENORMALIZED, OREN_NAYAR, GGX_HAMMON, LAYERED} */

vec3 pbr_fresnel(Surface s, float LoH)
{
#if defined(SL_FRESNEL_SCHLICK_SG)
  return F_SchlickSG(s.f0, s.f90, LoH);
#elif defined(SL_FRESNEL_SCHLICK_GENERAL)
  return F_SchlickGeneral(s.f0, s.f90, s.fresnel_p, LoH);
#elif defined(SL_FRESNEL_EXACT)
  /* The dielectric part from its IOR; the metal part from its complex IOR when the material has
   * one, else Schlick from the base colour (a base colour alone does not determine n + ik). */
  vec3 dielectric = vec3(F_Dielectric(s.eta, LoH));
  vec3 metal = s.has_complex_ior ? F_Conductor(s.ior_n, s.ior_k, LoH) : F_Schlick(s.base_color, 1.0, LoH);
  return mix(dielectric, metal, s.metalness);
#else
  return F_Schlick(s.f0, s.f90, LoH);
#endif
}

float pbr_distribution(float NoH, float NxH2, float alpha)
{
#if defined(SL_NDF_BECKMANN)
  return D_Beckmann(NoH, NxH2, alpha);
#else
  return D_GGX(NoH, NxH2, alpha);
#endif
}

float pbr_visibility(float NoV, float NoL, float NoH, float LoH, float alpha)
{
#if defined(SL_VISIBILITY_VCAVITY)
  return V_CookTorrance(NoV, NoL, NoH, LoH);
#elif defined(SL_NDF_BECKMANN)
#  if defined(SL_VISIBILITY_SMITH_SEPARABLE)
  return V_SmithBeckmannSeparable(NoV, NoL, alpha);
#  elif defined(SL_VISIBILITY_APPROX)
  return V_SchlickBeckmann(NoV, NoL, alpha);
#  else
  return V_SmithBeckmannCorrelated(NoV, NoL, alpha);
#  endif
#else
#  if defined(SL_VISIBILITY_SMITH_SEPARABLE)
  return V_SmithGGXSeparable(NoV, NoL, alpha);
#  elif defined(SL_VISIBILITY_APPROX)
  return V_SmithGGXHammon(NoV, NoL, alpha);
#  else
  return V_SmithGGXCorrelated(NoV, NoL, alpha);
#  endif
#endif
}

/* The diffuse lobe f_d (without the light's n.l). Only Lambert takes eq. 1.18's (1 - F) weight:
 * Burley's retro-reflection and Hammon's fit carry their own Fresnel-like falloff, Oren-Nayar
 * has none; LAYERED is Lambert under the dielectric layer's albedo at the view, as Blender's
 * Principled BSDF weighs its base (principled.glsl's layers: Kulla & Conty 2017, Cycles' S). */
vec3 pbr_diffuse(Surface s, vec3 F, float NoV, float NoL, float NoH, float LoH, float LoV)
{
  vec3 rho = s.base_color * (1.0 - s.metalness);
#if defined(SL_DIFFUSE_BURLEY)
  return rho * Fd_Burley(NoV, NoL, LoH, s.roughness);
#elif defined(SL_DIFFUSE_BURLEY_RENORMALIZED)
  return rho * Fd_BurleyRenormalized(NoV, NoL, LoH, s.roughness);
#elif defined(SL_DIFFUSE_OREN_NAYAR)
  /* cos of the azimuth between l and v: their projections on the tangent plane */
  float denom = sqrt(max((1.0 - NoL * NoL) * (1.0 - NoV * NoV), 0.0));
  float cos_phi = denom > 1e-6 ? clamp((LoV - NoL * NoV) / denom, -1.0, 1.0) : 1.0;
  return Fd_OrenNayar(rho, NoV, NoL, cos_phi, s.roughness);
#elif defined(SL_DIFFUSE_GGX_HAMMON)
  return Fd_GGXHammon(rho, NoV, NoL, NoH, LoV, s.alpha);
#elif defined(SL_DIFFUSE_LAYERED)
  return rho * (saturate(1.0 - s.layers.layer) * Fd_Lambert());
#else
  return (vec3(1.0) - F) * rho * Fd_Lambert();
#endif
}
