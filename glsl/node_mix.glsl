/* The Mix node (ShaderNodeMix) and its colour blend modes, one function per mode, as Cycles'
 * svm/color_util.h evaluates them: t the factor (clamped to [0, 1] first where the node says
 * so), c1 = A, c2 = B. */

vec3 mix_blend(float t, vec3 c1, vec3 c2) { return mix(c1, c2, t); }
vec3 mix_add(float t, vec3 c1, vec3 c2) { return mix(c1, c1 + c2, t); }
vec3 mix_multiply(float t, vec3 c1, vec3 c2) { return mix(c1, c1 * c2, t); }
vec3 mix_subtract(float t, vec3 c1, vec3 c2) { return mix(c1, c1 - c2, t); }
vec3 mix_difference(float t, vec3 c1, vec3 c2) { return mix(c1, abs(c1 - c2), t); }
vec3 mix_exclusion(float t, vec3 c1, vec3 c2) { return max(mix(c1, c1 + c2 - 2.0 * c1 * c2, t), 0.0); }
vec3 mix_darken(float t, vec3 c1, vec3 c2) { return mix(c1, min(c1, c2), t); }
vec3 mix_lighten(float t, vec3 c1, vec3 c2) { return mix(c1, max(c1, c2), t); }

vec3 mix_screen(float t, vec3 c1, vec3 c2)
{
  return vec3(1.0) - (vec3(1.0 - t) + t * (vec3(1.0) - c2)) * (vec3(1.0) - c1);
}

float mix_overlay_channel(float t, float c1, float c2)
{
  float tm = 1.0 - t;
  return c1 < 0.5 ? c1 * (tm + 2.0 * t * c2) : 1.0 - (tm + 2.0 * t * (1.0 - c2)) * (1.0 - c1);
}

vec3 mix_overlay(float t, vec3 c1, vec3 c2)
{
  return vec3(mix_overlay_channel(t, c1.r, c2.r), mix_overlay_channel(t, c1.g, c2.g),
              mix_overlay_channel(t, c1.b, c2.b));
}

float mix_divide_channel(float t, float c1, float c2)
{
  return c2 != 0.0 ? (1.0 - t) * c1 + t * c1 / c2 : c1;
}

vec3 mix_divide(float t, vec3 c1, vec3 c2)
{
  return vec3(mix_divide_channel(t, c1.r, c2.r), mix_divide_channel(t, c1.g, c2.g),
              mix_divide_channel(t, c1.b, c2.b));
}

float mix_dodge_channel(float t, float c1, float c2)
{
  if (c1 == 0.0) {
    return c1;
  }
  float tmp = 1.0 - t * c2;
  return (tmp <= 0.0 || c1 / tmp > 1.0) ? 1.0 : c1 / tmp;
}

vec3 mix_dodge(float t, vec3 c1, vec3 c2)
{
  return vec3(mix_dodge_channel(t, c1.r, c2.r), mix_dodge_channel(t, c1.g, c2.g),
              mix_dodge_channel(t, c1.b, c2.b));
}

float mix_burn_channel(float t, float c1, float c2)
{
  float tmp = (1.0 - t) + t * c2;
  if (tmp <= 0.0) {
    return 0.0;
  }
  return clamp(1.0 - (1.0 - c1) / tmp, 0.0, 1.0);
}

vec3 mix_burn(float t, vec3 c1, vec3 c2)
{
  return vec3(mix_burn_channel(t, c1.r, c2.r), mix_burn_channel(t, c1.g, c2.g),
              mix_burn_channel(t, c1.b, c2.b));
}

/* HUE and COLOR: c1 given c2's hue (and, for COLOR, its saturation), where c2 has a hue */
vec3 mix_take_hue(float t, vec3 c1, vec3 c2, bool with_saturation)
{
  vec3 hsv2 = color_rgb_to_hsv(c2);
  if (hsv2.y == 0.0) {
    return c1;
  }
  vec3 hsv = color_rgb_to_hsv(c1);
  hsv.x = hsv2.x;
  if (with_saturation) {
    hsv.y = hsv2.y;
  }
  return mix(c1, color_hsv_to_rgb(hsv), t);
}

vec3 mix_hue(float t, vec3 c1, vec3 c2) { return mix_take_hue(t, c1, c2, false); }

vec3 mix_saturation(float t, vec3 c1, vec3 c2)
{
  vec3 hsv = color_rgb_to_hsv(c1);
  if (hsv.y == 0.0) {
    return c1;
  }
  hsv.y = (1.0 - t) * hsv.y + t * color_rgb_to_hsv(c2).y;
  return color_hsv_to_rgb(hsv);
}

vec3 mix_value(float t, vec3 c1, vec3 c2)
{
  vec3 hsv = color_rgb_to_hsv(c1);
  hsv.z = (1.0 - t) * hsv.z + t * color_rgb_to_hsv(c2).z;
  return color_hsv_to_rgb(hsv);
}

vec3 mix_color(float t, vec3 c1, vec3 c2) { return mix_take_hue(t, c1, c2, true); }

vec3 mix_soft_light(float t, vec3 c1, vec3 c2)
{
  vec3 screen = vec3(1.0) - (vec3(1.0) - c2) * (vec3(1.0) - c1);
  return (1.0 - t) * c1 + t * ((vec3(1.0) - c1) * c2 * c1 + c1 * screen);
}

vec3 mix_linear_light(float t, vec3 c1, vec3 c2) { return c1 + t * (2.0 * c2 - vec3(1.0)); }
