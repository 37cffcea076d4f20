/* Radial Tiling (Blender 5's ShaderNodeRadialTiling; Cycles' svm_node_radial_tiling,
 * svm/radial_tiling.h and radial_tiling_shared.h: calculate_out_variables,
 * calculate_out_variables_irregular_circular, calculate_out_segment_id): the plane about the
 * origin cut into Sides angular segments, each a (rounded) polygon's, with coordinates inside its
 * segment. Cycles' branches and float operations in its order; where its CPU kernel fuses a
 * product into a sum, float_fma (node_float.glsl; measured against Cycles 5.0 case by case).
 *
 * Names shortened from Cycles': `bisector` the angle from a segment's border to its bisector
 * (pi / sides), `segment` a segment's angle, `coord` the coordinate's angle from its segment's
 * border, `bevel` the angle from the border where a rounded corner starts, `last` the last,
 * narrower segment's half angle where Sides is not whole. Results vec4(l along the bisector,
 * parameter across it, width, rotation). */

/* the coordinate across a straight edge: l tan|bisector - angle|, negative before the bisector */
float rt_straight(float l, float bisector, float angle)
{
  PRECISE float r = l * tan(abs(bisector - angle));
  return angle < bisector ? -r : r;
}

/* half a segment's width at distance l along its bisector (Cycles'
 * normalize_based_on_l_angle_bisector): l tan(angle) + spline (l / 2 + 1/2) + roundness bevel */
float rt_normalizer(float l, float angle, float spline, float roundness, float bevel, bool fused_k)
{
  PRECISE float t = float_fma(l, tan(angle), spline * (0.5 * l + 0.5));
  PRECISE float r = fused_k ? float_fma(roundness, bevel, t) : t + roundness * bevel;
  return r;
}

/* the same at the coordinate's distance (normalize_based_on_l_coord): l sin(angle) + spline
 * (l cos(angle) / 2 + 1/2) + roundness bevel */
float rt_normalizer_coord(float l, float angle, float spline, float roundness, float bevel, bool first,
                          bool fused_k)
{
  float inner = float_fma(0.5 * l, cos(angle), 0.5);
  PRECISE float t = first ? float_fma(l, sin(angle), spline * inner) :
                            float_fma(spline, inner, l * sin(angle));
  PRECISE float r = fused_k ? float_fma(roundness, bevel, t) : t + roundness * bevel;
  return r;
}

/* what a rounded corner adds to l sin(angle): along its spline, then along its arc */
float rt_rounded_terms(float l, float angle, float to_bevel, float spline)
{
  PRECISE float c = l * cos(angle);
  if (to_bevel < spline) {
    PRECISE float q = 0.5 * (1.0 - c) * (to_bevel * to_bevel) / spline;
    return float_fma(c, to_bevel, q);
  }
  return float_fma(spline, float_fma(0.5 * l, cos(angle), -0.5), to_bevel);
}

/* Cycles' mix: a + t (b - a) */
float rt_mix(float a, float b, float t) { return float_fma(t, b - a, a); }

/* the arcs of a segment with rounded corners, about its borders: vec2(l, parameter) */
vec2 rt_round(bool normalize, float k, float l_coord, float bisector, float segment, float coord, float bevel)
{
  float to_bisector = bisector - bevel;
  float spline = (1.0 - k) * bevel;
  PRECISE float signed_angle = coord - float(coord > bisector) * segment;
  PRECISE float l_center = (1.0 - k) / cos(bisector);
  PRECISE float along = cos(signed_angle) * l_center;
  PRECISE float l = l_coord / (along + sqrt(float_fma(-l_center, l_center, float_fma(along, along, k * k))));
  PRECISE float to_bevel = bevel - abs(signed_angle);
  PRECISE float p = l_coord * sin(to_bisector) + rt_rounded_terms(l_coord, to_bisector, to_bevel, spline);
  p = coord < bisector ? -p : p;
  if (normalize) {
    p /= rt_mix(rt_normalizer(l, to_bisector, spline, k, bevel, false),
                rt_normalizer_coord(l_coord, to_bisector, spline, k, bevel, false, false), to_bevel / bevel);
  }
  return vec2(l, p);
}

