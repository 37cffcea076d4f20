/* The occlusion pass's camera helpers (glsl/gtao.frag.glsl, glsl/occlusion_resolve.frag.glsl):
 * view-space positions through the OcclusionData block. The pass's depths are view depths (z,
 * negative in front of the camera; SKY_Z where nothing is), taken once a pixel by
 * glsl/occlusion_depths.frag.glsl: a position is then a few products, where from a depth-buffer
 * value it was a matrix product and a division, at each of the trace's samples (measured: the
 * trace 17.9 -> 15.8 ms at 640x360, material_grid; the resolve 4.9 -> 4.6). */

#define SKY_Z 1.0 /* a view depth no surface has: nothing there, or unknown */

/* The view position at normalised device coordinates ndc and view depth z: on the pixel's ray
 * (perspective: its x and y in proportion to z) or parallel to the view (orthographic). */
vec3 view_at(vec2 ndc, float z)
{
  vec2 lateral = occlusion.lateral_origin.xy + ndc.x * occlusion.lateral_axes.xy +
                 ndc.y * occlusion.lateral_axes.zw;
  float scale = occlusion.params.y > 0.5 ? z : 1.0;
  return vec3(lateral * scale, z);
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
