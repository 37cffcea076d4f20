/* What a mesh's vertex stage hands the fragment stage beside its position: the world normal
 * (through the inverse transpose, so that non-uniform scale keeps it perpendicular to the
 * surface), the active UV map's coordinates, the tangent (a mirror reverses the bitangent too:
 * B = sign x det-sign x (N x T)), and a node graph's attributes and object-space position where its
 * program reads them. glsl/mesh.vert.glsl's, and glsl/shadow.vert.glsl's for a caster whose
 * coverage a node graph gives. */
void write_mesh_varyings(ObjectData object)
{
  world_normal = mat3(object.normal_matrix) * nor;
  world_uv = uv;
  world_tangent = vec4(mat3(object.model) * tangent.xyz, tangent.w * object.normal_matrix[3][3]);
#ifdef SL_PASS_ATTRIBUTES
  SL_PASS_ATTRIBUTES /* a node graph's attributes, as the mesh's corners hold them */
#endif
#if defined(SL_GRAPH_OBJECT) || defined(SL_GRAPH_GENERATED)
  object_position = pos;
#endif
}
