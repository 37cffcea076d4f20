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

/* The sphere light's angular radius in half-vector space seen from p, r / (2 d'). */
float sphere_light_theta(LightData light, vec3 p)
{
  vec3 to_light = light.position_kind.xyz - p;
  float radius = light.shape.x;
  return radius * 0.5 * inversesqrt(max(dot(to_light, to_light) + light.shape.y * radius * radius, 1e-8));
}

/* Between these k = theta / alpha the physically based model turns from the representative point
 * to the linearly transformed cosines over the light's disc (light_shading.glsl's shade_light):
 * against Cycles the representative point errs about 25 k^2 % (0.3 % at k = 0.08, 4 % at 0.4). */
#define SPHERE_LTC_FROM 0.1
#define SPHERE_LTC_FULL 0.2
/* Beyond this k a sphere light's disc is a 16-gon, below it an octagon: a narrow lobe reflects
 * the disc's outline (an octagon's measured 4.5 % from Cycles under a 0.5 m light on roughness
 * 0.05, the 16-gon's 1.4 %), a wide one does not (alike within 0.3 %), at half the cost. */
#define SPHERE_FINE_K 2.0
#define SPHERE_COARSE_SIDES 8

vec3 sphere_light_specular(LightData light, vec3 p, vec3 r_dir, float alpha, out float alpha_wide,
                           out float wide_weight, out float point_weight)
{
  vec3 to_light = light.position_kind.xyz - p;
  float radius = light.shape.x;
  size_lobe_weights(sphere_light_theta(light, p), alpha, alpha_wide, wide_weight, point_weight);
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

#if defined(SL_HAS_AREA) || defined(SL_LTC)
/* A light's polygon seen from a point: the offset from the point to its centre, its half axes and
 * its sides (4: a rectangle; AREA_ELLIPSE_SIDES: a disk or ellipse, as the polygon of its area).
 * Area lights (area_polygon) and, in the physically based model, sphere lights (sphere_polygon:
 * the disc of the same solid angle) are integrated over one. */
#define AREA_ELLIPSE_SIDES 16
/* Beyond this many equal-area radii R the polygon is shaded as a point emitter of intensity I cos
 * (the emitter's cosine): the form factor's edge terms (~R/d each) cancel to |V| ~ (R/d)^2, which
 * costs about 2 eps d / R of relative precision in float32 (a 0.1 m light at 1 km: 1e-3, at 1e6 m:
 * all of it), while the point's own error is (R/d)^2: the two meet at 2.5e-5 at d = 200 R. */
#define AREA_FAR_FIELD 200.0
struct LightPolygon {
  vec3 to_centre;
  vec3 x_half;
  vec3 y_half;
  int sides;
};

/* Corner i of the polygon relative to its centre. */
vec3 polygon_offset(LightPolygon poly, int i)
{
  vec2 uv = vec2(i == 0 || i == 3 ? -1.0 : 1.0, i < 2 ? -1.0 : 1.0);
#if defined(SL_AREA_ELLIPSE) || defined(SL_SPHERE_LIGHTS) /* n-gons compiled only where some light
                                                           * is one: both sides of the test run */
  if (poly.sides > 4) {
    /* an n-gon of the ellipse's area (16 sides; 8 for a sphere light under a wide lobe): radius
     * scaled by sqrt(2 pi / (n sin(2 pi / n))) */
    float phi = 6.2831853 * float(i) / float(poly.sides);
    uv = (poly.sides == AREA_ELLIPSE_SIDES ? 1.0130016 : 1.0539074) * vec2(cos(phi), sin(phi));
  }
#endif
  return poly.x_half * uv.x + poly.y_half * uv.y;
}

/* V = 1/2 sum_i theta_i g_i of the polygon seen from its point, each corner mapped by `map`
 * first (the identity for the irradiance; an LTC's M^-1, glsl/ltc.glsl), oriented towards the
 * polygon. */
vec3 polygon_form_factor(LightPolygon poly, mat3 map)
{
  int n = poly.sides;
  /* V depends on the polygon's shape seen from the point, not on its scale: taken near unit
   * scale, so that the cross products of a micrometre light's corners (1e-20 and below, their
   * squares beneath float32's normal range) do not flush to zero -- mapped by a grazing mirror
   * lobe's M^-1 they did, and the integral came out 3 % off. The scale is a power of two, exact:
   * any other rounds the corners, which moves an edge-on light off its plane. */
  float extent = max(max(length(poly.to_centre), length(poly.x_half)), length(poly.y_half));
  float scale = exp2(-floor(log2(max(extent, 1e-30))));
  poly.to_centre *= scale;
  poly.x_half *= scale;
  poly.y_half *= scale;
  vec3 t = map * poly.to_centre;
  vec3 V = vec3(0.0);
  vec3 oa = map * polygon_offset(poly, n - 1);
  int i = 0;
  do { /* tested at the end (glsl/README.md): a polygon has 4 sides or more */
    vec3 ob = map * polygon_offset(poly, i);
    /* corners a = t + oa, b = t + ob, a x b = t x (ob - oa) + oa x ob: taken from unit vectors
     * towards the corners it cancelled, since they nearly coincide seen from afar */
    vec3 c = cross(t, ob - oa) + cross(oa, ob);
    float s = length(c);
    if (s > 0.0) {
      /* theta g, with theta from atan2 (acos loses precision), to float precision */
      V += c * (atan2_accurate(s, dot(t + oa, t + ob)) / s);
    }
    oa = ob;
  } while (++i < n && i < AREA_ELLIPSE_SIDES);
  V *= 0.5;
  return dot(V, t) < 0.0 ? -V : V; /* the corners' winding as seen from the point */
}
#endif

#ifdef SL_LTC
#  if defined(SL_HAS_POINT) || defined(SL_HAS_SPOT)
/* A sphere light seen from p, as the disc through its centre facing p with the same solid angle
 * (a cone of directions, radiance I / (pi r^2) throughout): with soft falloff Cycles' own disc of
 * radius r; the sphere's cone, of half-angle asin(r / d), is that of a disc of radius
 * r d / sqrt(d^2 - r^2) (inside the sphere the cone is held at 89.4 degrees). Its frame is any
 * one perpendicular to p's direction (the 16-gon's turn about its axis changes nothing that
 * matters: its solid angle is the same). */
LightPolygon sphere_polygon(LightData light, vec3 p, int sides)
{
  LightPolygon poly;
  poly.to_centre = light.position_kind.xyz - p;
  float d2 = dot(poly.to_centre, poly.to_centre);
  float r = light.shape.x;
  float radius = light.shape.y > 0.5 ? r : r * sqrt(d2 / max(max(d2 - r * r, 1e-4 * d2), 1e-30));
  vec3 w = poly.to_centre * inversesqrt(max(d2, 1e-30));
  vec3 other = abs(w.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
  /* p at the centre has no direction to face (w = 0): any frame */
  vec3 x_axis = cross(other, w);
  float x_len2 = dot(x_axis, x_axis);
  x_axis = x_len2 > 1e-30 ? x_axis * inversesqrt(x_len2) : other;
  poly.x_half = x_axis * radius;
  poly.y_half = cross(w, x_axis) * radius;
  poly.sides = sides;
  return poly;
}

/* Seen from farther than AREA_FAR_FIELD radii, a sphere light is shaded from its centre and its
 * nearest point (sphere_light_specular), the polygon's precision being spent there. */
bool sphere_far_field(LightData light, float d2)
{
  float r = light.shape.x * AREA_FAR_FIELD;
  return r * r < d2;
}
#  endif
#endif

#ifdef SL_HAS_AREA
/* Area light: a one-sided Lambertian emitter of radiance L = I / A (I = P / pi along its normal,
 * packed on the CPU; A its area) towards its -Z. Its irradiance is exact for the polygon (a disk
 * or ellipse: a 16-gon of the same area): the vector form factor (Lambert 1760; Arvo 1995)
 * V = 1/2 sum_i theta_i g_i over the edges seen from p (theta_i the angle an edge subtends, g_i
 * the unit normal of the plane through p and the edge), E . (n.l) = L n.V with l = V / |V| and
 * E = L |V|: exact for every diffuse term's n.l, the polygon not clipped by p's horizon. */

/* The area light's polygon seen from p. */
LightPolygon area_polygon(LightData light, vec3 p)
{
  LightPolygon poly;
  poly.to_centre = light.position_kind.xyz - p;
  poly.x_half = light.area.xyz * light.shape.z;
  poly.y_half = cross(-light.direction_cone.xyz, light.area.xyz) * light.shape.w;
#ifdef SL_AREA_ELLIPSE
  poly.sides = light.area.w > 0.5 ? AREA_ELLIPSE_SIDES : 4;
#else
  poly.sides = 4; /* every area light of the scene is a rectangle (addon/plan/programs.py) */
#endif
  return poly;
}

/* Spread (Blender's, as Cycles' area_light_spread_attenuation): the emitter's radiance towards a
 * direction at angle a from its normal is scaled by W(a) = max(tan h - tan a, 0) / (tan h - h), h
 * half the spread -- normalised so that the light emits what it would without (and a light that
 * fills the cone delivers pi L to a facing point, as a Lambertian plane does). LightData's
 * influence.y = tan h, influence.z = 1 / (tan h - h), 0 for no spread (180 degrees). */
float spread_weight(LightData light, float tan_a)
{
  return max(light.influence.y - tan_a, 0.0) * light.influence.z;
}

#define SPREAD_GAUSS 0.57735027 /* 1 / sqrt(3): 2-point Gauss-Legendre nodes on [-1, 1] */
#ifdef SL_LTC
float ltc_density(vec4 m, vec3 w, float floor_cosine); /* ltc.glsl */
#endif

/* What of an area light reaches p through its spread, and W's mean over it. From p's height z
 * above the emitter's plane only the part within R = z tan h of its foot can (Cycles clips
 * likewise): `poly` becomes the light's box clipped to that square (a disk or ellipse the square
 * holds whole is kept), and the return value is W's mean over it as a surface facing the light
 * receives it (weights cos^2 a / r^2), by 2 x 2 Gauss points on each of its quarters about p's
 * foot, where the cone W has its apex; for a clipped disk or ellipse, times each point's cell's
 * share inside it (the coverage of a box by the boundary's tangent line), which makes it the
 * share of the box the light fills. Against quadrature (squares, rectangles, disks and ellipses
 * under spreads of 60, 30 and 10 degrees, points inside, at and beyond their edges, near and
 * far: tests/test_light_shapes.py): 0.1-5.7 %; W at the clipped light's direction alone: up to
 * +280 %. With `lobe`, `lobe_mean` is W's mean for the specular lobe too: weighted by the LTC of
 * entries m in the shading frame (rows x, y, n) instead. Twin: shading.area_spread. */
float area_spread(LightData light, vec3 p, inout LightPolygon poly, bool lobe, vec4 m, mat3 to_shading,
                  out float lobe_mean)
{
  vec3 normal = light.direction_cone.xyz;
  vec3 x_axis = light.area.xyz;
  vec3 y_axis = cross(-normal, x_axis);
  vec3 to_light_centre = poly.to_centre;
  vec3 q = -poly.to_centre;
  float z = dot(q, normal);
  vec2 foot = vec2(dot(q, x_axis), dot(q, y_axis));
  float R = z * light.influence.y;
  vec2 half_size = light.shape.zw;
  bool holds_all = all(lessThanEqual(foot - R, -half_size)) && all(greaterThanEqual(foot + R, half_size));
  vec2 lo = max(-half_size, foot - R);
  vec2 hi = min(half_size, foot + R);
  lobe_mean = 0.0;
  if (any(lessThanEqual(hi, lo)) || z <= 0.0) {
    return 0.0;
  }
  bool ellipse = light.area.w > 0.5;
  if (!holds_all) {
    vec2 centre = 0.5 * (lo + hi);
    poly.to_centre += x_axis * centre.x + y_axis * centre.y;
    poly.x_half = x_axis * (0.5 * (hi.x - lo.x));
    poly.y_half = y_axis * (0.5 * (hi.y - lo.y));
    poly.sides = 4;
  }
  vec2 split = clamp(foot, lo, hi);
  float sum = 0.0;
  float weights = 0.0;
  float lobe_sum = 0.0;
  float lobe_weights = 0.0;
  int i = 0;
  do { /* tested at the end (glsl/README.md); `continue` goes to the test */
    vec2 a = vec2((i & 1) == 0 ? lo.x : split.x, (i & 2) == 0 ? lo.y : split.y);
    vec2 b = vec2((i & 1) == 0 ? split.x : hi.x, (i & 2) == 0 ? split.y : hi.y);
    vec2 size = b - a;
    if (size.x <= 0.0 || size.y <= 0.0) {
      continue;
    }
    int j = 0;
    do {
      vec2 g = vec2((j & 1) == 0 ? -SPREAD_GAUSS : SPREAD_GAUSS,
                    (j & 2) == 0 ? -SPREAD_GAUSS : SPREAD_GAUSS);
      vec2 at = 0.5 * (a + b + size * g);
      vec2 d = at - foot;
      float r2 = dot(d, d) + z * z;
      float w = z * z / (r2 * r2) * (size.x * size.y);
      float W = spread_weight(light, length(d) / z);
      float w_mean = w;
      if (ellipse) {
        vec2 e = at / half_size;
        float rho = length(e);
        float across = 0.5 * (abs(e.x) * size.x / half_size.x + abs(e.y) * size.y / half_size.y);
        float cover = across > 0.0 ? saturate(0.5 + (1.0 - rho) * rho / across) : (rho < 1.0 ? 1.0 : 0.0);
        W *= cover;
        w_mean = holds_all ? w * cover : w; /* the ellipse itself: W's mean over it */
      }
      sum += w * W;
      weights += w_mean;
#ifdef SL_LTC
      if (lobe) {
        /* for the specular lobe: weighted by the LTC's density towards the point (ltc.glsl) over
         * the solid angle of its cell, z / r^3 dA = w r / z */
        vec3 to_point = to_light_centre + x_axis * at.x + y_axis * at.y;
        float lobe_w = ltc_density(m, to_shading * normalize(to_point), 0.0) * w * sqrt(r2) / z;
        lobe_sum += lobe_w * W;
        lobe_weights += lobe_w * (w_mean / max(w, 1e-37));
      }
#endif
    } while (++j < 4);
  } while (++i < 4);
  lobe_mean = lobe_weights > 0.0 ? lobe_sum / lobe_weights : (weights > 0.0 ? sum / weights : 0.0);
  return weights > 0.0 ? sum / weights : 0.0;
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
  float cos_a = dot(-l, light.direction_cone.xyz);
  if (area_far_field(light, d2)) {
    float spread = 1.0;
#  ifdef SL_AREA_SPREAD
    spread = light.influence.z > 0.0 ? spread_weight(light, sqrt(max(1.0 - cos_a * cos_a, 0.0)) / cos_a)
                                     : 1.0;
#  endif
    return light.intensity_blend.rgb * (cos_a * spread / max(d2, MIN_DIST2));
  }
  LightPolygon poly = area_polygon(light, p);
  float spread = 1.0;
#  ifdef SL_AREA_SPREAD /* compiled only where an area light has a Spread under 180 degrees: the
                        * test at run time would not save its cost on llvmpipe (10 % of softbox) */
  if (light.influence.z > 0.0) {
    float lobe_spread;
    spread = area_spread(light, p, poly, false, vec4(0.0), mat3(1.0), lobe_spread);
  }
#  endif
  vec3 V = polygon_form_factor(poly, mat3(1.0));
  float len = length(V);
  if (len <= 0.0 || spread <= 0.0) {
    return vec3(0.0);
  }
  l = V / len;
  return light.intensity_blend.rgb * (spread / max(area_light_area(light), 1e-12) * len);
}

#endif

/* Dispatch on the light kind; only the kinds the scene has are compiled in. */
/* A light's reach r (Blender's Custom Distance, else where I / d^2 falls to the scene's scaled
 * Light Threshold t over 1.0887: addon/plan/programs.py light_reaches, light_tiles.py) as a
 * window on its irradiance, (1 - (d / r)^4)^2 clamped (EEVEE's and Unreal's): 1 near the light,
 * exactly 0 from r on, where light culling leaves the light out. Below a threshold-derived r it
 * removes at most t of irradiance anywhere. */
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
