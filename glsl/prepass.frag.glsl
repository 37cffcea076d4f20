/* Depth and normals of the opaque surfaces, ahead of shading, for the occlusion pass: the
 * shading normal (flipped towards the viewer on back faces, as the shading does) in world space,
 * float32 as the G-buffer's (glsl/gbuffer.frag.glsl, drawn in its place for surfaces shaded
 * deferred), alpha 1 where the surface is seen from outside and 0.5 from inside. With SL_BACK_FACES,
 * only the faces turned away from the viewer, depth alone: where rays leave the objects. With
 * SL_DEPTH_ONLY, the depth alone, into a target without colour (the prepass ahead of costly
 * shading where nothing reads normals): nothing computed here. */

void main()
{
#if defined(SL_DEPTH_ONLY)
  frag_color = vec4(0.0);
#elif defined(SL_BACK_FACES)
  if (facing_outward()) {
    discard;
  }
  frag_color = vec4(0.0);
#else
  vec3 n = shading_normal(world_position);
  bool outward = facing_outward();
  frag_color = vec4(outward ? n : -n, outward ? 1.0 : 0.5);
#endif
}
