/* Area and sphere lights' specular lobe by linearly transformed cosines (Heitz, Dupuy, Hill &
 * Neubelt 2016, "Real-Time Polygonal-Light Shading with Linearly Transformed Cosines"), and the horizon clipping
 * of a polygon's form factor by the sphere of the same vector form factor (Heitz & Hill 2017,
 * "Real-time area lighting: a journey from research to production"). Twin: addon/reference/ltc.py.
 *
 * The lobe f (n.l) / E(mu, r) of the program's distribution (GGX; Beckmann with SL_NDF_BECKMANN)
 * with Smith's height-correlated masking, seen at n.v = mu, is approximated by a clamped cosine
 * D_o moved by a linear map M: D(w) = D_o(M^-1 w / |M^-1 w|) |det M^-1| / |M^-1 w|^3. Its
 * integral over a polygon is the clamped cosine's over the polygon mapped by M^-1: a form factor,
 * in closed form. E(mu, r), the directional albedo of the program's own D and V with F = 1, is
 * ms_table's; the Fresnel term is taken once, at the half vector of the light's irradiance-weighted
 * direction l.
 *
 * ltc_table (RGBA32F, SL_LTC_SIZE wide): rows 0 .. SL_LTC_SIZE - 1 hold M^-1 per (mu, roughness),
 * scaled so that its middle entry is 1, as (m00, m02, m20, m22) in the shading frame x = the
 * tangent towards v, y = n x x, z = n (column i: sqrt(1 - mu) = i / (N - 1), row j: roughness
 * j / (N - 1), both ends on the grid); the SL_LTC_SPHERE_SIZE rows after them hold, in red, the
 * form factor of a spherical cap cut by the horizon (Snyder 1996), row j: its unclipped form
 * factor j / (M - 1), column i: its centre's height z = 2 i / (M - 1) - 1. */

#if defined(SL_LTC) || defined(SL_SHEEN)
/* D(w) = D_o(M^-1 w / |M^-1 w|) |det M^-1| / |M^-1 w|^3 of the LTC with entries m at a unit
 * direction w of the shading frame (any scale of M^-1: D does not depend on it), D_o's cosine
 * floored at `floor_cosine` (ltc_density_floor). (The sheen's lobe is such a cosine too.) */
float ltc_density(vec4 m, vec3 w, float floor_cosine)
{
  vec3 y = vec3(m.x * w.x + m.y * w.z, w.y, m.z * w.x + m.w * w.z);
  /* |M^-1 w| = 0 (w = 0: a light at the shaded point) gives 0, not 0 / 0: floored where len2^1.5
   * is still a normal float32 (1e-30's 1e-45 flushed to 0 on llvmpipe: the sheen NaN at distance 0) */
  float len2 = max(dot(y, y), 1e-24);
  float cosine = max(y.z * inversesqrt(len2), floor_cosine);
  return cosine * abs(m.x * m.w - m.y * m.z) / (PI * len2 * sqrt(len2));
}

/* The unit direction M w / |M w| a direction w of the clamped cosine's space maps to under the LTC with
 * entries m: M = adj(M^-1) = [[m22, 0, -m02], [0, det, 0], [-m20, 0, m00]], a positive multiple of the
 * inverse (det M^-1 > 0). Maps cosine-distributed directions to the lobe's (Heitz et al. 2016, sec. 3). */
vec3 ltc_direction(vec4 m, vec3 w)
{
  return normalize(vec3(m.w * w.x - m.y * w.z, (m.x * m.w - m.y * m.z) * w.y, m.x * w.z - m.z * w.x));
}
#endif