/* a regular segment with rounded corners (Cycles' "Regular straight part" and "Regular rounded
 * part" of 0 < roundness < 1): vec3(l, parameter, width) */
vec3 rt_bevelled(bool normalize, float k, float l_coord, float bisector, float segment, float coord,
                 float bevel)
{
  PRECISE float width = tan(bisector - bevel) + (1.0 - k) * bevel + k * bevel;
  if (coord >= segment - bevel || coord < bevel) {
    return vec3(rt_round(normalize, k, l_coord, bisector, segment, coord, bevel), width);
  }
  PRECISE float l = l_coord * cos(bisector - coord);
  PRECISE float p = rt_straight(l, bisector, coord);
  if (normalize) {
    p /= rt_normalizer(l, bisector - bevel, (1.0 - k) * bevel, k, bevel, false);
  }
  return vec3(l, p, width);
}

/* Sides a whole number: every segment alike (straight, round, or straight with rounded corners) */
vec4 rt_regular(bool normalize, float n, float k, float l_coord, float bisector, float segment, float coord,
                float rotation)
{
  if (k == 0.0) {
    PRECISE float l = l_coord * cos(bisector - coord);
    PRECISE float p = rt_straight(l, bisector, coord);
    if (normalize && n != 2.0) { /* (a 2-gon's edges are one line: tan(pi / 2) is infinite) */
      p /= l * tan(bisector);
    }
    return vec4(l, p, n != 2.0 ? tan(bisector) : 0.0, rotation);
  }
  if (k == 1.0) {
    PRECISE float p = abs(bisector - coord);
    p = coord < bisector ? -p : p;
    if (normalize) {
      p /= bisector;
    }
    return vec4(l_coord, p, bisector, rotation);
  }
  PRECISE float bevel = bisector - float_atan((1.0 - k) * tan(bisector));
  return vec4(rt_bevelled(normalize, k, l_coord, bisector, segment, coord, bevel), rotation);
}

/* Sides not a whole number, roundness 0: whole segments, and the last, narrower one */
vec4 rt_irregular_straight(bool normalize, float n, float l_coord, float x_axis_coord, float bisector,
                           float segment_id, float segment, float coord, float rotation)
{
  float last = float_fma(-floor(n), bisector, 3.1415927);
  if (x_axis_coord < 6.2831855 - 2.0 * last) {
    PRECISE float l = l_coord * cos(bisector - coord);
    PRECISE float p = rt_straight(l, bisector, coord);
    if (normalize) {
      p /= l * tan(bisector);
    }
    return vec4(l, p, tan(bisector), rotation);
  }
  PRECISE float ratio = cos(bisector) / cos(last);
  PRECISE float l = ratio * (l_coord * cos(last - coord));
  PRECISE float p = rt_straight(l, last, coord);
  if (normalize) {
    p /= l * tan(last);
  }
  PRECISE float rotation_last = segment_id * segment + last;
  return vec4(l, p, tan(last), rotation_last);
}

/* Sides not a whole number, roundness above 0 (Cycles' calculate_out_variables_irregular_circular):
 * whole segments with rounded corners; the last one's straight part and its two arcs */
