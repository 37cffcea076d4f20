/* The closure nodes drawn beside the Principled BSDF's lobes, by the physically based model's
 * Principled set (glsl/node_closure_bsdfs.glsl gives their inputs per fragment: MaterialData's
 * closure rows), each only in programs whose materials use it:
 *   SL_DIFFUSE_ROUGHNESS  the Diffuse BSDF's Roughness: Cycles' Oren-Nayar (bsdf_oren_nayar.h) of the
 *                         Blender that read the graph (materials/surface.py's oren_nayar: one
 *                         SL_OREN_NAYAR_<RULE>), in place of the base's Lambert: Fujii's improved
 *                         Oren-Nayar with the OpenPBR energy-preserving multiple-scattering term
 *                         (FUJII_MULTISCATTER: 4.5, 5.0), or alone (FUJII: 4.2);
 *   SL_VELVET             the Sheen BSDF's Ashikhmin distribution (bsdf_ashikhmin_velvet.h);
 *   SL_TOON               the Toon BSDF's Diffuse and Glossy components (bsdf_toon.h).
 * (The Sheen BSDF's Microfiber distribution is the Principled BSDF's sheen: principled.glsl.)
 * Each lobe's f (n.l) is Cycles' bsdf eval (which holds the light's cosine); twins in
 * addon/reference/closures.py. Lights: each lobe at the light's direction (an area or sphere light
 * at its representative direction, as the surface's diffuse lobe); the world: each lobe's
 * directional albedo times the world's light around its direction (docs/limits.md). */

#ifdef SL_CLOSURE_BSDFS

/* Fujii's G(theta) (bsdf_oren_nayar_G): the directional albedo's Oren-Nayar part, E = A pi + B G;
 * below cos 1e-6 tan(theta) is unstable (Cycles falls back to its Taylor expansion there). */
float oren_nayar_G(float cos_theta)
{
  if (cos_theta < 1e-6) {
    return (0.5 * PI - 2.0 / 3.0) - cos_theta;
  }
  float sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
  float theta = acos_accurate(cos_theta);
  return sin_theta * (theta - 2.0 / 3.0 - sin_theta * cos_theta) +
         2.0 / 3.0 * (sin_theta / cos_theta) * (1.0 - sin_theta * sin_theta * sin_theta);
}

/* Ashikhmin's velvet f (n.l) for a view at cos_v and a light at cos_l with half vector h
 * (bsdf_ashikhmin_velvet_eval; 1 / sigma^2 given): D the inverted Gaussian of cot^2 of n.h, G
 * Cook-Torrance's V-cavity, f (n.l) = D G / (4 n.v). 0 off both hemispheres and where h lies along
 * n (sin^2 of n.h vanishing, where Cycles returns 0 too). */
float velvet_eval(float cos_v, float cos_l, float cos_nh, float cos_hl, float inv_sigma2)
{
  if (!(cos_v > 0.0 && cos_l > 0.0) || !(abs(cos_nh) < 1.0 - 1e-5 && cos_hl > 1e-5)) {
    return 0.0;
  }
  float ratio = max(cos_nh / cos_hl, 1e-5); /* Cycles' own floor of the V-cavity's ratio */
  float G = min(1.0, 2.0 * ratio * min(cos_v, cos_l));
  float sin2 = 1.0 - cos_nh * cos_nh;
  float D = exp(-cos_nh * cos_nh / sin2 * inv_sigma2) * inv_sigma2 * INV_PI / (sin2 * sin2);
  return 0.25 * D * G / cos_v;
}

/* The toon's intensity at `angle` from its axis (bsdf_toon_get_intensity): 1 within Size, then a
 * linear ramp over Smooth (both in radians), 0 beyond. */
float toon_intensity(float size, float smooth_, float angle)
{
  if (angle < size) {
    return 1.0;
  }
  return angle < size + smooth_ && smooth_ != 0.0 ? 1.0 - (angle - size) / smooth_ : 0.0;
}

