/* Blinn-Phong, eq. 1.7: c = p_ambi + sum_lights [p_diff (n.l)+ + p_spec ((n.h)+)^shininess],
 * in an LDR pipeline clamped to [0, 1] like the seed's renderer. The light colours c_light are
 * the seed's c_PL (section 1.2.7): the radiance of a white Lambertian surface facing the light,
 * E / pi, times Blender's per-light diffuse and specular factors. The specular term is gated by
 * n.l > 0: (n.h)+ > 0 does not imply the light is above the surface (SPEC). */

vec3 shade_direct(Surface s, vec3 l, vec3 E, vec4 factors)
{
  float NoL = dot(s.n, l);
  if (NoL <= 0.0) {
    return vec3(0.0);
  }
  vec3 c_light = E * INV_PI;
  vec3 h = half_vector(l, s.v, s.n);
  vec3 diffuse = s.diffuse_color * c_light * factors.x * NoL;
#ifdef SL_BLINN_PHONG_NORMALIZED
  /* energy-normalised option: a BRDF lobe, so it takes E and n.l like the diffuse term */
  vec3 specular = s.specular_color * E * factors.y * S_BlinnPhongNormalized(dot(s.n, h), s.shininess) * NoL;
#else
  vec3 specular = s.specular_color * c_light * factors.y * S_BlinnPhong(dot(s.n, h), s.shininess);
#endif
  return diffuse + specular;
}

/* Eq. 1.4: p_ambi = c_surface_ambi * x. */
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
