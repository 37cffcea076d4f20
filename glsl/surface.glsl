/* The shading point: geometry and material inputs every model reads. */

#ifdef SL_LAYERS
/* What the Principled set (and the LAYERED diffuse) needs at the view direction (principled.glsl):
 * the metal lobe's and the dielectric lobe's multiple-scattering compensation and the dielectric
 * layer's albedo estimate that the diffuse base sits under. They depend on the view only, so
 * make_surface computes them once per shading point, not once per light. */
struct PrincipledLayers {
  vec3 metal_M;
  float dielectric_M;
  float layer;
};
PrincipledLayers principled_layers_at(float NoV, float roughness, vec3 base_color, float eta);
#endif

#ifdef SL_LTC
/* What area lights' linearly transformed cosines need at the view direction (ltc.glsl): the
 * shading frame (x the tangent towards v, y = n x x), the LTC's M^-1 entries and the lobe's
 * albedo. They depend on the view only, so make_surface computes them once per shading point,
 * not once per area light. */
struct LtcFrame {
  vec3 x_axis;
  vec3 y_axis;
  vec4 m;
  float albedo;
};
LtcFrame ltc_frame_at(vec3 n, vec3 v, float NoV, float roughness);
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
};

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
#ifdef SL_LAYERS
  s.layers = principled_layers_at(s.NoV, s.roughness, s.base_color, s.eta);
#endif
#ifdef SL_MULTISCATTER
  s.ms_compensation = ms_compensation_at(s.NoV, s.roughness, s.f0);
#endif
#ifdef SL_LTC
  s.ltc = ltc_frame_at(n, v, s.NoV, s.roughness);
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