/* The toon's f (n.l) at `angle` from its axis (bsdf_diffuse_toon_eval / bsdf_glossy_toon_eval):
 * its intensity over the cone it samples, of half-angle min(Size + Smooth, pi / 2), uniformly
 * (pdf 1 / (2 pi (1 - cos))); 1 - cos as 2 sin^2(x / 2), exact for the Size floor's 1.6e-5 rad. */
float toon_eval(vec2 shape, float angle)
{
  float cone = min(shape.x + shape.y, 0.5 * PI);
  if (!(angle < cone)) {
    return 0.0;
  }
  float s = sin(0.5 * cone);
  return toon_intensity(shape.x, shape.y, angle) / (4.0 * PI * s * s);
}

/* The toon's directional albedo: its intensity integrated over the cone it samples, over the cone's
 * solid angle (1 where Smooth is 0: the eval is the sampling's pdf). In closed forms free of
 * cancellation (Size's floor is 1.6e-5 rad, where 1 - cos rounds to 0 in float32): the inner cap
 * 2 sin^2(size / 2); the ramp int_0^w (1 - u / smooth) sin(size + u) du over the w = cone - size it
 * has below the horizon, sin(size) Re J + cos(size) Im J with J its integral of e^(iu). */
float toon_albedo(vec2 shape)
{
  float size = min(shape.x, 0.5 * PI);
  float cone = min(shape.x + shape.y, 0.5 * PI);
  float s = sin(0.5 * cone);
  float h = sin(0.5 * size);
  float ramp = 0.0;
  if (shape.y > 0.0 && cone > size) {
    float w = cone - size;
    float hw = sin(0.5 * w);
    float re = sin(w) - (w * sin(w) - 2.0 * hw * hw) / shape.y;
    float im = 2.0 * hw * hw - (sin(w) - w * cos(w)) / shape.y;
    ramp = sin(size) * re + cos(size) * im;
  }
  return (2.0 * h * h + ramp) / (2.0 * s * s);
}

/* The share of a cone of half-angle `c` about an axis at cos_axis from n that lies above the horizon:
 * the solid angle of two spherical caps' intersection (the cone's and the hemisphere's; Tovchigrechko &
 * Vakser 2001) over the cone's, 2 (pi - acos(cos g / sin c) - cos c acos(-cot g cot c)) / (2 pi (1 - cos c)),
 * g the axis' angle from n; 1 wholly above, 0 wholly below. */
float cone_above_horizon(float cos_axis, float c)
{
  float g = acos_accurate(cos_axis);
  if (g + c <= 0.5 * PI) {
    return 1.0;
  }
  if (g - c >= 0.5 * PI) {
    return 0.0;
  }
  float sin_c = max(sin(c), 1e-6); /* c > 0 here: the cone straddles the horizon */
  float sin_g = max(sin(g), 1e-6);
  float half_cap = sin(0.5 * c);
  float omega = 2.0 * (PI - acos_accurate(cos_axis / sin_c) -
                       cos(c) * acos_accurate(-cos_axis * cos(c) / (sin_g * sin_c)));
  return saturate(omega / (4.0 * PI * half_cap * half_cap));
}

/* The closure lobes at the view (surface.glsl's ClosureBsdfLobes, made once per shading point by
 * make_surface) from MaterialData's closure rows, as Cycles' setups take them: Oren-Nayar's A and B
 * of sigma = roughness and its multiple scattering's colour times 1 - E(v) (bsdf_oren_nayar_setup; the
 * colour per closure: node_closure.glsl's closure_diffuse), its directional albedo at the view; the
 * velvet's 1 / sigma^2 of sigma at least 0.01 (bsdf_ashikhmin_velvet_setup); the toons' Size and
 * Smooth times pi / 2 (bsdf_toon_setup_common). */
