/* One light's reflected radiance from its irradiance E and direction l (light_irradiance, after
 * the shadow test, whose factor is `visibility`): the body of mesh.frag.glsl's light loop, shared
 * with the term harness (tests/test_stability.py). Twin: shading.shade_light. Needs the model
 * file's shade_direct (and, for the physically based model, pbr_specular_tint). */

#ifdef SL_AREA_LTC
/* An area light (the physically based model): the diffuse lobe from the polygon's irradiance cut
 * by the horizon (the sphere of the same vector form factor, ltc.glsl), the specular lobe from the
 * linearly transformed cosine's integral over the polygon (ltc_lobe_integral), with the Fresnel
 * term at the half vector of the light's irradiance-weighted direction l. Behind the light, or
 * seen from its far field, it is the point emitter E_Area shades. */
vec3 shade_area_light(Surface s, LightData light, vec3 l, vec3 E, float visibility, vec4 factors)
{
  vec3 to_centre = light.position_kind.xyz - s.p;
  if (area_far_field(light, dot(to_centre, to_centre))) {
    return shade_direct(s, l, E, factors);
  }
  /* the radiance as it arrives: the emitter's I / A, windowed and shadowed as E is */
  vec3 L = light.intensity_blend.rgb * (visibility * light_window(light, s.p) /
                                        max(area_light_area(light), 1e-12));
  float L_max = max(L.r, max(L.g, L.b));
  float E_max = max(E.r, max(E.g, E.b));
  if (L_max <= 0.0 || E_max <= 0.0) {
    return vec3(0.0); /* behind the emitting side, shadowed, or out of reach */
  }
  /* E = L pi |F| along l: the form factor's length from E, its height from n.l */
  float form_factor = E_max / (PI * L_max);
  float NoL = dot(s.n, l);
  vec3 c = vec3(0.0);
  if (NoL > 0.0) {
    float clipped = ltc_horizon_clip(form_factor, 1.0 + NoL);
    c = shade_direct(s, l, L * (PI * clipped / NoL), factors * vec4(1.0, 0.0, 1.0, 1.0));
  }
  float density;
  float form_factor_lobe = ltc_polygon(s, light, l, density);
  if (form_factor_lobe > 0.0) {
    float LoH = saturate(dot(l, half_vector(l, s.v, s.n)));
    float lobe = ltc_lobe_integral(form_factor_lobe, s.ltc.albedo, pbr_lobe(s, l), density);
    c += pbr_specular_tint(s, LoH) * L * (lobe * factors.y);
  }
  return c;
}
#endif

vec3 shade_light(Surface s, LightData light, vec3 l, vec3 E, float visibility, vec4 factors)
{
#ifdef SL_AREA_LTC
  if (int(light.position_kind.w) == LIGHT_AREA && light.shape.z > 0.0) {
    return shade_area_light(s, light, l, E, visibility, factors);
  }
#endif
#ifdef SL_MODEL_PBR
#  if defined(SL_HAS_POINT) || defined(SL_HAS_SPOT)
  if (light.shape.x > 0.0) {
    /* a sphere light (lights.glsl): the diffuse lobe as its irradiance says; the specular from
     * its nearest point and, widened, from its centre */
    Surface wide = s;
    float wide_weight, point_weight;
    vec3 l_specular = sphere_light_specular(light, s.p, reflect(-s.v, s.n), s.alpha, wide.alpha,
                                            wide_weight, point_weight);
    vec4 specular = factors * vec4(0.0, 1.0, 1.0, 1.0);
    return shade_direct(s, l, E, factors * vec4(1.0, 0.0, 1.0, 1.0)) +
           shade_direct(wide, l, E * wide_weight, specular) +
           shade_direct(s, l_specular, E * point_weight, specular);
  }
#  endif
#endif
  return shade_direct(s, l, E, factors);
}
