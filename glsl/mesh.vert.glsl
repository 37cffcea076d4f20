/* Object space -> world space -> clip space. Normals go through the inverse transpose so that
 * non-uniform scale keeps them perpendicular to the surface. */

void main()
{
  vec4 world = object.model * vec4(pos, 1.0);
  world_position = world.xyz;
  world_normal = mat3(object.normal_matrix) * nor;
  gl_Position = frame.view_proj * world;
}
