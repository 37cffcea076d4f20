/* A|B compare of two renders of the same frame (two models): SL_COMPARE_SPLIT shows A left of
 * the split position and B right of it, with a 1-pixel divider; SL_COMPARE_DIFFERENCE shows the
 * luminance difference |A - B| as a false-colour heat map scaled to `range`, with the scale
 * (0 -> range) as a strip along the bottom rows. The heat map is written display-linear (its sRGB
 * colours decoded), so Blender's Standard view shows the colours of the map exactly. */

/* Mikhailov 2019, "Turbo, An Improved Rainbow Colormap for Visualization" (Google): his
 * polynomial approximation of the map, t in [0, 1] -> display-linear-ish rgb. */
vec3 turbo(float t)
{
  const vec4 kr4 = vec4(0.13572138, 4.61539260, -42.66032258, 132.13108234);
  const vec4 kg4 = vec4(0.09140261, 2.19418839, 4.84296658, -14.18503333);
  const vec4 kb4 = vec4(0.10667330, 12.64194608, -60.58204836, 110.36276771);
  const vec2 kr2 = vec2(-152.94239396, 59.28637943);
  const vec2 kg2 = vec2(4.27729857, 2.82956604);
  const vec2 kb2 = vec2(-89.90310912, 27.34824973);
  t = clamp(t, 0.0, 1.0);
  vec4 v4 = vec4(1.0, t, t * t, t * t * t);
  vec2 v2 = v4.zw * v4.z;
  /* the polynomial overshoots [0, 1] by a few percent at the ends: clamp (no negative output) */
  return clamp(vec3(dot(v4, kr4) + dot(v2, kr2), dot(v4, kg4) + dot(v2, kg2), dot(v4, kb4) + dot(v2, kb2)),
               0.0, 1.0);
}

float compare_luminance(vec3 c)
{
  return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

void main()
{
  ivec2 px = ivec2(gl_FragCoord.xy);
  vec4 a = texelFetch(image_a, px, 0);
  vec4 b = texelFetch(image_b, px, 0);
#if defined(SL_COMPARE_DIFFERENCE)
  float width = float(textureSize(image_a, 0).x);
  if (px.y < SL_LEGEND_ROWS) {
    /* the scale: left edge 0, right edge `range` */
    frag_color = vec4(srgb_to_linear(turbo((float(px.x) + 0.5) / width)), 1.0);
    return;
  }
  float d = abs(compare_luminance(a.rgb) - compare_luminance(b.rgb));
  frag_color = vec4(srgb_to_linear(turbo(d / max(range, 1e-20))), 1.0);
#else
  int edge = int(floor(split * float(textureSize(image_a, 0).x)));
  if (px.x == edge) {
    frag_color = vec4(1.0, 1.0, 1.0, 1.0); /* the divider */
    return;
  }
  frag_color = px.x < edge ? a : b;
#endif
}
