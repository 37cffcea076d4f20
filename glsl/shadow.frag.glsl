/* A shadow map's depth: the distance from the light's centre (a perspective layer) over the
 * layer's far distance, so that glsl/shadows.glsl compares distances in metres; an orthographic
 * layer's depth is already its distance from the near plane over the far one. */

void main()
{
  if (light_origin.w > 0.0) {
    gl_FragDepth = length(world_position - light_origin.xyz) * light_origin.w;
  }
  else {
    gl_FragDepth = gl_FragCoord.z;
  }
  frag_color = vec4(0.0);
}
