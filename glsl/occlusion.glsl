/* The occlusion pass's camera helpers (glsl/gtao.frag.glsl, glsl/occlusion_resolve.frag.glsl):
 * view-space positions from depth-buffer values, through the OcclusionData block. */

vec3 view_position(vec2 uv, float d)
{
  vec4 p = occlusion.inverse_projection * vec4(uv * 2.0 - 1.0, d * 2.0 - 1.0, 1.0);
  return p.xyz / p.w;
}

/* The view-space depth (z) at a depth-buffer value: perspective and orthographic projections
 * alike map depth to z without x and y. */
float view_z(float d)
{
  mat4 ip = occlusion.inverse_projection;
  float z = d * 2.0 - 1.0;
  return (ip[2][2] * z + ip[3][2]) / (ip[2][3] * z + ip[3][3]);
}