#ifdef SL_LTC
/* Bilinear lookups by texelFetch, as the twin's (the grid includes both ends). */
vec4 ltc_texel_mix(ivec2 origin, vec2 x, int size)
{
  ivec2 i0 = ivec2(floor(x));
  ivec2 i1 = min(i0 + 1, ivec2(size - 1));
  vec2 t = x - vec2(i0);
  vec4 e00 = texelFetch(ltc_table, origin + ivec2(i0.x, i0.y), 0);
  vec4 e10 = texelFetch(ltc_table, origin + ivec2(i1.x, i0.y), 0);
  vec4 e01 = texelFetch(ltc_table, origin + ivec2(i0.x, i1.y), 0);
  vec4 e11 = texelFetch(ltc_table, origin + ivec2(i1.x, i1.y), 0);
  return mix(mix(e00, e10, t.x), mix(e01, e11, t.x), t.y);
}

vec4 ltc_entries(float NoV, float roughness)
{
  float n = float(SL_LTC_SIZE - 1);
  vec2 x = clamp(vec2(sqrt(saturate(1.0 - NoV)), roughness) * n, vec2(0.0), vec2(n));
  return ltc_texel_mix(ivec2(0), x, SL_LTC_SIZE);
}

/* The form factor of a polygon whose vector form factor has length len (<= 1) and height z
 * (its unit direction's, towards the surface's normal), given as one_plus_z = 1 + z, which the
 * caller can take without cancelling when z is near -1; clipped to the horizon as the cap of the
 * same vector form factor would be (sin^2 sigma = len): len z when the cap lies wholly above
 * (z >= sin sigma: the table's bilinear lookup of len z is exact there), 0 wholly below, between
 * Snyder's closed form as tabulated. */
float ltc_horizon_clip(float len, float one_plus_z)
{
  float n = float(SL_LTC_SPHERE_SIZE - 1);
  vec2 x = clamp(vec2(one_plus_z * 0.5, len) * n, vec2(0.0), vec2(n));
  return ltc_texel_mix(ivec2(0, SL_LTC_SIZE), x, SL_LTC_SPHERE_SIZE).r;
}


/* The cosine a light's density is floored at where its polygon, mapped by M^-1, is small: the
 * mean over it, I / |F| (the cap of the same vector form factor: z when wholly above the horizon,
 * the clipped integral's own across it), faded out as |F| grows to LTC_SMALL_POLYGON. A small
 * light's integral is then at least its density's own measure (I = D dw): the density at the
 * light's direction alone is 0 below the cosine's horizon, where the clipped cap still holds some
 * of it, and far below the mean where the lobe's tail is steep; the ratio estimator overshot such
 * tails 3-30x (a rough sphere's rim under a small sphere light) and ran away uncapped. A large
 * mapped polygon (a light that holds much of a narrow lobe) is better measured by the density at
 * l. Small lights in the lobe's tail (tests/test_ltc.py, 0.1 m square 2 m away in 25 directions,
 * GGX roughness 0.2 / 0.5 / 0.8 at n.v 0.9), worst relative error: unfloored 4.4 / 0.79 / 0.42,
 * floored 0.02 / 0.60 / 0.01. Against Cycles (tests/test_light_shapes.py, white GGX metal sphere,
 * square light, roughness 0.1 / 0.3 / 0.6 / 1): the floor at sizes 1e30 (always) / 0.3 / 0.1 /
 * 0.03 measured (crossing the horizon only) 3.6 / 1.4 / 1.3 / 1.5, 1.1 / 1.6 / 1.4 / 1.4,
 * 0.6 / 1.7 / 1.4 / 1.4, 0.7 / 2.1 / 1.4 / 1.3 %, unfloored 1.1 / 2.1 / 1.4 / 1.3 %. */
#define LTC_SMALL_POLYGON 0.1
float ltc_density_floor(float integral, float len)
{
  return integral / len * saturate(1.0 - len / LTC_SMALL_POLYGON);
}

/* surface.glsl's LtcFrame at a view: the shading frame, M^-1 and the lobe's albedo. */
LtcFrame ltc_frame_at(vec3 n, vec3 v, float NoV, float roughness)
{
  LtcFrame f;
  vec3 x_axis = v - n * dot(n, v);
  float x_len2 = dot(x_axis, x_axis);
  vec3 other = abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
  f.x_axis = x_len2 > 1e-18 ? x_axis * inversesqrt(x_len2) : normalize(cross(other, n));
  f.y_axis = cross(n, f.x_axis);
  f.m = ltc_entries(NoV, roughness);
  f.albedo = ms_albedo(NoV, roughness);
  return f;
}

