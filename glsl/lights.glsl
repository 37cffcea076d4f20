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

#if defined(SL_HAS_POINT) || defined(SL_HAS_SPOT)
/* Point light: radiant intensity I = P / (4 pi) W/sr (packed on the CPU), inverse-square falloff.
 * Spot lights build on it. With a radius r, Cycles' light is a sphere of radiance
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
 * (0.3 % / 7 %). sphere_light_specular returns the representative direction; alpha_wide and the
 * weights by `out` (size_lobe_weights). */
void size_lobe_weights(float theta, float alpha, out float alpha_wide, out float wide_weight,
                       out float point_weight)
{
  /* r / (2 d) grows without bound as p nears the light (d -> 0 inside a sphere);
   * no light spans more than the hemisphere, pi / 4 in half-vector space. Unbounded, alpha_wide
   * reached 5e7 and the visibility terms' NoV^2 (1 - a^2) + a^2 cancelled to 0 at n.v = 1: Inf
   * (tests/test_stability.py's sphere lights at 1e-6 m). */
  theta = min(theta, 0.78539816);
  float k2 = theta * theta / max(alpha * alpha, 1e-12);
  alpha_wide = sqrt(alpha * alpha + theta * theta);
  wide_weight = 1.0 / (1.0 + k2);
  point_weight = (1.0 - wide_weight) / (1.0 + 1.5707963 * sqrt(k2) + k2);
}

