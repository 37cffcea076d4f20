/* Physically based: f = f_spec (eq. 1.10) + f_diff, metal/dielectric workflow, HDR.
 * f_spec = F(l.h) D(h) G(l, v, h) / (4 |n.v| |n.l|) = F D V with the variants of pbr_terms.glsl;
 * the default program is Schlick F, GGX D, Smith height-correlated G and Lambert (1 - F) rho / pi.
 * F0 = mix(dielectric F0, base colour, metalness); F90 = saturate(50 F0) unless the material sets
 * it: 1 for any real material (F0 >= 0.02), fading the Fresnel tail out as F0 -> 0 so that "no
 * specular" (F0 = 0) means none at grazing angles either (Schueler 2012, used by Filament). */

/* What multiplies D V in the specular lobe at l.h = LoH: F (eq. 1.10) with the energy
 * compensation; for the Principled set, its metal and dielectric lobes' Fresnel and compensation,
 * weighted by metalness. An area light's lobe (light_shading.glsl) shares it. */
vec3 pbr_specular_tint(Surface s, float LoH)
{
#ifdef SL_PRINCIPLED
  return principled_specular_tint(s, LoH);
#else
  return pbr_fresnel(s, LoH) * specular_energy_compensation(s);
#endif
}

/* The specular lobe's shape towards l, D V (n.l) with F = 1 (the program's distribution and
 * visibility; the Principled set's GGX and Smith). */
float pbr_lobe(Surface s, vec3 l)
{
  float NoL = dot(s.n, l);
  if (NoL <= 0.0) {
    return 0.0;
  }
  vec3 h = half_vector(l, s.v, s.n);
  float NoH = saturate(dot(s.n, h));
  vec3 NxH = cross(s.n, h);
  float LoH = saturate(dot(l, h));
#ifdef SL_PRINCIPLED
  float DV = principled_DV(s, l, h, NoL, NoH, dot(NxH, NxH));
#  ifdef SL_GLOSSY
  DV = glossy_lobe(s, DV, NoL, NoH, dot(NxH, NxH), LoH); /* the Glossy BSDFs' distributions (closures.glsl) */
#  endif
  return DV * NoL;
#else
  return pbr_distribution(NoH, dot(NxH, NxH), s.alpha) * pbr_visibility(s.NoV, NoL, NoH, LoH, s.alpha) * NoL;
#endif
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
  float LoV = dot(l, s.v);
#ifdef SL_PRINCIPLED
  return principled_direct(s, l, h, NoL, NoH, dot(NxH, NxH), LoH, E, factors);
#endif
  vec3 F = pbr_fresnel(s, LoH);
  float D = pbr_distribution(NoH, dot(NxH, NxH), s.alpha);
  float V = pbr_visibility(s.NoV, NoL, NoH, LoH, s.alpha);
  vec3 specular = F * (D * V) * specular_energy_compensation(s);  /* eq. 1.10 */
  vec3 diffuse = pbr_diffuse(s, F, s.NoV, NoL, NoH, LoH, LoV);
  return (diffuse * factors.x + specular * factors.y) * E * NoL;
}

#ifdef SL_ENV_SAMPLES
/* The world's specular light by importance sampling the actual BRDF at every pixel: half
 * vectors drawn from D (Walter et al. 2007, eq. 35-36 for GGX, 28-29 for Beckmann) at
 * SL_ENV_SAMPLES Hammersley points, each sample's light read with filtered importance sampling
 * (environment.glsl), weighted by f cos / pdf = F V 4 (v.h)(n.l) / (n.h). No split-sum
 * assumption (n = v = r): it converges to the unoccluded reference as the count grows. */