vec4 rt_irregular_circular(bool normalize, float n, float k, vec2 co, float l_coord, float x_axis_coord,
                           float bisector, float segment_id, float segment, float coord, float rotation)
{
  const float two_pi = 6.2831855;
  PRECISE float bevel = bisector - float_atan((1.0 - k) * tan(bisector));
  PRECISE float last = 3.1415927 - floor(n) * bisector;
  PRECISE float last_segment = 2.0 * last;
  PRECISE float inner_bevel = last - float_atan((1.0 - k) * tan(last));
  PRECISE float radius = k * tan(last) / tan(0.5 * (bisector + last));
  PRECISE float c = cos(last - inner_bevel);
  PRECISE float center_x = float_fma(-radius, cos(last), cos(inner_bevel) / c);
  PRECISE float center_y = radius * sin(last) - sin(inner_bevel) / c;
  PRECISE float outer_x = float_fma(radius, cos(bisector), center_x);
  PRECISE float outer_bevel = float_atan((center_y + radius * sin(bisector)) / outer_x);
  PRECISE float outer_to_bisector = bisector - outer_bevel;
  PRECISE float effective = 1.0 - tan(bisector - outer_bevel) / tan(bisector);
  PRECISE float outer_spline = (1.0 - effective) * outer_bevel;

  if (x_axis_coord >= outer_bevel && x_axis_coord < two_pi - last_segment - outer_bevel) {
    /* the whole segments: as a regular polygon's, but the straight parts beside the last segment
     * normalised by its outer arc */
    bool straight = (coord >= bevel && coord < segment - bevel) ||
                    x_axis_coord >= two_pi - last_segment - bevel || x_axis_coord < bevel;
    if (!straight) {
      return vec4(rt_bevelled(normalize, k, l_coord, bisector, segment, coord, bevel), rotation);
    }
    PRECISE float width = tan(bisector - bevel) + (1.0 - k) * bevel + k * bevel;
    PRECISE float l = l_coord * cos(bisector - coord);
    PRECISE float p = rt_straight(l, bisector, coord);
    if (normalize) {
      bool beside_last = x_axis_coord >= two_pi - last_segment - bisector || x_axis_coord < bisector;
      p /= beside_last ? rt_normalizer(l, outer_to_bisector, outer_spline, effective, outer_bevel, true) :
                         rt_normalizer(l, bisector - bevel, (1.0 - k) * bevel, k, bevel, false);
    }
    return vec4(l, p, width, rotation);
  }

  PRECISE float to_last = last - inner_bevel;
  PRECISE float ratio = cos(bisector) / cos(last);
  PRECISE float spline = (1.0 - k) * inner_bevel;
  PRECISE float width_last = tan(to_last) + ratio * (spline * ((0.5 / ratio) + 0.5) + k * inner_bevel);
  PRECISE float rotation_last = segment_id * segment + last;
  if (x_axis_coord >= two_pi - last_segment + inner_bevel && x_axis_coord < two_pi - inner_bevel) {
    /* the last segment's straight part */
    PRECISE float l_last = l_coord * cos(last - coord);
    PRECISE float l = ratio * l_last;
    PRECISE float p = rt_straight(l, last, coord);
    if (normalize) {
      p /= ratio * rt_normalizer(l_last, to_last, spline, k, inner_bevel, false);
    }
    return vec4(l, p, width_last, rotation_last);
  }

  /* the last segment's arcs, their angle mirrored about its bisector */
  PRECISE float mirrored = float_atan2(co.y, co.x);
  if (x_axis_coord >= two_pi - last_segment - outer_bevel && x_axis_coord < two_pi - last) {
    mirrored = -(mirrored + last_segment);
  }
  PRECISE float along = float_fma(sin(mirrored), center_y, cos(mirrored) * center_x);
  PRECISE float inside = float_fma(-center_x, center_x, float_fma(along, along, radius * radius)) -
                         center_y * center_y;
  PRECISE float l_arc_last = l_coord / (along + sqrt(inside));
  PRECISE float l = ratio * l_arc_last;
  if (mirrored < 0.0) {
    /* the inner arc, towards the last segment's bisector */
    PRECISE float to_bevel = inner_bevel - abs(mirrored);
    PRECISE float p = float_fma(ratio, rt_rounded_terms(l_coord, to_last, to_bevel, spline),
                                ratio * l_coord * sin(to_last));
    p = coord < last ? -p : p;
    if (normalize) {
      p /= ratio * rt_mix(rt_normalizer(l_arc_last, to_last, spline, k, inner_bevel, false),
                          rt_normalizer_coord(l_coord, to_last, spline, k, inner_bevel, true, false),
                          to_bevel / inner_bevel);
    }
    return vec4(l, p, width_last, rotation_last);
  }
  /* the outer arc, towards the whole segment beside it */
  PRECISE float to_outer = outer_bevel - abs(mirrored);
  PRECISE float p = l_coord * sin(outer_to_bisector) +
                    rt_rounded_terms(l_coord, outer_to_bisector, to_outer, outer_spline);
  p = coord < bisector ? -p : p;
  if (normalize) {
    p /= rt_mix(rt_normalizer(l, outer_to_bisector, outer_spline, effective, outer_bevel, true),
                rt_normalizer_coord(l_coord, outer_to_bisector, outer_spline, effective, outer_bevel, false,
                                    true),
                to_outer / outer_bevel);
  }
  PRECISE float width_outer = float_fma(k, bevel, tan(bisector - bevel) + (1.0 - k) * bevel);
  return vec4(l, p, width_outer, rotation);
}

