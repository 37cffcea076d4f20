/* The occlusion pass's depths, one texel per sample read: x the nearest surface's depth, y the
 * depth where the ray leaves that object (the nearest face turned away behind it), or 1 where
 * that is unknown: no such face (a floor, an open surface) or the surface seen from inside. */

void main()
{
  ivec2 texel = ivec2(gl_FragCoord.xy);
  float front = texelFetch(depth_map, texel, 0).r;
  float back = texelFetch(back_depth_map, texel, 0).r;
  bool outside = texelFetch(facing_map, texel, 0).a > 0.75;
  frag_color = vec4(front, outside && back > front ? back : 1.0, 0.0, 1.0);
}
