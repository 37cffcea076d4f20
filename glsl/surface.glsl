/* The shading point: geometry and material inputs every model reads. */

#ifdef SL_LAYERS
/* What the Principled set (and the LAYERED diffuse) needs at the view direction (principled.glsl):
 * the metal lobe's and the dielectric lobe's multiple-scattering compensation and the dielectric
 * layer's albedo estimate that the diffuse base sits under. They depend on the view only, so
 * make_surface computes them once per shading point, not once per light. */
struct PrincipledLayers {
  vec3 metal_M;
  vec3 dielectric_M;
  vec3 albedo;         /* the dielectric layer's albedo estimate (rgb) */
  float layer;         /* its largest channel: what the base below loses */
  vec3 dielectric_f0;  /* the dielectric's F0 (times the tint: SL_SPECULAR_TINT) */
#ifdef SL_SPECULAR_TINT
  vec3 metal_b;        /* F82-tint's b */
#endif
#ifdef SL_GLOSSY
  vec3 glossy_M;       /* the compensation of a metal lobe whose Fresnel is its colour (Glossy BSDF) */
#endif
};
PrincipledLayers principled_layers_at(float NoV, float roughness, vec3 base_color, float eta, vec3 tint);
#endif

#if defined(SL_LTC) || defined(SL_SHEEN)
/* What area lights' linearly transformed cosines need at the view direction (ltc.glsl): the
 * shading frame (x the tangent towards v, y = n x x), the LTC's M^-1 entries and the lobe's
 * albedo. They depend on the view only, so make_surface computes them once per shading point,
 * not once per area light. (The sheen is such a cosine itself: SheenLobe.) */
struct LtcFrame {
  vec3 x_axis;
  vec3 y_axis;
  vec4 m;
  float albedo;
};
#endif
#ifdef SL_LTC
LtcFrame ltc_frame_at(vec3 n, vec3 v, float NoV, float roughness);
#endif

#ifdef SL_COAT
/* The Principled BSDF's coat at the view (principled.glsl's coat_at): a dielectric GGX layer of
 * its own normal, roughness and IOR over the rest, its compensation and albedo estimate (its
 * PrincipledLayers, of a black dielectric) and its LTC frame, made once per shading point; the
 * lights and the world shade it as a Surface of its own (coat_surface). */
struct CoatLayer {
  float weight;        /* the coat's lobe weight: Coat Weight, times what the sheen above leaves it */
  vec3 n;
  float NoV;
  float roughness;
  float eta;
  PrincipledLayers layers;
#  ifdef SL_LTC
  LtcFrame ltc;
#  endif
};
CoatLayer coat_at(vec3 n, vec3 v, vec4 coat, vec3 coat_normal);
vec3 coat_transmittance(CoatLayer c, vec3 tint);
#endif

#ifdef SL_SHEEN
/* The Principled BSDF's sheen at the view (principled.glsl's sheen_at): Zeltner, Burley & Chiang
 * 2022's microfiber sheen, a linearly transformed cosine of its own normal (its frame and M^-1 in
 * ltc; ltc.albedo its directional albedo), times its colour. */
struct SheenLobe {
  vec3 color;          /* Sheen Weight x Sheen Tint x the lobe's albedo (0: no sheen) */
  vec3 n;
  LtcFrame ltc;
};
SheenLobe sheen_at(vec3 n, vec3 v, float roughness, vec3 color);
float ltc_density(vec4 m, vec3 w, float floor_cosine);
#endif

#ifdef SL_ANISOTROPY
/* The anisotropic GGX lobe at the shading point (anisotropy.glsl's anisotropic_lobe): its frame
 * (x along the tangent, y = n x x) and its roughness along each axis, made once per shading point. */
struct AnisotropicLobe {
  vec3 x;
  vec3 y;
  float alpha_x;
  float alpha_y;
};
AnisotropicLobe anisotropic_lobe(vec3 n, vec3 t, float alpha, float stretch);
float anisotropic_roughness(AnisotropicLobe a);
#endif
#ifdef SL_TRANSMISSION
/* The glass at the shading point (transmission.glsl's transmission_at). */
struct TransmissionLobe {
  float share;         /* the glass share of the non-metallic part (what the diffuse base loses) */
  float weight;        /* the glass share of the whole surface: share x (1 - metalness) */
  bool fresnel;        /* the Fresnel splits reflection and transmission (else all transmitted) */
  float eta;           /* its IOR (inside over outside) */
  vec3 tint;           /* each crossing's tint */
  vec3 reflection_tint; /* the dielectric reflection's tint */
  /* the view ray's way through the glass (transmission.glsl's transmission_trace, in the programs
   * passes.RefractionPass draws; else none: `inside` 0) */
  vec3 inside;         /* what crosses into the surface towards the viewer, per unit behind (weight,
                        * tint, the first crossing's Fresnel); 0 where nothing does */
  vec3 inner;          /* the view ray refracted in: its direction inside */
  vec3 exit_p;         /* where it leaves a closed object through a face turned away from the viewer */
  vec3 exit_n;         /* that face's normal, facing the inside (against `inner`) */
  bool exit;           /* it leaves through such a face (else it refracts once: an open surface) */
  vec3 behind;         /* where it then meets the opaque scene (or leaves the view) */
};
TransmissionLobe transmission_at(MaterialData m, float metalness);
#endif
#ifdef SL_CLOSURE_BSDFS
/* The closure nodes drawn beside the Principled BSDF's lobes, at the view (closures.glsl's
 * closure_bsdfs_at), made once per shading point. */