ClosureBsdfLobes closure_bsdfs_at(vec3 n, vec3 v, vec3 base_color, MaterialData m)
{
  ClosureBsdfLobes b;
#  ifdef SL_DIFFUSE_ROUGHNESS
  float sigma = saturate(m.closure_bsdfs.y);
  vec3 k = oren_nayar_coefficients(sigma);
  b.on_a = k.x;
  b.on_b = k.y;
  float e_v = k.x * PI + k.y * oren_nayar_G(max(dot(n, v), 0.0));
#    ifdef SL_OREN_NAYAR_FUJII
  /* Blender 4.2's Cycles: Lambert at roughness 0 only (svm_node_closure_bsdf), Fujii's single
   * scattering alone (4.2's bsdf_oren_nayar_get_intensity: rho (A + B t) n.l), whose albedo is E(v) */
  b.oren_nayar = sigma > 0.0;
  b.on_ms = vec3(0.0);
  b.on_albedo = b.oren_nayar ? base_color * e_v : base_color;
#    else
  /* Cycles 4.5 and 5.0 draw a Diffuse BSDF of roughness below 1e-5 as Lambert (bsdf_diffuse_setup) */
  b.oren_nayar = sigma >= 1e-5;
  b.on_ms = b.oren_nayar ? max(m.diffuse_ms.rgb, 0.0) * (1.0 - e_v) : vec3(0.0);
  /* int f (n.l) d omega_l: E(v) of the single scattering, pi (1 - E_avg) of the multiple's 1 - E(l) */
  b.on_albedo = b.oren_nayar ? base_color * e_v + PI * b.on_ms * (1.0 - k.z) : base_color;
#    endif
#  endif
#  ifdef SL_VELVET
  b.velvet = max(m.velvet.rgb, 0.0);
  float velvet_sigma = max(m.closure_bsdfs.z, 0.01);
  b.velvet_inv_sigma2 = 1.0 / (velvet_sigma * velvet_sigma);
#  endif
#  ifdef SL_TOON
  b.toon_diffuse = max(m.toon_diffuse.rgb, 0.0);
  b.toon_diffuse_shape = vec2(clamp(m.toon_diffuse.w, 1e-5, 1.0), saturate(m.toon_smooth.x)) * (0.5 * PI);
  b.toon_glossy = max(m.toon_glossy.rgb, 0.0);
  b.toon_glossy_shape = vec2(clamp(m.toon_glossy.w, 1e-5, 1.0), saturate(m.toon_smooth.y)) * (0.5 * PI);
#  endif
  return b;
}

#  ifdef SL_DIFFUSE_ROUGHNESS
/* The diffuse base of colour rho towards a light at cos_l, l.v = LoV, without n.l: Lambert's rho / pi,
 * or Oren-Nayar's (bsdf_oren_nayar_get_intensity over n.l) rho (A + B t) + E_ms (1 - E(v)) (1 - E(l)),
 * t = l.v - n.l n.v, over max(n.l, n.v) where positive; Blender 4.2's without the multiple scattering
 * (SL_OREN_NAYAR_FUJII: closure_bsdfs_at). */
vec3 oren_nayar_diffuse(Surface s, vec3 rho, float NoL, float LoV)
{
  if (!s.bsdfs.oren_nayar) {
    return rho * INV_PI;
  }
  float nl = max(NoL, 0.0);
  float nv = max(dot(s.n, s.v), 0.0);
  float t = LoV - nl * nv;
  if (t > 0.0) {
    t /= max(nl, nv) + 1.175494e-38; /* Cycles' FLT_MIN: both cosines 0 */
  }
#    ifdef SL_OREN_NAYAR_FUJII
  return rho * (s.bsdfs.on_a + s.bsdfs.on_b * t);
#    else
  float e_l = s.bsdfs.on_a * PI + s.bsdfs.on_b * oren_nayar_G(nl);
  return rho * (s.bsdfs.on_a + s.bsdfs.on_b * t) + s.bsdfs.on_ms * (1.0 - e_l);
#    endif
}
#  endif

/* The velvet's and the toons' f (n.l) towards l per unit irradiance, each lobe times its colour:
 * rgb the diffuse lobes' (velvet and Diffuse toon, Cycles' diffuse passes), the second the Glossy
 * toon's. */
