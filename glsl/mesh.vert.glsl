/* Object space -> world space -> clip space. Normals go through the inverse transpose so that
 * non-uniform scale keeps them perpendicular to the surface. */

void main()
{
  ObjectData object = objects.object[object_index];
  vec4 world = object.model * vec4(pos, 1.0);
  world_position = world.xyz;
  world_normal = mat3(object.normal_matrix) * nor;
  world_uv = uv;
  /* a mirror reverses the bitangent too: B = sign x det-sign x (N x T) */
  world_tangent = vec4(mat3(object.model) * tangent.xyz, tangent.w * object.normal_matrix[3][3]);
#ifdef SL_PASS_ATTRIBUTES
  SL_PASS_ATTRIBUTES /* a node graph's attributes, as the mesh's corners hold them */
#endif
#if defined(SL_GRAPH_OBJECT) || defined(SL_GRAPH_GENERATED)
  object_position = pos;
#endif
  gl_Position = frame.view_proj * world;
}
