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

/* The Blackbody node as Cycles evaluates it (kernel/svm/blackbody.h, math_util.h's
 * svm_math_blackbody_color_rec709 and kernel/tables.h's fit): a/t + b t + c per range of t for R
 * and G, a cubic for B, in Rec. 709; constant beyond 800 .. 12000 K. Cycles then converts Rec.
 * 709 to the scene linear space (rec709_to_rgb: the identity for Blender's Linear Rec.709, the
 * only working space the engine renders in) and clamps negatives (the fit reaches out of gamut). */
const float BLACKBODY_R[21] = float[](
  1.61919106e+03, -2.05010916e-03, 5.02995757e+00, 2.48845471e+03, -1.11330907e-03, 3.22621544e+00,
  3.34143193e+03, -4.86551192e-04, 1.76486769e+00, 4.09461742e+03, -1.27446582e-04, 7.25731635e-01,
  4.67028036e+03, 2.91258199e-05, 1.26703442e-01, 4.59509185e+03, 2.87495649e-05, 1.50345020e-01,
  3.78717450e+03, 9.35907826e-06, 3.99075871e-01);
const float BLACKBODY_G[21] = float[](
  -4.88999748e+02, 6.04330754e-04, -7.55807526e-02, -7.55994277e+02, 3.16730098e-04, 4.78306139e-01,
  -1.02363977e+03, 1.20223470e-04, 9.36662319e-01, -1.26571316e+03, 4.87340896e-06, 1.27054498e+00,
  -1.42529332e+03, -4.01150431e-05, 1.43972784e+00, -1.17554822e+03, -2.16378048e-05, 1.30408023e+00,
  -5.00799571e+02, -4.59832026e-06, 1.09098763e+00);
const float BLACKBODY_B[28] = float[](
  5.96945309e-11, -4.85742887e-08, -9.70622247e-05, -4.07936148e-03,
  2.40430366e-11, 5.55021075e-08, -1.98503712e-04, 2.89312858e-02,
  -1.40949732e-11, 1.89878968e-07, -3.56632824e-04, 9.10767778e-02,
  -3.61460868e-11, 2.84822009e-07, -4.93211319e-04, 1.56723440e-01,
  -1.97075738e-11, 1.75359352e-07, -2.50542825e-04, -2.22783266e-02,
  -1.61997957e-13, -1.64216008e-08, 3.86216271e-04, -7.38077418e-01,
  6.72650283e-13, -2.73078809e-08, 4.24098264e-04, -7.52335691e-01);

vec3 blackbody_rec709(float t)
{
  if (t >= 12000.0) {
    return vec3(0.8262954810464208, 0.9945080501520986, 1.566307710274283);
  }
  if (t < 800.0) { /* very dim light: OSL's lower limit */
    return vec3(5.413294490189271, -0.20319390035873933, -0.0822535242887164);
  }
  int i = t >= 6365.0 ? 6 : t >= 3315.0 ? 5 : t >= 1902.0 ? 4 : t >= 1449.0 ? 3 : t >= 1167.0 ? 2 : t >= 965.0 ? 1 : 0;
  float t_inv = 1.0 / t;
  return vec3(BLACKBODY_R[3 * i] * t_inv + BLACKBODY_R[3 * i + 1] * t + BLACKBODY_R[3 * i + 2],
              BLACKBODY_G[3 * i] * t_inv + BLACKBODY_G[3 * i + 1] * t + BLACKBODY_G[3 * i + 2],
              ((BLACKBODY_B[4 * i] * t + BLACKBODY_B[4 * i + 1]) * t + BLACKBODY_B[4 * i + 2]) * t +
                  BLACKBODY_B[4 * i + 3]);
}

vec4 node_blackbody(float temperature) { return vec4(max(blackbody_rec709(temperature), 0.0), 1.0); }

/* The Wavelength node as Cycles evaluates it (kernel/svm/wavelength.h): the CIE 1931 colour
 * matching functions (kernel/tables.h, 380 .. 780 nm by 5 nm) interpolated, black outside them
 * (the index truncates toward 0, as C converts: just below 380 nm extrapolates the first
 * interval), to the scene linear space by the running Blender's XYZ -> RGB rows (constants), scaled
 * by 1 / 2.52 and negatives clamped */