/* vec4(Segment Coordinates' x (across the bisector) and y (along it), Segment Width, Segment
 * Rotation); Sides at least 2, Roundness clamped to [0, 1] as Cycles does */
vec4 radial_tiling(vec3 vector, float sides, float roundness, bool normalize)
{
  vec2 co = vector.xy;
  float n = max(sides, 2.0);
  float k = clamp(roundness, 0.0, 1.0);
  PRECISE float l_coord = sqrt(float_fma(co.y, co.y, co.x * co.x));
  PRECISE float x_axis_coord = float_atan2(co.y, co.x) + float(co.y < 0.0) * 6.2831855;
  PRECISE float bisector = 3.1415927 / n;
  PRECISE float segment = 2.0 * bisector;
  PRECISE float segment_id = floor(x_axis_coord / segment);
  PRECISE float coord = x_axis_coord - segment_id * segment;
  PRECISE float rotation = segment_id * segment + bisector;
  vec4 v;
  if (n - floor(n) == 0.0) {
    v = rt_regular(normalize, n, k, l_coord, bisector, segment, coord, rotation);
  }
  else if (k == 0.0) {
    v = rt_irregular_straight(normalize, n, l_coord, x_axis_coord, bisector, segment_id, segment, coord,
                              rotation);
  }
  else {
    v = rt_irregular_circular(normalize, n, k, co, l_coord, x_axis_coord, bisector, segment_id, segment,
                              coord, rotation);
  }
  if (co.x == 0.0 && co.y == 0.0) { /* the parameter is 0 at the origin (Cycles' definition) */
    v.y = 0.0;
  }
  if (normalize) {
    v.y = 0.5 * v.y + 0.5; /* [-1, 1] -> [0, 1] */
  }
  else {
    v.x -= 1.0;
  }
  return vec4(v.y, v.x, v.z, v.w);
}

vec4 node_radial_tiling(vec3 vector, float sides, float roundness)
{
  return radial_tiling(vector, sides, roundness, false);
}

vec4 node_radial_tiling_normalized(vec3 vector, float sides, float roundness)
{
  return radial_tiling(vector, sides, roundness, true);
}

/* Segment ID: the segment's index counterclockwise from the x axis (calculate_out_segment_id),
 * atan2 / 2 pi through the reciprocal, fused; Sides at least 2 as Cycles' */
float node_radial_tiling_id(vec3 vector, float sides)
{
  vec2 co = vector.xy;
  return floor(max(sides, 2.0) * float_fma(float_atan2(co.y, co.x), 0.15915494, float(co.y < 0.0)));
}