struct ClosureBsdfLobes {
#  ifdef SL_DIFFUSE_ROUGHNESS
  bool oren_nayar;     /* the Diffuse BSDF's Roughness above 0 (else Lambert) */
  float on_a;          /* Oren-Nayar's A and B */
  float on_b;
  vec3 on_ms;          /* its multiple scattering's colour x E_ms (1 - E(v)) */
  vec3 on_albedo;      /* the diffuse base's directional albedo at the view (rgb) */
  vec3 on_polygon;     /* (mean t, mean n.l, 1) over the light polygon being shaded (closures.glsl's
                        * oren_nayar_polygon), z 0: at each light's own direction */
#  endif
#  ifdef SL_VELVET
  vec3 velvet;         /* Sheen BSDF (Ashikhmin) colour */
  float velvet_inv_sigma2;
#  endif
#  ifdef SL_TOON
  vec3 toon_diffuse;   /* Toon BSDF colours, Size and Smooth in radians */
  vec2 toon_diffuse_shape;
  vec3 toon_glossy;
  vec2 toon_glossy_shape;
#  endif
};
ClosureBsdfLobes closure_bsdfs_at(vec3 n, vec3 v, vec3 base_color, MaterialData m);
#endif

#ifdef SL_MULTISCATTER
/* The specular lobe's multiple-scattering compensation (multiscatter.glsl): it depends on the view
 * only, so make_surface computes it once per shading point, not once per light. */
vec3 ms_compensation_at(float NoV, float roughness, vec3 f0);
#endif

struct Surface {
  vec3 p;             /* world position */
  vec3 n;             /* unit shading normal, flipped towards the viewer on back faces */
  vec3 v;             /* unit direction towards the viewer */
  float NoV;          /* n.v floored at MIN_COS (grazing and silhouette fragments) */
  vec3 base_color;
  vec3 diffuse_color;
  vec3 specular_color;
  vec3 ambient_color;
  float roughness;    /* perceptual roughness r, floored at MIN_PERCEPTUAL_ROUGHNESS */
  float alpha;        /* GGX alpha = r^2 (Burley 2012) */
  float metalness;
  float shininess;
  float f0_dielectric;
  vec3 f0;            /* mix(F0 dielectric, base colour, metalness) */
  float f90;          /* Schlick's grazing reflectance: saturate(50 F0) unless the material sets it */
  float fresnel_p;    /* eq. 1.13's p (1/5 gives eq. 1.11) */
  float eta;          /* dielectric IOR from F0: (1 + sqrt F0) / (1 - sqrt F0) */
  bool has_complex_ior;
  vec3 ior_n;         /* conductor's complex IOR n + ik per channel (exact Fresnel) */
  vec3 ior_k;
#ifdef SL_LAYERS
  PrincipledLayers layers;
#endif
#ifdef SL_MULTISCATTER
  vec3 ms_compensation;
#endif
#ifdef SL_LTC
  LtcFrame ltc;
#endif
#ifdef SL_GRAPH_BENT_NORMAL
  vec3 smooth_n;      /* the interpolated normal before a node graph bent it (Cycles' sd->N) */
#endif
#ifdef SL_SPECULAR_TINT
  vec3 specular_tint; /* the Principled BSDF's Specular Tint */
  float conductor;    /* the Physical Conductors' share of the metal lobe: its Fresnel exact of ior_n, ior_k */
#endif
#ifdef SL_COAT
  CoatLayer coat;
#endif
#ifdef SL_SHEEN
  SheenLobe sheen;
#endif
#if defined(SL_COAT) || defined(SL_SHEEN)
  vec3 below;         /* what the sheen and the coat above leave the base at the view (rgb) */
#endif
#ifdef SL_THIN_FILM
  vec4 thin_film;     /* the Thin Film: thickness (nm; 0.1 or less: none), IOR, 0, 0 (its rule: the
                       * program's define, thin_film.glsl) */
  vec3 film_metal_n;  /* the metal's IOR n + ik under it (thin_film_metal_ior) and its F82 value */
  vec3 film_metal_k;
  vec3 film_metal_g;
#endif
#ifdef SL_ANISOTROPY
  AnisotropicLobe aniso; /* the specular lobes' anisotropic GGX (roughness, alpha: its isotropic stand-in's) */
#endif
#ifdef SL_TRANSLUCENT
  vec3 translucent;   /* a node graph's Translucent BSDFs' colour (glsl/subsurface.glsl) */
#endif
#ifdef SL_SUBSURFACE
  float subsurface;        /* Subsurface Weight: the share of the diffuse base that scatters below */
  vec3 subsurface_radius;  /* its mean free path per channel (m) */
  float curvature;         /* the surface's curvature (1/m) where the mesh program measures it, else 0 */
  vec3 subsurface_walk;    /* the random walk's light over its Lambert base at the view (subsurface.glsl) */
  vec3 subsurface_drift;   /* and its mean drift away from the viewer, in units of the mean free path */
  vec3 subsurface_gain;    /* and its gain on a convex surface per unit profile width over radius */
#endif
#ifdef SL_TRANSMISSION
  TransmissionLobe transmission;
#endif
#ifdef SL_CLOSURE_BSDFS
  ClosureBsdfLobes bsdfs;
#endif
#ifdef SL_GLOSSY
  vec4 glossy;        /* MaterialData's glossy: the Glossy BSDFs' shares (closures.glsl) */
#endif
};
#ifdef SL_SUBSURFACE
vec3 subsurface_walk_at(vec3 n, vec3 v, vec3 albedo, vec4 walk, float roughness, out vec3 drift,
                        out vec3 gain); /* subsurface.glsl */