vec3 sphere_light_specular(LightData light, vec3 p, vec3 r_dir, float alpha, out float alpha_wide,
                           out float wide_weight, out float point_weight)
{
  vec3 to_light = light.position_kind.xyz - p;
  float d2 = dot(to_light, to_light);
  float radius = light.shape.x;
  float theta = radius * 0.5 * inversesqrt(max(d2 + light.shape.y * radius * radius, 1e-8));
  size_lobe_weights(theta, alpha, alpha_wide, wide_weight, point_weight);
  vec3 centre_to_ray = dot(to_light, r_dir) * r_dir - to_light;
  float gap = length(centre_to_ray);
  /* a ray that meets the sphere: the point is on the ray itself, taken as such -- as to_light +
   * centre_to_ray it cancelled to the light's centre in float32 (n.v = 1e-4, light 1e-6 m away) */
  vec3 closest = gap > radius ? to_light + centre_to_ray * (radius / gap) : dot(to_light, r_dir) * r_dir;
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
/* Area light: a one-sided Lambertian emitter of radiance L = I / A (I = P / pi along its normal,
 * packed on the CPU; A its area) towards its -Z. Its irradiance is exact for the polygon (a disk
 * or ellipse: a 16-gon of the same area): the vector form factor (Lambert 1760; Arvo 1995)
 * V = 1/2 sum_i theta_i g_i over the edges seen from p (theta_i the angle an edge subtends, g_i
 * the unit normal of the plane through p and the edge), E . (n.l) = L n.V with l = V / |V| and
 * E = L |V|: exact for every diffuse term's n.l, the polygon not clipped by p's horizon. */
#define AREA_ELLIPSE_SIDES 16
/* Beyond this many equal-area radii R the polygon is shaded as a point emitter of intensity I cos
 * (the emitter's cosine): the form factor's edge terms (~R/d each) cancel to |V| ~ (R/d)^2, which
 * costs about 2 eps d / R of relative precision in float32 (a 0.1 m light at 1 km: 1e-3, at 1e6 m:
 * all of it), while the point's own error is (R/d)^2: the two meet at 2.5e-5 at d = 200 R. */
#define AREA_FAR_FIELD 200.0

/* Corner i of the polygon relative to the light's centre. */
vec3 area_offset(LightData light, int i, vec3 y_axis)
{
  vec2 half_size = light.shape.zw;
  vec2 uv;
  if (light.area.w > 0.5) {
    /* a 16-gon of the ellipse's area: radius scaled by sqrt(2 pi / (n sin(2 pi / n))) */
    float phi = 6.2831853 * float(i) / float(AREA_ELLIPSE_SIDES);
    uv = 1.0130016 * vec2(cos(phi), sin(phi));
  }
  else {
    uv = vec2(i == 0 || i == 3 ? -1.0 : 1.0, i < 2 ? -1.0 : 1.0);
  }
  return light.area.xyz * (uv.x * half_size.x) + y_axis * (uv.y * half_size.y);
}

/* V = 1/2 sum_i theta_i g_i of the light's polygon seen from the point at -to_centre from its
 * centre, each corner mapped by `map` first (the identity for the irradiance; an LTC's M^-1,
 * glsl/ltc.glsl), oriented towards the polygon. */
vec3 polygon_form_factor(LightData light, mat3 map, vec3 to_centre)
{
  vec3 y_axis = cross(-light.direction_cone.xyz, light.area.xyz);
  int n = light.area.w > 0.5 ? AREA_ELLIPSE_SIDES : 4;
  vec3 t = map * to_centre;
  vec3 V = vec3(0.0);
  vec3 oa = map * area_offset(light, n - 1, y_axis);
  for (int i = 0; i < AREA_ELLIPSE_SIDES; i++) {
    if (i >= n) {
      break;
    }
    vec3 ob = map * area_offset(light, i, y_axis);
    /* corners a = t + oa, b = t + ob, a x b = t x (ob - oa) + oa x ob: taken from unit vectors
     * towards the corners it cancelled, since they nearly coincide seen from afar */
    vec3 c = cross(t, ob - oa) + cross(oa, ob);
    float s = length(c);
    if (s > 0.0) {
      /* theta g, with theta from atan2 (acos loses precision), to float precision */
      V += c * (atan2_accurate(s, dot(t + oa, t + ob)) / s);
    }
    oa = ob;
  }
  V *= 0.5;
  return dot(V, t) < 0.0 ? -V : V; /* the corners' winding as seen from the point */
}

/* The light's area (a disk or ellipse: of the ellipse, not of its 16-gon, which has the same). */
float area_light_area(LightData light)
{
  return 4.0 * light.shape.z * light.shape.w * (light.area.w > 0.5 ? 0.78539816 : 1.0);
}

/* Seen from farther than AREA_FAR_FIELD equal-area radii, a light is shaded as a point. */
bool area_far_field(LightData light, float d2)
{
  float area = area_light_area(light);
  return area > 0.0 && area * (AREA_FAR_FIELD * AREA_FAR_FIELD) < PI * d2;
}

vec3 E_Area(LightData light, vec3 p, out vec3 l)
{
  vec3 centre = light.position_kind.xyz;
  vec3 to_centre = centre - p;
  float d2 = dot(to_centre, to_centre);
  /* as a point light's: no direction (l = 0, no light) for p exactly at the centre, where
   * normalize() gave NaN and NaN * 0 reached the shaded colour */
  l = to_centre * inversesqrt(max(d2, 1e-30));
  if (dot(-to_centre, light.direction_cone.xyz) <= 0.0) {
    return vec3(0.0); /* behind the emitting side */
  }
  if (area_far_field(light, d2)) {
    return light.intensity_blend.rgb * (dot(-l, light.direction_cone.xyz) / max(d2, MIN_DIST2));
  }
  vec3 V = polygon_form_factor(light, mat3(1.0), to_centre);
  float len = length(V);
  if (len <= 0.0) {
    return vec3(0.0);
  }
  l = V / len;
  return light.intensity_blend.rgb / max(area_light_area(light), 1e-12) * len;
}

#endif

/* Dispatch on the light kind; only the kinds the scene has are compiled in. */
/* A light's reach r (Blender's Custom Distance, else where I / d^2 falls to the scene's Light
 * Threshold t: addon/light_tiles.py) as a window on its irradiance, (1 - (d / r)^4)^2 clamped
 * (EEVEE's and Unreal's): 1 near the light, exactly 0 from r on, where light culling leaves the
 * light out. Below a threshold-derived r it removes at most t of irradiance anywhere. */
float light_window(LightData light, vec3 p)
{
  vec3 d = light.position_kind.xyz - p;
  float x = dot(d, d) * light.influence.x;
  float w = saturate(1.0 - x * x);
  return w * w;
}

vec3 light_irradiance(LightData light, vec3 p, out vec3 l)
{
  int kind = int(light.position_kind.w);
  l = vec3(0.0, 0.0, 1.0);
#ifdef SL_HAS_POINT
  if (kind == LIGHT_POINT) {
    return E_Point(light, p, l) * light_window(light, p);
  }
#endif
#ifdef SL_HAS_SPOT
  if (kind == LIGHT_SPOT) {
    return E_Spot(light, p, l) * light_window(light, p);
  }
#endif
#ifdef SL_HAS_SUN
  if (kind == LIGHT_SUN) {
    return E_Sun(light, l);
  }
#endif
#ifdef SL_HAS_AREA
  if (kind == LIGHT_AREA) {
    return E_Area(light, p, l) * light_window(light, p);
  }
#endif
  return vec3(0.0);
}
