/* The occlusion pass's depths, one texel per sample read, as view depths (glsl/occlusion.glsl):
 * x the nearest surface's, y where the ray leaves that object (the nearest face turned away
 * behind it); SKY_Z where there is no surface, and in y where the way out is unknown: no such
 * face (a floor, an open surface) or the surface seen from inside. */

void main()
{
  ivec2 texel = ivec2(gl_FragCoord.xy);
  float front = texelFetch(depth_map, texel, 0).r;
  float back = texelFetch(back_depth_map, texel, 0).r;
  bool outside = texelFetch(facing_map, texel, 0).a > 0.75;
  frag_color = vec4(front < 1.0 ? view_z(front) : SKY_Z,
                    front < 1.0 && outside && back > front ? view_z(back) : SKY_Z, 0.0, 1.0);
}
