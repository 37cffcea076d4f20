/* Automatic exposure's reduction (addon/scene/exposure.py has the numpy twin and the metering): a frame
 * to a histogram of log2 luminance, SL_EXPOSURE_BINS bins over [SL_LOG_MIN, SL_LOG_MAX], each
 * texel (sum of log2 L, pixel count) of the pixels in that bin, in three full-screen stages:
 *   BLOCKS   frame -> one texel per `block` x `block` pixels: (sum of log2 L, pixels counted);
 *   ROWS     blocks -> (bin, block row): each block's pixels join the bin of their mean log2 L;
 *   COLUMNS  rows -> (bin, 0): the block rows summed.
 * Pixels with alpha 0 (a transparent film's background) are not counted. */

void main()
{
  ivec2 px = ivec2(gl_FragCoord.xy);
#if defined(SL_EXPOSURE_BLOCKS)
  ivec2 size = textureSize(source, 0);
  int k = int(block + 0.5);
  ivec2 start = px * k;
  ivec2 stop = min(start + ivec2(k), size);
  vec2 acc = vec2(0.0);
  for (int y = start.y; y < stop.y; y++) {
    for (int x = start.x; x < stop.x; x++) {
      vec4 c = texelFetch(source, ivec2(x, y), 0);
      if (c.a > 0.0) {
        float lum = dot(max(c.rgb, 0.0), vec3(0.2126, 0.7152, 0.0722));
        acc += vec2(log2(clamp(lum, exp2(SL_LOG_MIN), exp2(SL_LOG_MAX))), 1.0);
      }
    }
  }
  frag_color = vec4(acc, 0.0, 1.0);
#elif defined(SL_EXPOSURE_ROWS)
  int width = textureSize(source, 0).x;
  float scale = float(SL_EXPOSURE_BINS) / (SL_LOG_MAX - SL_LOG_MIN);
  vec2 acc = vec2(0.0);
  for (int x = 0; x < width; x++) {
    vec2 b = texelFetch(source, ivec2(x, px.y), 0).xy;
    if (b.y > 0.0) {
      int bin = clamp(int(floor((b.x / b.y - SL_LOG_MIN) * scale)), 0, SL_EXPOSURE_BINS - 1);
      if (bin == px.x) {
        acc += b;
      }
    }
  }
  frag_color = vec4(acc, 0.0, 1.0);
#else /* SL_EXPOSURE_COLUMNS */
  int height = textureSize(source, 0).y;
  vec2 acc = vec2(0.0);
  for (int y = 0; y < height; y++) {
    acc += texelFetch(source, ivec2(px.x, y), 0).xy;
  }
  frag_color = vec4(acc, 0.0, 1.0);
#endif
}
