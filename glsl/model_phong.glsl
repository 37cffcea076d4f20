/* Phong, eqs. 1.1-1.4: ambient + diffuse (n.l)+ + specular ((r.v)+)^shininess, clamped to
 * [0, 1]. Light colours as in model_blinn_phong.glsl; the specular term is gated by n.l > 0. */

vec3 shade_direct(Surface s, vec3 l, vec3 E, vec4 factors)
{
  float NoL = dot(s.n, l);
  if (NoL <= 0.0) {
    return vec3(0.0);
  }
  vec3 c_light = E * INV_PI;
  vec3 diffuse = s.diffuse_color * c_light * factors.x * NoL;                             /* eq. 1.1 */
  vec3 specular = s.specular_color * c_light * factors.y * S_Phong(s.n, l, s.v, s.shininess); /* eq. 1.2 */
  return diffuse + specular;
}

/* Eq. 1.4. */
vec3 shade_ambient(Surface s, vec3 x)
{
#ifdef SL_AMBIENT_WORLD
  /* Ambient: World -- the diffuse light the world gives: irradiance / pi (glsl/ibl.glsl) */
  return s.ambient_color * env_irradiance(env_bent_normal(s.n)) * (env_occlusion_diffuse() * INV_PI);
#else
  return s.ambient_color * x;
#endif
}

/* The world lights the empirical models only through their ambient term. */
vec3 shade_environment(Surface s, vec2 weights)
{
  return vec3(0.0);
}

vec3 shade_finish(vec3 c)
{
  return clamp(c, 0.0, 1.0);
}