/* The integral of an LTC (frame f about the normal n) over a light's polygon seen from the
 * polygon's origin (an area light's, or a sphere light's disc), and (out) the LTC's density towards
 * l (the light's irradiance-weighted direction, E_Area's). Corners as E_Area takes them (offsets
 * from the light's centre, edges' cross products from offsets: precise for small or far lights),
 * each mapped by M^-1 first. */
float ltc_polygon_frame(LtcFrame f, vec3 n, LightPolygon poly, vec3 l, out float density_l)
{
  vec4 m = f.m;
  vec3 x_axis = f.x_axis;
  vec3 y_axis = f.y_axis;
  /* M^-1 in the world: rows (m00 x + m02 n), y, (m20 x + m22 n) */
  mat3 to_cosine = transpose(mat3(m.x * x_axis + m.y * n, y_axis, m.z * x_axis + m.w * n));
  vec3 F = polygon_form_factor(poly, to_cosine) * INV_PI;
  vec3 l_local = vec3(dot(l, x_axis), dot(l, y_axis), dot(l, n));
  float len = length(F);
  if (len <= 0.0) {
    density_l = ltc_density(m, l_local, 0.0);
    return 0.0;
  }
  /* 1 + F.z / |F| without cancelling near -1 (a light below the horizon that nearly fills it,
   * where the table is steep in z): (F.x^2 + F.y^2) / (|F| (|F| - F.z)) */
  float z = F.z / len;
  float one_plus_z = z < 0.0 ? (F.x * F.x + F.y * F.y) / (len * (len - F.z)) : 1.0 + z;
  len = min(len, 1.0);
  float integral = ltc_horizon_clip(len, one_plus_z);
  density_l = ltc_density(m, l_local, ltc_density_floor(integral, len));
  return integral;
}

/* The surface's own LTC over the polygon (ltc_polygon_frame). */
float ltc_polygon(Surface s, LightPolygon poly, vec3 l, out float density_l)
{
  return ltc_polygon_frame(s.ltc, s.n, poly, l, density_l);
}

/* The specular integral over the polygon, int_P f (n.l) (F = 1), from the LTC's integral I over
 * it and the albedo E: E I would be right if the LTC had the BRDF's shape, which it has not in the
 * tails of rough lobes. A ratio estimator takes the BRDF itself towards the light, c = f (n.l) / D
 * there (exact for a small light: I -> D dw); a light that holds the whole lobe
 * (I -> 1) is E exactly; the two limits blended by I: I (c + (E - c) I). c is at most
 * LTC_MAX_SHAPE_RATIO E: where the light's direction sits beyond the cosine's horizon but the light
 * reaches into the lobe (a smooth sphere's rim) the ratio is unbounded and the estimate with it.
 * Against Cycles, a white GGX metal sphere under a square light at roughness 0.1 / 0.3 / 0.6 / 1:
 * E I alone (fixed axis) 1.0 / 1.7 / 14 / 3.2 %; with the ratio capped at 10 E 2.6 / 6.5 / 5.2 /
 * 1.4 %, at 2 E 1.2 / 2.6 / 1.5 / 1.3 %, at 1.5 E 1.1 / 2.1 / 1.4 / 1.3 %, at 1 E 1.0 / 1.7 / 2.2 /
 * 2.1 % (the softbox preset's FLIP: 0.100 at 10 E, 0.086 at 1.5 E, 0.085 at 1 E). */
#define LTC_MAX_SHAPE_RATIO 1.5
float ltc_lobe_integral(float form_factor, float albedo, float lobe_l, float density_l)
{
  float c = min(lobe_l / max(density_l, 1e-30), LTC_MAX_SHAPE_RATIO * albedo);
  return form_factor * (c + (albedo - c) * min(form_factor, 1.0));
}
#endif
