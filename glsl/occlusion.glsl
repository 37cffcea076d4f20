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

/* The trace runs at 1 / SL_OCCLUSION_SCALE of the pixels in each direction (1 or 2): a texel of
 * the trace (a cell) stands for a SL_OCCLUSION_SCALE^2 block of pixels and traces one of them,
 * its corner moving with the cell ((x, y) mod 2) so that thin surfaces are traced somewhere. */
ivec2 traced_texel(ivec2 cell)
{
#if SL_OCCLUSION_SCALE > 1
  ivec2 size = ivec2(occlusion.params.zw);
  return min(cell * SL_OCCLUSION_SCALE + (cell & 1), size - 1);
#else
  return cell;
#endif
}
