/* A shadow map's layer: object space -> world space -> the layer's clip space. A caster whose
 * coverage is tested (SL_SHADOW_GRAPH: a node graph's) hands on what its graph reads of the mesh,
 * as the shading programs do (glsl/mesh_varyings.glsl). */

void main()
{
  ObjectData object = objects.object[object_index];
  vec4 world = object.model * vec4(pos, 1.0);
  world_position = world.xyz;
#ifdef SL_SHADOW_GRAPH
  write_mesh_varyings(object);
#endif
  gl_Position = shadow_view_projection * world;
}
