/* A shadow map's layer: object space -> world space -> the layer's clip space. A caster whose
 * coverage is tested (SL_SHADOW_GRAPH: a node graph's) hands on what its graph reads of the mesh,
 * as glsl/mesh.vert.glsl does for the shading programs. */

void main()
{
  ObjectData object = objects.object[object_index];
  vec4 world = object.model * vec4(pos, 1.0);
  world_position = world.xyz;
#ifdef SL_SHADOW_GRAPH
  world_normal = mat3(object.normal_matrix) * nor;
  world_uv = uv;
  /* a mirror reverses the bitangent too (mesh.vert.glsl) */
  world_tangent = vec4(mat3(object.model) * tangent.xyz, tangent.w * object.normal_matrix[3][3]);
#  ifdef SL_PASS_ATTRIBUTES
  SL_PASS_ATTRIBUTES /* a node graph's attributes, as the mesh's corners hold them */
#  endif
#  if defined(SL_GRAPH_OBJECT) || defined(SL_GRAPH_GENERATED)
  object_position = pos;
#  endif
#endif
  gl_Position = shadow_view_projection * world;
}