vec3 env_sample_lobe(Surface s, sampler2D chain_map)
{
#  ifdef SL_ANISOTROPY
  /* the anisotropic lobe by its visible normals (anisotropy.glsl's anisotropic_sample): f cos / pdf =
   * F G2 / G1(v); any roughness (an axis may be long where the mean roughness is at the floor) */
  AnisotropicView w = anisotropic_view(s.aniso, s.n, s.v, s.NoV);
  vec3 sum = vec3(0.0);
  int i = 0;
  do { /* tested at the end (glsl/README.md) */
    float pdf, VoH, weight;
    vec3 l = anisotropic_sample(s.aniso, s.n, w, i, SL_ENV_SAMPLES, pdf, VoH, weight);
    if (weight > 0.0) {
      vec3 L = chain_lookup(chain_map, l, chain_lod(pdf, SL_ENV_SAMPLES, 0.0));
      sum += L * principled_specular_tint(s, VoH) * weight;
    }
  } while (++i < SL_ENV_SAMPLES);
  return sum / float(SL_ENV_SAMPLES);
#  else
  vec3 up = abs(s.n.z) < 0.999 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
  vec3 tx = normalize(cross(up, s.n));
  vec3 ty = cross(s.n, tx);
  float a2 = s.alpha * s.alpha;
  if (s.roughness <= MIN_PERCEPTUAL_ROUGHNESS) {
    /* at the roughness floor the lobe stands for a perfect mirror (roughness 0, as Cycles
     * renders it): GGX's long tails at alpha = 0.002 would still blur fine detail */
    vec3 r = reflect(-s.v, s.n);
#  ifdef SL_PRINCIPLED
    return chain_level(chain_map, 0, equirect_uv(r)) * principled_specular_tint(s, s.NoV);
#  else
    return chain_level(chain_map, 0, equirect_uv(r)) * pbr_fresnel(s, s.NoV);
#  endif
  }
  vec3 sum = vec3(0.0);
  int i = 0;
  do { /* tested at the end (glsl/README.md); `continue` goes to the test */
    float phi = 2.0 * PI * (float(i) + 0.5) / float(SL_ENV_SAMPLES);
    float xi = radical_inverse(uint(i));
#  ifdef SL_NDF_BECKMANN
    float cos_t = inversesqrt(1.0 - a2 * log(max(1.0 - xi, 1e-12)));
#  else
    float cos_t = sqrt((1.0 - xi) / (1.0 + (a2 - 1.0) * xi));
#  endif
    float sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    vec3 h = tx * (sin_t * cos(phi)) + ty * (sin_t * sin(phi)) + s.n * cos_t;
    float VoH = dot(s.v, h);
    vec3 l = 2.0 * VoH * h - s.v;
    float NoL = dot(s.n, l);
    if (VoH <= 0.0 || NoL <= 0.0) {
      continue;
    }
    float NoH = max(cos_t, MIN_COS);
    float D = pbr_distribution(NoH, sin_t * sin_t, s.alpha);
    float pdf = D * NoH / (4.0 * VoH);
    /* no extra bias level: measured against Cycles on the bundled forest world, bias 0 and 0.5
     * differ by under 1 % at 256 samples; 1 blurs what near-mirror lobes see */
    vec3 L = chain_lookup(chain_map, l, chain_lod(pdf, SL_ENV_SAMPLES, 0.0));
#  ifdef SL_PRINCIPLED
    vec3 F = principled_specular_tint(s, VoH);
    float V = V_SmithGGXCorrelated(s.NoV, NoL, s.alpha);
#  else
    vec3 F = pbr_fresnel(s, VoH);
    float V = pbr_visibility(s.NoV, NoL, NoH, VoH, s.alpha);
#  endif
    sum += L * F * (V * 4.0 * VoH * NoL / NoH);
  } while (++i < SL_ENV_SAMPLES);
#  ifdef SL_PRINCIPLED
  return sum / float(SL_ENV_SAMPLES);
#  else
  return sum / float(SL_ENV_SAMPLES) * specular_energy_compensation(s);
#  endif
#  endif
}

/* The whole world for smooth surfaces, the world without its suns (lit by them as lights) for
 * rough ones, ramping between as the split-sum levels do (world_sun_specular). */
vec3 env_sampled_specular(Surface s)
{
  float t = world_sun_specular(s.roughness);
  vec3 whole = t < 1.0 ? env_sample_lobe(s, env_chain) : vec3(0.0);
  vec3 clamped = t > 0.0 ? env_sample_lobe(s, env_chain_clamped) : vec3(0.0);
  return mix(whole, clamped, t);
}
#endif

#if defined(SL_ENV_UNIFORM) || defined(SL_ENV_MAP)
/* The world's light (glsl/ibl.glsl): the split-sum specular lobe, the prefiltered radiance read
 * where the lobe's energy peaks, and the diffuse lobe lit by the irradiance, weighted by the
 * energy the specular lobe did not take (1 - F0 (E - B) - F90 B: Lambert's 1 - F over the
 * hemisphere; every diffuse variant is lit this way). */
