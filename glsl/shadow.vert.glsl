/* A shadow map's layer: object space -> world space -> the layer's clip space. */

void main()
{
  vec4 world = objects.object[object_index].model * vec4(pos, 1.0);
  world_position = world.xyz;
  gl_Position = shadow_view_projection * world;
}
