/* Converter and colour nodes, each as Cycles' SVM evaluates it (svm/map_range.h, clamp.h,
 * color_util.h, invert.h, gamma.h, brightness.h, hsv.h). */

/* Cycles' smoothstep(edge0, edge1, x): 0 below edge0, 1 from edge1 on (GLSL's is undefined for
 * edge0 >= edge1) */
float node_smoothstep(float e0, float e1, float x)
{
  if (x < e0) {
    return 0.0;
  }
  if (x >= e1) {
    return 1.0;
  }
  float t = (x - e0) / (e1 - e0);
  return (3.0 - 2.0 * t) * (t * t);
}

float node_smootherstep(float e0, float e1, float x)
{
  float t = clamp(e1 != e0 ? (x - e0) / (e1 - e0) : 0.0, 0.0, 1.0);
  return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

/* Clamp, "Range": the bounds in either order */
float clamp_range(float value, float lo, float hi) { return lo > hi ? clamp(value, hi, lo) : clamp(value, lo, hi); }
float clamp_minmax(float value, float lo, float hi) { return min(max(value, lo), hi); }

/* Map Range on a float: 0 where the source range is empty */
float map_range_linear(float x, float a, float b, float c, float d, float steps)
{
  return a != b ? c + (x - a) / (b - a) * (d - c) : 0.0;
}

float map_range_stepped(float x, float a, float b, float c, float d, float steps)
{
  if (a == b) {
    return 0.0;
  }
  float f = (x - a) / (b - a);
  f = steps > 0.0 ? floor(f * (steps + 1.0)) / steps : 0.0;
  return c + f * (d - c);
}

float map_range_smoothstep(float x, float a, float b, float c, float d, float steps)
{
  if (a == b) {
    return 0.0;
  }
  float f = a > b ? 1.0 - node_smoothstep(b, a, x) : node_smoothstep(a, b, x);
  return c + f * (d - c);
}

float map_range_smootherstep(float x, float a, float b, float c, float d, float steps)
{
  if (a == b) {
    return 0.0;
  }
  float f = a > b ? 1.0 - node_smootherstep(b, a, x) : node_smootherstep(a, b, x);
  return c + f * (d - c);
}

vec4 invert_color(float fac, vec4 color) { return vec4(mix(color.rgb, vec3(1.0) - color.rgb, fac), color.a); }

float gamma_channel(float c, float g) { return c > 0.0 ? pow(c, g) : c; }

vec4 gamma_color(vec4 color, float g)
{
  if (g == 0.0) {
    return vec4(1.0, 1.0, 1.0, color.a);
  }
  return vec4(gamma_channel(color.r, g), gamma_channel(color.g, g), gamma_channel(color.b, g), color.a);
}

vec4 brightness_contrast(vec4 color, float brightness, float contrast)
{
  float a = 1.0 + contrast;
  float b = brightness - contrast * 0.5;
  return vec4(max(a * color.rgb + vec3(b), 0.0), color.a);
}

vec4 hue_saturation_value(float hue, float saturation, float value, float fac, vec4 color)
{
  vec3 hsv = color_rgb_to_hsv(color.rgb);
  float h = hsv.x + hue + 0.5;
  hsv.x = h - floor(h);
  hsv.y = clamp(hsv.y * saturation, 0.0, 1.0);
  hsv.z *= value;
  vec3 rgb = fac * color_hsv_to_rgb(hsv) + (1.0 - fac) * color.rgb;
  return vec4(max(rgb, 0.0), color.a);
}

/* Map Range on vectors, per component, as Cycles' svm_node_vector_map_range: a division by an
 * empty source range gives 0; Clamp (linear and stepped) to the target range in either order */
vec3 map_range_vector_factor(int kind, vec3 x, vec3 a, vec3 b, vec3 steps)
{
  vec3 f = vec3(math_safe_divide(x.x - a.x, b.x - a.x), math_safe_divide(x.y - a.y, b.y - a.y),
                math_safe_divide(x.z - a.z, b.z - a.z));
  if (kind == 1) {
    return vec3(steps.x > 0.0 ? floor(f.x * (steps.x + 1.0)) / steps.x : 0.0,
                steps.y > 0.0 ? floor(f.y * (steps.y + 1.0)) / steps.y : 0.0,
                steps.z > 0.0 ? floor(f.z * (steps.z + 1.0)) / steps.z : 0.0);
  }
  if (kind == 2) {
    f = clamp(f, 0.0, 1.0);
    return (vec3(3.0) - 2.0 * f) * (f * f);
  }
  if (kind == 3) {
    f = clamp(f, 0.0, 1.0);
    return f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
  }
  return f;
}

vec3 map_range_vector(int kind, bool use_clamp, vec3 x, vec3 a, vec3 b, vec3 c, vec3 d, vec3 steps)
{
  vec3 r = c + map_range_vector_factor(kind, x, a, b, steps) * (d - c);
  if (use_clamp && kind < 2) {
    r = vec3(clamp_range(r.x, c.x, d.x), clamp_range(r.y, c.y, d.y), clamp_range(r.z, c.z, d.z));
  }
  return r;
}