void closure_bsdfs_direct(Surface s, vec3 l, out vec3 diffuse, out vec3 glossy)
{
  diffuse = vec3(0.0);
  glossy = vec3(0.0);
  float NoL = dot(s.n, l);
  float NoV = dot(s.n, s.v);
#  ifdef SL_VELVET
  vec3 sum = l + s.v;
  if (dot(sum, sum) > 0.0) {
    vec3 h = normalize(sum);
    diffuse += s.bsdfs.velvet * velvet_eval(NoV, NoL, dot(s.n, h), abs(dot(l, h)), s.bsdfs.velvet_inv_sigma2);
  }
#  endif
#  ifdef SL_TOON
  if (NoL >= 0.0) {
    diffuse += s.bsdfs.toon_diffuse * toon_eval(s.bsdfs.toon_diffuse_shape, acos_accurate(min(NoL, 1.0)));
  }
  if (NoV > 0.0 && NoL > 0.0) {
    vec3 r = 2.0 * NoV * s.n - s.v; /* the view reflected */
    glossy = s.bsdfs.toon_glossy * toon_eval(s.bsdfs.toon_glossy_shape, acos_accurate(saturate(dot(r, l))));
  }
#  endif
}

#  ifdef SL_VELVET
/* The velvet's directional albedo at the view: its f (n.l) integrated over the hemisphere by a
 * midpoint rule in t = sqrt(cos theta) (cos theta = t^2: denser towards the horizon, where a smooth
 * velvet's lobe lies) and phi, 16 x 8 points over the half the lobe is symmetric in (the world's
 * light only: 128 evaluations a fragment; within 4 % of a fine quadrature where the albedo exceeds
 * 0.01: tests/test_closure_nodes.py). */
float velvet_albedo(Surface s)
{
  float NoV = max(dot(s.n, s.v), MIN_COS);
  vec3 v = vec3(sqrt(max(1.0 - NoV * NoV, 0.0)), 0.0, NoV);
  float sum = 0.0;
  for (int i = 0; i < 16; i++) {
    float t = (float(i) + 0.5) / 16.0;
    float cos_l = t * t;
    float sin_l = sqrt(1.0 - cos_l * cos_l);
    float weight = 2.0 * t; /* d cos = 2 t dt */
    for (int j = 0; j < 8; j++) {
      float phi = PI * (float(j) + 0.5) / 8.0;
      vec3 l = vec3(sin_l * cos(phi), sin_l * sin(phi), cos_l);
      vec3 h = normalize(l + v);
      /* per unit solid angle: the eval holds n.l, d omega = d cos d phi */
      sum += weight * velvet_eval(NoV, cos_l, h.z, abs(dot(l, h)), s.bsdfs.velvet_inv_sigma2);
    }
  }
  return sum * (2.0 * PI / 128.0); /* both halves of phi: 2 x (1 / 16) x (pi / 8) per point */
}
#  endif

#  if defined(SL_ENV_UNIFORM) || defined(SL_ENV_MAP)
/* The world's light on the velvet and the toons: each lobe's directional albedo times the world's
 * light around its axis, the diffuse lobes' the irradiance about n over pi (exact for a uniform world),
 * the Glossy toon's the prefiltered radiance about the view's reflection at the roughness whose
 * GGX lobe is about as wide as its cone (alpha = tan of the cone's half-angle, at most 1), times the
 * share of its cone above the horizon (its solid angle's, the ramp taken as flat). */