#endif
#ifdef SL_THIN_FILM
#  ifdef SL_LAYERS
void thin_film_at(inout Surface s, vec4 film);
#  endif
#endif
#ifdef SL_DIFFUSE_ROUGHNESS
vec3 oren_nayar_diffuse(Surface s, vec3 rho, float NoL, float LoV); /* closures.glsl */
#  if defined(SL_ENV_UNIFORM) || defined(SL_ENV_MAP)
vec3 oren_nayar_environment(Surface s, vec3 irradiance);
#  endif
#endif
#ifdef SL_GLOSSY
vec3 glossy_metal(Surface s, vec3 F, vec3 M, float albedo); /* closures.glsl */
float glossy_lobe(Surface s, float DV, float NoL, float NoH, float NxH2, float LoH);
float glossy_albedo(Surface s, float E_ggx, float NoV, float roughness);
#endif

/* Unit half vector of eq. 1.6; l + v = 0 only when the light is exactly behind the viewer's
 * line of sight, where any unit vector serves: fall back to n. */
vec3 half_vector(vec3 l, vec3 v, vec3 n)
{
  vec3 s = l + v;
  float len2 = dot(s, s);
  return len2 > 1e-12 ? s * inversesqrt(len2) : n;
}

/* The shading point from a position, a unit normal facing the viewer, the view direction and
 * the material's uniform block; shared by the mesh program and the term test harness. */
