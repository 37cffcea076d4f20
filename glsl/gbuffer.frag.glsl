/* The G-buffer of the opaque surfaces shaded deferred (addon/frame/passes.py's OpaquePass): per pixel the
 * nearest surface's world position, its normal facing the viewer and its flat face's normal, as
 * glsl/mesh.frag.glsl's forward main computes them, in float32, so that the deferred program
 * shades exactly what the forward one would. frag_color: position, w the material's row in the
 * material table; gbuffer_normal: w the group of the program that shades it (gbuffer.y);
 * gbuffer_face: the receiver's plane for shadow lookups, w 1 where the surface is seen from
 * outside and 0.5 from inside (glsl/prepass.frag.glsl's alpha: the occlusion pass draws this in
 * the prepass's place). Materials with image maps are shaded forward (their group -1: no
 * deferred program claims the pixel). */

void main()
{
  vec3 n = shading_normal(world_position);
  vec3 ng = face_normal(world_position, n);
  bool outward = facing_outward();
  frag_color = vec4(world_position, float(gbuffer.x));
  gbuffer_normal = vec4(outward ? n : -n, float(gbuffer.y));
  gbuffer_face = vec4(ng, outward ? 1.0 : 0.5);
}
