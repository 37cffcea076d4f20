/* Colour helpers of the node library, as Cycles' util/color.h defines them: RGB <-> HSV (hue in
 * [0, 1); a grey has hue and saturation 0). */

vec3 color_rgb_to_hsv(vec3 rgb)
{
  float cmax = max(rgb.r, max(rgb.g, rgb.b));
  float cmin = min(rgb.r, min(rgb.g, rgb.b));
  float delta = cmax - cmin;
  float s = cmax != 0.0 ? delta / cmax : 0.0;
  float h = 0.0;
  if (s != 0.0) {
    vec3 c = (vec3(cmax) - rgb) / delta;
    if (rgb.r == cmax) {
      h = c.b - c.g;
    }
    else if (rgb.g == cmax) {
      h = 2.0 + c.r - c.b;
    }
    else {
      h = 4.0 + c.g - c.r;
    }
    h /= 6.0;
    if (h < 0.0) {
      h += 1.0;
    }
  }
  return vec3(h, s, cmax);
}

vec3 color_hsv_to_rgb(vec3 hsv)
{
  float h = hsv.x, s = hsv.y, v = hsv.z;
  if (s == 0.0) {
    return vec3(v);
  }
  if (h == 1.0) {
    h = 0.0;
  }
  h *= 6.0;
  float i = floor(h);
  float f = h - i;
  float p = v * (1.0 - s);
  float q = v * (1.0 - s * f);
  float t = v * (1.0 - s * (1.0 - f));
  if (i == 0.0) {
    return vec3(v, t, p);
  }
  if (i == 1.0) {
    return vec3(q, v, p);
  }
  if (i == 2.0) {
    return vec3(p, v, t);
  }
  if (i == 3.0) {
    return vec3(p, q, v);
  }
  if (i == 4.0) {
    return vec3(t, p, v);
  }
  return vec3(v, p, q);
}