Surface make_surface(vec3 p, vec3 n, vec3 v, MaterialData m)
{
  Surface s;
  s.p = p;
  s.n = n;
  s.v = v;
  s.NoV = max(dot(n, v), MIN_COS);
  s.base_color = m.base_color.rgb;
  s.diffuse_color = m.diffuse_color.rgb;
  s.specular_color = m.specular_color.rgb;
  s.ambient_color = m.ambient_color.rgb;
  s.roughness = max(m.params.x, MIN_PERCEPTUAL_ROUGHNESS);
  s.alpha = s.roughness * s.roughness;
#ifdef SL_ANISOTROPY
  s.aniso = anisotropic_lobe(n, m.anisotropy.xyz, s.alpha, m.anisotropy.w);
  /* what stands in for it isotropically (the layers' estimate and compensation, area lights' LTC,
   * the world's split sum) takes its (alpha_x alpha_y)^(1/4), as Cycles' compensation does: the
   * roughness itself, unless an axis was clamped at 1 */
  s.roughness = max(anisotropic_roughness(s.aniso), MIN_PERCEPTUAL_ROUGHNESS);
  s.alpha = s.roughness * s.roughness;
#endif
  s.metalness = m.params.y;
  s.shininess = m.params.z;
  s.f0_dielectric = m.params.w;
  s.f0 = mix(vec3(s.f0_dielectric), s.base_color, s.metalness);
  s.f90 = m.fresnel.x >= 0.0 ? m.fresnel.x : saturate(50.0 * dot(s.f0, vec3(1.0 / 3.0)));
  s.fresnel_p = m.fresnel.y;
  float sqrt_f0 = sqrt(min(s.f0_dielectric, 0.99));
  s.eta = (1.0 + sqrt_f0) / (1.0 - sqrt_f0);
  s.has_complex_ior = m.fresnel.z > 0.5;
  s.ior_n = m.ior_n.rgb;
  s.ior_k = m.ior_k.rgb;
#ifdef SL_TRANSMISSION
  s.transmission = transmission_at(m, s.metalness);
#endif
#ifdef SL_SPECULAR_TINT
  s.conductor = saturate(m.ior_n.w);
  s.specular_tint = max(m.specular_tint.rgb, 0.0);
  vec3 tint = s.specular_tint;
#else
  const vec3 tint = vec3(1.0);
#endif
#ifdef SL_LAYERS
  s.layers = principled_layers_at(s.NoV, s.roughness, s.base_color, s.eta, tint);
#  ifdef SL_THIN_FILM
  thin_film_at(s, m.thin_film);
#  endif
#  ifdef SL_GRAPH
  /* the share of the diffuse base beside the specular layer, not under it (a node graph's Specular
   * BSDF, EEVEE's: node_closure_bsdfs.glsl) */
  s.layers.layer *= 1.0 - saturate(m.closure_bsdfs.w);
#  endif
#endif
  /* the Principled BSDF's upper layers, each attenuating what lies below it at the view (Cycles'
   * svm_node_closure_bsdf: the sheen over the coat over the rest) */
#if defined(SL_COAT) || defined(SL_SHEEN)
  s.below = vec3(1.0);
#endif
  vec3 sheen_n = n;
#ifdef SL_COAT
  s.coat = coat_at(n, v, m.coat, m.coat_normal.xyz);
  s.below *= coat_transmittance(s.coat, max(m.coat_tint.rgb, 0.0));
  /* the sheen lies on the coat: its normal leans to the coat's by the coat's weight (Cycles') */
  vec3 leaning = mix(n, s.coat.n, saturate(s.coat.weight));
  sheen_n = dot(leaning, leaning) > 1e-20 ? normalize(leaning) : n;
#endif
#ifdef SL_SHEEN
  s.sheen = sheen_at(sheen_n, v, m.sheen.w, max(m.sheen.rgb, 0.0));
  /* Cycles' closure_layering_weight of the sheen's albedo (colour x albedo): its largest channel,
   * what the sheen leaves the coat's lobe as well as the base */
  float sheen_max = max(s.sheen.color.r, max(s.sheen.color.g, s.sheen.color.b));
#  ifdef SL_GRAPH
  sheen_max *= saturate(m.closure_bsdfs.x); /* a Sheen BSDF's share is over nothing (node graphs') */
#  endif
  float sheen_left = saturate(1.0 - sheen_max);
  s.below *= sheen_left;
#  ifdef SL_COAT
  s.coat.weight *= sheen_left;
#  endif
#endif
#ifdef SL_MULTISCATTER
  s.ms_compensation = ms_compensation_at(s.NoV, s.roughness, s.f0);
#endif
#ifdef SL_CLOSURE_BSDFS
  s.bsdfs = closure_bsdfs_at(n, v, s.base_color, m);
#endif
#ifdef SL_GLOSSY
  s.glossy = m.glossy;
#endif
#ifdef SL_LTC
  s.ltc = ltc_frame_at(n, v, s.NoV, s.roughness);
#  ifdef SL_GLOSSY
  s.ltc.albedo = glossy_albedo(s, s.ltc.albedo, s.NoV, s.roughness); /* Beckmann's, Ashikhmin-Shirley's */
#  endif
#endif
#ifdef SL_TRANSLUCENT
  s.translucent = max(m.translucent.rgb, 0.0);
#endif
#ifdef SL_SUBSURFACE
  /* the weight within [0, 1] and the paths at least 0, as Cycles' svm_node_closure_bsdf clamps them */
  s.subsurface = saturate(m.subsurface.w);
  s.subsurface_radius = max(m.subsurface.rgb, 0.0);
  s.curvature = 0.0;
  /* its albedo the base colour within [0, 1] (Cycles' clamped_base_color) */
  s.subsurface_walk = subsurface_walk_at(n, v, clamp(s.base_color, 0.0, 1.0), m.subsurface_walk, m.params.x,
                                         s.subsurface_drift, s.subsurface_gain);
#endif
  return s;
}

/* Half floats top out at 65504: a viewport target (RGBA16F) would store Inf above it, so its
 * programs cap radiance there (SL_HALF_TARGET); float targets keep the full range. */
vec3 write_target(vec3 c)
{
#ifdef SL_HALF_TARGET
  return min(c, vec3(65504.0));
#else
  return c;
#endif
}
