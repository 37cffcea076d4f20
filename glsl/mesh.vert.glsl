/* Object space -> world space -> clip space, and what the fragment stage reads of the mesh
 * (glsl/mesh_varyings.glsl). */

void main()
{
  ObjectData object = objects.object[object_index];
  vec4 world = object.model * vec4(pos, 1.0);
  world_position = world.xyz;
  write_mesh_varyings(object);
  gl_Position = frame.view_proj * world;
}
