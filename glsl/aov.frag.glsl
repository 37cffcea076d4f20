/* A material's AOV Output (SL_AOV): the value its node graph gives the view layer's AOV at the
 * nearest surface, as Cycles writes it for a camera ray's first hit (a Color AOV's colour, alpha
 * 1; a Value AOV's value in x), no shading. */

void main()
{
  bool outward = facing_outward();
  vec3 n = shading_normal(world_position);
  n = outward ? n : -n;
  vec4 color;
  float value;
  material_aov(graph_inputs(n, view_direction(world_position), !outward), color, value);
#ifdef SL_AOV_VALUE
  frag_color = vec4(value, 0.0, 0.0, 1.0);
#else
  frag_color = vec4(color.rgb, 1.0);
#endif
}