vec3 closure_bsdfs_environment(Surface s, vec2 weights)
{
  vec3 c = vec3(0.0);
  vec3 irradiance = env_irradiance(env_bent_normal(s.n)) * (env_occlusion_diffuse() * INV_PI);
#    ifdef SL_VELVET
  c += s.bsdfs.velvet * velvet_albedo(s) * irradiance * weights.x;
#    endif
#    ifdef SL_TOON
  c += s.bsdfs.toon_diffuse * toon_albedo(s.bsdfs.toon_diffuse_shape) * irradiance * weights.x;
  vec3 r = reflect(-s.v, s.n);
  float cone = min(s.bsdfs.toon_glossy_shape.x + s.bsdfs.toon_glossy_shape.y, 0.5 * PI);
  float roughness = sqrt(min(tan(min(cone, 0.25 * PI)), 1.0));
  /* the cone's part below the horizon reflects nothing (Cycles' eval: n.l > 0) */
  float above = cone_above_horizon(dot(s.n, r), cone);
  c += s.bsdfs.toon_glossy * toon_albedo(s.bsdfs.toon_glossy_shape) * env_prefiltered(r, roughness) *
       (above * env_occlusion_specular(s.n, r, roughness * roughness) * weights.y);
#    endif
  return c;
}
#  endif
#endif

#ifdef SL_GLOSSY
/* The Glossy BSDF (node_closure_bsdfs.glsl) in the Principled set's metal lobe: Cycles 5.0 gives it no
 * Fresnel but its colour (bsdf_microfacet.h's MicrofacetFresnel::NONE; Multiscatter GGX's
 * compensation takes the colour as its average Fresnel), and GGX, Beckmann or Ashikhmin-Shirley. */

/* Ashikhmin & Shirley 2000's isotropic lobe as Cycles evaluates it (bsdf_ashikhmin_shirley_eval; its
 * Fresnel left out): (e + 1) / (8 pi) (n.h)^e over (l.h) max(n.v, n.l), e = 2 / alpha^2 - 2, the
 * cosines floored at 1e-6 as Cycles floors them; f = this times the colour. */
float D_V_AshikhminShirley(float NoV, float NoL, float NoH, float LoH, float alpha)
{
  if (alpha <= 1e-4) {
    return 0.0; /* Cycles' mirror limit of the lobe: none */
  }
  float e = 2.0 / (alpha * alpha) - 2.0;
  float pump = 1.0 / max(1e-6, max(LoH, 1e-6) * max(max(NoV, NoL), 1e-6));
  return (e + 1.0) / (8.0 * PI) * pow(max(NoH, 1e-6), e) * pump;
}

#  ifdef SL_LAYERS /* the Principled set's (its metal lobe's compensation) */
/* The metal lobe's Fresnel times its compensation: the Principled BSDF's F82-tint `F` (its albedo
 * for the world's split sum) and compensation M beside the Glossy BSDFs' share of the lobe, their
 * colour (times `albedo`, the lobe's own albedo for the world's split sum, 1 towards a light) and its
 * compensation; the share of uncompensated lobes (GGX, Beckmann, Ashikhmin-Shirley) without it, spread
 * over both where both are mixed. */
vec3 glossy_metal(Surface s, vec3 F, vec3 M, float albedo)
{
  float colour_share = s.glossy.x;
  float uncompensated = s.glossy.y;
  vec3 glossy = max(s.base_color, 0.0) * albedo * mix(s.layers.glossy_M, vec3(1.0), uncompensated);
  return (1.0 - colour_share) * F * mix(M, vec3(1.0), uncompensated) + colour_share * glossy;
}

/* The specular lobe's D V with the Glossy BSDFs' shares of Beckmann (Smith height-correlated, the
 * Beckmann Lambda Cycles uses) and Ashikhmin-Shirley in place of GGX's `DV`. */
float glossy_lobe(Surface s, float DV, float NoL, float NoH, float NxH2, float LoH)
{
  float beckmann = s.glossy.z;
  float ashikhmin = s.glossy.w;
  if (beckmann + ashikhmin <= 0.0) {
    return DV;
  }
  float b = beckmann > 0.0 ? D_Beckmann(NoH, NxH2, s.alpha) * V_SmithBeckmannCorrelated(s.NoV, NoL, s.alpha) : 0.0;
  float a = ashikhmin > 0.0 ? D_V_AshikhminShirley(s.NoV, NoL, NoH, LoH, s.alpha) : 0.0;
  return (1.0 - beckmann - ashikhmin) * DV + beckmann * b + ashikhmin * a;
}
#  endif
#endif