vec3 shade_environment_surface(Surface s, vec2 weights)
{
  vec2 EB = env_split_sum(s.NoV, s.roughness);
#  ifdef SL_ANISOTROPY
  /* a round lobe in an anisotropic program (a coat, anisotropic_none; a pixel whose Anisotropic is 0)
   * takes the round split sum below, as the round program draws it (the same image to 2e-7,
   * tests/test_anisotropy.py); an anisotropic one's reflection, for the specular occlusion: about its
   * bent normal (anisotropy.glsl) */
  bool anisotropic = s.aniso.alpha_x != s.aniso.alpha_y;
  vec3 n_r = anisotropic ? anisotropic_bent_normal(s.aniso, s.n, s.v, s.roughness) : s.n;
#  else
  vec3 n_r = s.n;
#  endif
  vec3 r = reflect(-s.v, n_r);
  float ao = env_occlusion_diffuse();
  float specular_ao = env_occlusion_specular(s.n, r, s.alpha);
  vec3 radiance;
#  ifdef SL_ANISOTROPY
  if (anisotropic) {
    /* the anisotropic lobe's albedo times the radiance it sees, sampled (anisotropy.glsl), over the round
     * lobe's E the split sum's albedo multiplies back (the table's E >= 0.31 at every n.v and roughness:
     * the guard keeps the division finite whatever the table) */
    radiance = anisotropic_environment(s.aniso, s.n, s.v, s.NoV) / max(EB.x, 1e-4) * specular_ao;
  } else
#  endif
  {
    radiance = env_prefiltered(s.roughness > MIN_PERCEPTUAL_ROUGHNESS ? env_dominant_direction(n_r, r, s.alpha) : r,
                               s.roughness) * specular_ao;
  }
  vec3 irradiance = env_irradiance(env_bent_normal(s.n)) * ao;
#  ifdef SL_PRINCIPLED
  return principled_environment(s, EB, radiance, irradiance, weights);
#  else
  vec3 albedo = s.f0 * (EB.x - EB.y) + s.f90 * EB.y;
#    ifdef SL_ENV_SAMPLES
  vec3 specular = env_sampled_specular(s) * specular_ao;
#    else
  vec3 specular = albedo * radiance;
#    endif
#    ifdef SL_MULTISCATTER
  /* light scattered more than once between microfacets leaves like a rough diffuse lobe
   * (Fdez-Aguera 2019, eq. 16-18): Fms Ems of the irradiance */
  float Ems = 1.0 - EB.x;
  vec3 Favg = s.f0 + (1.0 - s.f0) / 21.0;
  vec3 Fms_Ems = albedo * Favg * Ems / (1.0 - Ems * Favg);
  specular += Fms_Ems * irradiance * INV_PI;
  albedo += Fms_Ems;
#    endif
#    ifdef SL_DIFFUSE_LAYERED
  vec3 diffuse = s.base_color * (1.0 - s.metalness) * saturate(1.0 - s.layers.layer) * irradiance * INV_PI;
#    else
  vec3 diffuse = s.base_color * (1.0 - s.metalness) * clamp(1.0 - albedo, 0.0, 1.0) * irradiance * INV_PI;
#    endif
  return diffuse * weights.x + specular * weights.y;
#  endif
}

/* The world's light: the surface's, under the Principled BSDF's upper layers where the program draws
 * them (as light_shading.glsl's shade_light: the base times what they leave it at the view, the
 * coat's split sum of its own lobe, and the sheen's albedo times the world through its own lobe,
 * sampled: principled.glsl's sheen_environment). */
vec3 shade_environment(Surface s, vec2 weights)
{
  vec3 c = shade_environment_surface(s, weights);
#  if defined(SL_COAT) || defined(SL_SHEEN)
  c *= s.below;
#  endif
#  ifdef SL_COAT
  c += s.coat.weight * shade_environment_surface(coat_surface(s), weights * vec2(0.0, 1.0));
#  endif
#  ifdef SL_SHEEN
  c += s.sheen.color * sheen_environment(s) * (env_occlusion_diffuse() * weights.x);
#  endif
#  ifdef SL_CLOSURE_BSDFS
  c += closure_bsdfs_environment(s, weights); /* the velvet's and the toons' (closures.glsl) */
#  endif
  return c;
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
