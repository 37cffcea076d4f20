/* Half the size of an equirectangular level (in rectangle `offset` of its texture: x, y, width,
 * height): each texel the solid-angle-weighted mean of the 2 x 2 texels it covers (a row's
 * texels span sin(theta) times the equator's solid angle), so that every level integrates to
 * the same light. */

void main()
{
#ifdef SL_COPY
  /* a level copied into its rectangle of the chain texture (offset: the rectangle's origin),
   * drawn with the viewport one texel wider on every side: the border repeats the opposite
   * column at the sides, and above and below holds 2 P - the edge row, P the edge row's mean,
   * the pole's value (environment.glsl bordered_level_pole; addon/reference/environment.py chain_layout) */
  ivec2 size = textureSize(source, 0);
  ivec2 q = ivec2(floor(gl_FragCoord.xy - offset.xy));
  q.x = q.x < 0 ? size.x - 1 : (q.x >= size.x ? 0 : q.x);
  int y = clamp(q.y, 0, size.y - 1);
  frag_color = texelFetch(source, ivec2(q.x, y), 0);
  if (y != q.y) {
    vec3 pole = vec3(0.0);
    for (int x = 0; x < size.x; x++) {
      pole += texelFetch(source, ivec2(x, y), 0).rgb;
    }
    frag_color.rgb = 2.0 * pole / float(size.x) - frag_color.rgb;
  }
  return;
#endif
  /* the source level: rectangle offset (x, y, width, height) of its texture */
  ivec2 p = ivec2(gl_FragCoord.xy) * 2;
  ivec2 at = ivec2(offset.xy) + p;
  float height = offset.w;
  vec3 sum = vec3(0.0);
  float weight = 0.0;
  for (int y = 0; y < 2; y++) {
    float w = sin(PI * (1.0 - (float(p.y + y) + 0.5) / height));
    sum += w * (texelFetch(source, at + ivec2(0, y), 0).rgb + texelFetch(source, at + ivec2(1, y), 0).rgb);
    weight += 2.0 * w;
  }
  frag_color = vec4(sum / weight, 1.0);
}
