/* A deferred group's full-screen triangle (passes.OpaquePass), at the depth the group-depth pass
 * wrote where the group's surfaces are (glsl/group_depth.frag.glsl, deferred_depth): drawn with the
 * depth test EQUAL against it, the rasteriser leaves every other pixel unshaded, which a discard
 * in the program did not (on the CPU rasteriser a pass of discarded pixels cost 24 ms on softbox
 * at 640x360, behind a failing depth test 0.6 ms). */

void main()
{
  gl_Position = vec4(pos, 2.0 * deferred_depth(deferred_group) - 1.0, 1.0);
}
