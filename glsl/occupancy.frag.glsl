/* Occupancy of a peeled transparency layer, one output texel per SL_BLOCK x SL_BLOCK block of the
 * layer: 1 where any texel of the block holds a peeled fragment (its depth below the cleared 1.0),
 * else 0. Read back, it tells the renderer whether another peeling pass can find anything. */

void main()
{
  ivec2 size = textureSize(layer_depth, 0);
  ivec2 base = ivec2(gl_FragCoord.xy) * SL_BLOCK;
  float nearest = 1.0;
  for (int y = 0; y < SL_BLOCK; y++) {
    for (int x = 0; x < SL_BLOCK; x++) {
      nearest = min(nearest, texelFetch(layer_depth, min(base + ivec2(x, y), size - 1), 0).r);
    }
  }
  frag_color = vec4(nearest < 1.0 ? 1.0 : 0.0);
}
