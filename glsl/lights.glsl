/* Punctual lights in Blender's units (SPEC section 4). Each function returns the irradiance E
 * (W/m^2, rgb) that the light delivers to a surface facing it, and the unit direction l from the
 * shaded point towards the light. Radiance is then f(l, v) * E * (n.l)+ summed over lights. */

#define LIGHT_POINT 0
#define LIGHT_SPOT 1
#define LIGHT_SUN 2
#define LIGHT_AREA 3

/* Squared distance floor: a light closer than 1 cm is treated as 1 cm away, so a light at
 * distance 0 gives a large finite irradiance instead of Inf (Filament does the same). */
#define MIN_DIST2 1e-4

#if defined(SL_HAS_POINT) || defined(SL_HAS_SPOT) || defined(SL_HAS_AREA)
/* Point light: radiant intensity I = P / (4 pi) W/sr (packed on the CPU), inverse-square falloff.
 * Spot and area lights build on it. With a radius r, Cycles' light is a sphere of radiance
 * I / (pi r^2): seen whole it delivers what the point does, I / d^2; with soft falloff (Blender's
 * default) it is instead a disc of that radiance facing the point, I / (d^2 + r^2) on its axis. */
vec3 E_Point(LightData light, vec3 p, out vec3 l)
{
  vec3 d = light.position_kind.xyz - p;
  float d2 = dot(d, d);
  /* the direction from the true distance (a light exactly at p has none: l = 0, no light),
   * the falloff from the floored one */
  l = d * inversesqrt(max(d2, 1e-30));
  float r = light.shape.x;
  return light.intensity_blend.rgb / max(d2 + light.shape.y * r * r, MIN_DIST2);
}

/* The specular lobe of a sphere light of radius r (a point or spot light with a size), seen
 * from p at angular radius theta = r / (2 d') in half-vector space (d' = d, or sqrt(d^2 + r^2) for
 * soft falloff's disc). Relative to the lobe's width alpha, k = theta / alpha:
 * - a narrow lobe (k >> 1) reflects the light's disc: Karis 2013's representative point, the
 *   light direction moved to the point of the sphere nearest the reflected ray r_dir, which shifts
 *   the GGX profile f(u) outward by theta; its energy grows by 1 + (pi / 2) k + k^2 (the shifted
 *   profile's integral over the plane, from the integral of f: pi alpha^2, and along a radius:
 *   pi alpha / 4), so it is divided by that (Karis' (alpha / (alpha + theta))^2 is nearly this);
 * - a wide lobe (k << 1) is widened by the disc: the GGX distribution with alpha'^2 = alpha^2 +
 *   theta^2 (lobe widths convolved add in quadrature), from the light's centre, normalised as is.
 * The two are mixed with the representative point's weight k^2 / (1 + k^2). Against Cycles (a
 * white GGX metal sphere, unshadowed, mean |error| / mean): mirror 0.05 under a 0.1 / 0.5 m light
 * 8 % / 7 % (a point: 93 % / 98 %), roughness 0.2: 8 % / 28 % (11 % / 98 %), 0.5: 0.3 % / 4 %
 * (0.3 % / 7 %). Returns the representative direction; alpha_wide and the weights by `out`. */
vec3 sphere_light_specular(LightData light, vec3 p, vec3 r_dir, float alpha, out float alpha_wide,
                           out float wide_weight, out float point_weight)
{
  vec3 to_light = light.position_kind.xyz - p;
  float d2 = dot(to_light, to_light);
  float radius = light.shape.x;
  float theta = radius * 0.5 * inversesqrt(max(d2 + light.shape.y * radius * radius, 1e-8));
  float k2 = theta * theta / max(alpha * alpha, 1e-12);
  float k = sqrt(k2);
  alpha_wide = sqrt(alpha * alpha + theta * theta);
  wide_weight = 1.0 / (1.0 + k2);
  point_weight = (1.0 - wide_weight) / (1.0 + 1.5707963 * k + k2);
  vec3 centre_to_ray = dot(to_light, r_dir) * r_dir - to_light;
  float gap = length(centre_to_ray);
  vec3 closest = to_light + centre_to_ray * (gap > radius ? radius / gap : 1.0);
  float len2 = dot(closest, closest);
  return len2 > 1e-30 ? closest * inversesqrt(len2) : r_dir;
}
#endif

#ifdef SL_HAS_SPOT
/* Spot light: a point light (same I = P / 4 pi: the cone does not concentrate it) times Cycles'
 * cone attenuation, smoothstep((cos(theta) - cos(size / 2)) * smooth) with
 * smooth = 1 / ((1 - cos(size / 2)) * blend) packed on the CPU. */
vec3 E_Spot(LightData light, vec3 p, out vec3 l)
{
  vec3 E = E_Point(light, p, l);
  float cos_theta = dot(-l, light.direction_cone.xyz);
  float t = saturate((cos_theta - light.direction_cone.w) * light.intensity_blend.w);
  return E * (t * t * (3.0 - 2.0 * t));
}
#endif

#ifdef SL_HAS_SUN
/* Sun light: constant irradiance E = strength (W/m^2), arriving against the light's direction. */
vec3 E_Sun(LightData light, out vec3 l)
{
  l = -light.direction_cone.xyz;
  return light.intensity_blend.rgb;
}
#endif

#ifdef SL_HAS_AREA
/* Area light, approximated as a one-sided Lambertian point emitter at its centre: intensity
 * I(theta) = (P / pi) cos(theta) towards the light's -Z, zero behind it. Exact in the far field;
 * ignores the light's extent (no soft highlights, no horizon clipping). */
vec3 E_Area(LightData light, vec3 p, out vec3 l)
{
  vec3 E = E_Point(light, p, l);
  return E * max(dot(-l, light.direction_cone.xyz), 0.0);
}
#endif

/* Dispatch on the light kind; only the kinds the scene has are compiled in. */
vec3 light_irradiance(LightData light, vec3 p, out vec3 l)
{
  int kind = int(light.position_kind.w);
  l = vec3(0.0, 0.0, 1.0);
#ifdef SL_HAS_POINT
  if (kind == LIGHT_POINT) {
    return E_Point(light, p, l);
  }
#endif
#ifdef SL_HAS_SPOT
  if (kind == LIGHT_SPOT) {
    return E_Spot(light, p, l);
  }
#endif
#ifdef SL_HAS_SUN
  if (kind == LIGHT_SUN) {
    return E_Sun(light, l);
  }
#endif
#ifdef SL_HAS_AREA
  if (kind == LIGHT_AREA) {
    return E_Area(light, p, l);
  }
#endif
  return vec3(0.0);
}
