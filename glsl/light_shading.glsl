/* One light's reflected radiance from its irradiance E and direction l (light_irradiance, after
 * the shadow test): the body of mesh.frag.glsl's light loop, shared with the term harness
 * (tests/test_stability.py). Twin: shading.shade_light. Needs the model file's shade_direct. */

vec3 shade_light(Surface s, LightData light, vec3 l, vec3 E, vec4 factors)
{
#ifdef SL_MODEL_PBR
#  if defined(SL_HAS_POINT) || defined(SL_HAS_SPOT) || defined(SL_HAS_AREA)
  if (light.shape.x > 0.0 || light.shape.z > 0.0) {
    /* a light with a size (lights.glsl): the diffuse lobe as its irradiance says; the specular
     * from its nearest point and, widened, from its centre */
    Surface wide = s;
    float wide_weight, point_weight;
    vec3 l_specular = light_specular_direction(light, s.p, reflect(-s.v, s.n), s.alpha, wide.alpha,
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
