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
 * Spot and area lights build on it. */
vec3 E_Point(LightData light, vec3 p, out vec3 l)
{
  vec3 d = light.position_kind.xyz - p;
  float d2 = dot(d, d);
  /* the direction from the true distance (a light exactly at p has none: l = 0, no light),
   * the falloff from the floored one */
  l = d * inversesqrt(max(d2, 1e-30));
  return light.intensity_blend.rgb / max(d2, MIN_DIST2);
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