const vec3 CIE_COLOR_MATCH[81] = vec3[](
  vec3(0.0014, 0.0000, 0.0065), vec3(0.0022, 0.0001, 0.0105), vec3(0.0042, 0.0001, 0.0201),
  vec3(0.0076, 0.0002, 0.0362), vec3(0.0143, 0.0004, 0.0679), vec3(0.0232, 0.0006, 0.1102),
  vec3(0.0435, 0.0012, 0.2074), vec3(0.0776, 0.0022, 0.3713), vec3(0.1344, 0.0040, 0.6456),
  vec3(0.2148, 0.0073, 1.0391), vec3(0.2839, 0.0116, 1.3856), vec3(0.3285, 0.0168, 1.6230),
  vec3(0.3483, 0.0230, 1.7471), vec3(0.3481, 0.0298, 1.7826), vec3(0.3362, 0.0380, 1.7721),
  vec3(0.3187, 0.0480, 1.7441), vec3(0.2908, 0.0600, 1.6692), vec3(0.2511, 0.0739, 1.5281),
  vec3(0.1954, 0.0910, 1.2876), vec3(0.1421, 0.1126, 1.0419), vec3(0.0956, 0.1390, 0.8130),
  vec3(0.0580, 0.1693, 0.6162), vec3(0.0320, 0.2080, 0.4652), vec3(0.0147, 0.2586, 0.3533),
  vec3(0.0049, 0.3230, 0.2720), vec3(0.0024, 0.4073, 0.2123), vec3(0.0093, 0.5030, 0.1582),
  vec3(0.0291, 0.6082, 0.1117), vec3(0.0633, 0.7100, 0.0782), vec3(0.1096, 0.7932, 0.0573),
  vec3(0.1655, 0.8620, 0.0422), vec3(0.2257, 0.9149, 0.0298), vec3(0.2904, 0.9540, 0.0203),
  vec3(0.3597, 0.9803, 0.0134), vec3(0.4334, 0.9950, 0.0087), vec3(0.5121, 1.0000, 0.0057),
  vec3(0.5945, 0.9950, 0.0039), vec3(0.6784, 0.9786, 0.0027), vec3(0.7621, 0.9520, 0.0021),
  vec3(0.8425, 0.9154, 0.0018), vec3(0.9163, 0.8700, 0.0017), vec3(0.9786, 0.8163, 0.0014),
  vec3(1.0263, 0.7570, 0.0011), vec3(1.0567, 0.6949, 0.0010), vec3(1.0622, 0.6310, 0.0008),
  vec3(1.0456, 0.5668, 0.0006), vec3(1.0026, 0.5030, 0.0003), vec3(0.9384, 0.4412, 0.0002),
  vec3(0.8544, 0.3810, 0.0002), vec3(0.7514, 0.3210, 0.0001), vec3(0.6424, 0.2650, 0.0000),
  vec3(0.5419, 0.2170, 0.0000), vec3(0.4479, 0.1750, 0.0000), vec3(0.3608, 0.1382, 0.0000),
  vec3(0.2835, 0.1070, 0.0000), vec3(0.2187, 0.0816, 0.0000), vec3(0.1649, 0.0610, 0.0000),
  vec3(0.1212, 0.0446, 0.0000), vec3(0.0874, 0.0320, 0.0000), vec3(0.0636, 0.0232, 0.0000),
  vec3(0.0468, 0.0170, 0.0000), vec3(0.0329, 0.0119, 0.0000), vec3(0.0227, 0.0082, 0.0000),
  vec3(0.0158, 0.0057, 0.0000), vec3(0.0114, 0.0041, 0.0000), vec3(0.0081, 0.0029, 0.0000),
  vec3(0.0058, 0.0021, 0.0000), vec3(0.0041, 0.0015, 0.0000), vec3(0.0029, 0.0010, 0.0000),
  vec3(0.0020, 0.0007, 0.0000), vec3(0.0014, 0.0005, 0.0000), vec3(0.0010, 0.0004, 0.0000),
  vec3(0.0007, 0.0002, 0.0000), vec3(0.0005, 0.0002, 0.0000), vec3(0.0003, 0.0001, 0.0000),
  vec3(0.0002, 0.0001, 0.0000), vec3(0.0002, 0.0001, 0.0000), vec3(0.0001, 0.0000, 0.0000),
  vec3(0.0001, 0.0000, 0.0000), vec3(0.0001, 0.0000, 0.0000), vec3(0.0000, 0.0000, 0.0000));

vec4 node_wavelength(float lambda, vec3 xyz_to_r, vec3 xyz_to_g, vec3 xyz_to_b)
{
  float ii = (lambda - 380.0) * (1.0 / 5.0);
  int i = int(ii);
  vec3 xyz = vec3(0.0);
  if (i >= 0 && i < 80) {
    xyz = mix(CIE_COLOR_MATCH[i], CIE_COLOR_MATCH[i + 1], ii - float(i));
  }
  vec3 rgb = vec3(dot(xyz_to_r, xyz), dot(xyz_to_g, xyz), dot(xyz_to_b, xyz)) * (1.0 / 2.52);
  return vec4(max(rgb, 0.0), 1.0);
}
