/* Color Ramp and the curve nodes (RGB Curves, Vector Curves, Float Curve) as Cycles evaluates
 * them (intern/cycles/kernel/svm/ramp.h): from a table Blender bakes (addon/blender/nodes.py,
 * following intern/cycles/blender/util.h's colorramp_to_array and curvemapping_*_to_array) of
 * RAMP_TABLE_ENTRIES entries at i / (RAMP_TABLE_ENTRIES - 1) of the range, looked up linearly.
 *
 * The tables are constants of the compiled graph: entry k of the table at `base` is
 * graph_table(base + k), which the compiled source defines (codegen: it reads GRAPH_CONST). A float
 * curve packs four entries in one vec4. */

#define RAMP_TABLE_ENTRIES 257

vec4 graph_table(int i);

/* entry i of a table of floats packed four to a vec4 */
float ramp_float_entry(int base, int i)
{
  return graph_table(base + i / 4)[i % 4];
}

/* Cycles' rgb_ramp_lookup inside [0, 1]: f clamped to the table (saturatef), the index clamped
 * too (it guards a NaN f), the next entry blended in where `interpolate` and f is between two */
vec4 ramp_lookup(int base, float f, bool interpolate)
{
  f = clamp(f, 0.0, 1.0) * float(RAMP_TABLE_ENTRIES - 1);
  int i = clamp(int(f), 0, RAMP_TABLE_ENTRIES - 1);
  float t = f - float(i);
  vec4 a = graph_table(base + i);
  if (interpolate && t > 0.0) {
    a = (1.0 - t) * a + t * graph_table(base + i + 1);
  }
  return a;
}

/* Cycles' rgb_ramp_lookup with extrapolate: outside [0, 1] the line through the two end entries */
vec4 ramp_lookup_extrapolated(int base, float f)
{
  if (f < 0.0) {
    vec4 t0 = graph_table(base);
    return t0 + (t0 - graph_table(base + 1)) * -f * float(RAMP_TABLE_ENTRIES - 1);
  }
  if (f > 1.0) {
    vec4 t0 = graph_table(base + RAMP_TABLE_ENTRIES - 1);
    return t0 + (t0 - graph_table(base + RAMP_TABLE_ENTRIES - 2)) * (f - 1.0) * float(RAMP_TABLE_ENTRIES - 1);
  }
  return ramp_lookup(base, f, true);
}

/* Cycles' float_ramp_lookup (interpolated), clamped to [0, 1] or extrapolated past it */
float ramp_float_lookup(int base, float f, bool extrapolate)
{
  const int last = RAMP_TABLE_ENTRIES - 1;
  if (extrapolate && (f < 0.0 || f > 1.0)) {
    float t0 = f < 0.0 ? ramp_float_entry(base, 0) : ramp_float_entry(base, last);
    float dy = t0 - (f < 0.0 ? ramp_float_entry(base, 1) : ramp_float_entry(base, last - 1));
    return t0 + dy * (f < 0.0 ? -f : f - 1.0) * float(last);
  }
  f = clamp(f, 0.0, 1.0) * float(last);
  int i = clamp(int(f), 0, last); /* guards a NaN f */
  float t = f - float(i);
  float a = ramp_float_entry(base, i);
  if (t > 0.0) {
    a = (1.0 - t) * a + t * ramp_float_entry(base, i + 1);
  }
  return a;
}

/* The Color Ramp (svm_node_rgb_ramp): colour and alpha from the table; Constant looks up the
 * entry at or below fac, the other interpolations blend two (Blender baked the interpolation
 * and colour mode into the table) */
vec4 node_ramp_linear(int base, float fac) { return ramp_lookup(base, fac, true); }
vec4 node_ramp_constant(int base, float fac) { return ramp_lookup(base, fac, false); }

/* RGB Curves and Vector Curves (svm_node_curves): each component through its own column of the
 * table over the curves' x range [lo, hi], blended with the input by fac */
vec3 curves_apply(int base, float lo, float hi, float fac, vec3 v, bool extrapolate)
{
  vec3 rel = (v - vec3(lo)) / (hi - lo);
  vec3 c;
  if (extrapolate) {
    c = vec3(ramp_lookup_extrapolated(base, rel.x).x, ramp_lookup_extrapolated(base, rel.y).y,
             ramp_lookup_extrapolated(base, rel.z).z);
  }
  else {
    c = vec3(ramp_lookup(base, rel.x, true).x, ramp_lookup(base, rel.y, true).y, ramp_lookup(base, rel.z, true).z);
  }
  return (1.0 - fac) * v + fac * c;
}

/* RGB Curves keep the colour's alpha */
vec4 node_rgb_curves(int base, float lo, float hi, float fac, vec4 color)
{
  return vec4(curves_apply(base, lo, hi, fac, color.rgb, false), color.a);
}

vec4 node_rgb_curves_extrapolated(int base, float lo, float hi, float fac, vec4 color)
{
  return vec4(curves_apply(base, lo, hi, fac, color.rgb, true), color.a);
}

vec3 node_vector_curves(int base, float lo, float hi, float fac, vec3 v)
{
  return curves_apply(base, lo, hi, fac, v, false);
}

vec3 node_vector_curves_extrapolated(int base, float lo, float hi, float fac, vec3 v)
{
  return curves_apply(base, lo, hi, fac, v, true);
}

/* Float Curve (svm_node_curve) */
float node_float_curve(int base, float lo, float hi, float fac, float value)
{
  return (1.0 - fac) * value + fac * ramp_float_lookup(base, (value - lo) / (hi - lo), false);
}

float node_float_curve_extrapolated(int base, float lo, float hi, float fac, float value)
{
  return (1.0 - fac) * value + fac * ramp_float_lookup(base, (value - lo) / (hi - lo), true);
}
