/* The interleaved occlusion's resolve (glsl/gtao.frag.glsl traces a quarter of the slices per
 * pixel, by a 2 x 2 pattern): each pixel merges its 3 x 3 neighbourhood with the tent weights
 * 1, 1/2, 1/4 (centre, edge, corner), which weigh the pattern's four classes equally, so a pixel
 * inside a surface ends with every slice. A neighbour on another surface (off the pixel's tangent
 * plane by more than PLANE_TOLERANCE of its depth, or its normal turned by more than acos
 * NORMAL_TOLERANCE) or the sky is left out, and the rest renormalised: at silhouettes a pixel
 * keeps fewer slices rather than another surface's occlusion.
 * At half resolution (SL_OCCLUSION_SCALE 2) the neighbourhood is the 2 x 2 cells of the trace
 * nearest the pixel's centre (its own and the three beside it towards the pixel's corner of
 * it), equally weighted: any 2 x 2 cells hold the pattern's four classes once each; each is
 * tested at the pixel it traced (glsl/occlusion.glsl). Four reads a pixel instead of nine: the
 * resolve 9.5 -> 4.4 ms at 640 x 360 (material_grid); against Cycles the presets' FLIP moved
 * 0.0322 -> 0.0323 (material_grid), 0.0194 -> 0.0194 (roughness_sweep), 0.0646 -> 0.0645
 * (world), and the occlusion tests' errors by 0.03-0.09 points (tests/test_world_light.py's notes).
 * Each neighbour's test is written without branches, its view position from its view depth (no
 * division: glsl/occlusion.glsl's view_at): on the CPU rasteriser every branch's both sides run.
 * The visibility is the ratio of the merged sums (visible over unoccluded arcs, glsl/gtao.frag.glsl).
 * raw: the trace (xyz bent-normal sum, w the two sums packed); traced_cells: each cell's traced
 * pixel's normal and depth (the trace's second output: one texel a neighbour, not two); depths,
 * normal_map as the trace's, for the pixel itself.
 * Output: xyz the world-space bent normal (the normal where nothing is visible), w visibility. */

#define PLANE_TOLERANCE 0.02
#define NORMAL_TOLERANCE 0.9

void main()
{
  ivec2 texel = ivec2(gl_FragCoord.xy);
  float z = texelFetch(depths, texel, 0).r;
  if (z >= 0.0) {
    frag_color = vec4(1.0); /* the sky: nothing to occlude */
    return;
  }
  vec3 N = texelFetch(normal_map, texel, 0).xyz;
  vec2 to_ndc = 2.0 / occlusion.params.zw;
  vec3 P = view_at((vec2(texel) + 0.5) * to_ndc - 1.0, z);
  vec3 Nv = mat3(occlusion.view) * N;
  float tolerance = PLANE_TOLERANCE * abs(P.z);
  vec3 bent = vec3(0.0);
  vec2 sums = vec2(0.0); /* visible, unoccluded */
  ivec2 cells = ivec2(textureSize(raw, 0));
#if SL_OCCLUSION_SCALE > 1
  /* the cells from the one before the pixel's own on its side of the cell's centre */
  ivec2 own = texel / SL_OCCLUSION_SCALE - 1 + (texel & 1);
  for (int dy = 0; dy <= 1; dy++) {
    for (int dx = 0; dx <= 1; dx++) {
      float w = 1.0;
#else
  ivec2 own = texel;
  for (int dy = -1; dy <= 1; dy++) {
    for (int dx = -1; dx <= 1; dx++) {
      float w = (dx == 0 ? 1.0 : 0.5) * (dy == 0 ? 1.0 : 0.5);
#endif
      ivec2 c = clamp(own + ivec2(dx, dy), ivec2(0), cells - 1);
      ivec2 t = traced_texel(c);
      vec4 traced = texelFetch(traced_cells, c, 0); /* xyz: the normal at t, w: its view depth */
      vec3 Q = view_at((vec2(t) + 0.5) * to_ndc - 1.0, traced.w);
      bool keep = c == own + ivec2(dx, dy) &&
                  (t == texel || (traced.w < 0.0 && dot(traced.xyz, N) >= NORMAL_TOLERANCE &&
                                  abs(dot(Q - P, Nv)) <= tolerance));
      w = keep ? w : 0.0;
      vec4 s = texelFetch(raw, c, 0);
      bent += w * s.xyz;
      sums += w * unpackHalf2x16(floatBitsToUint(s.w));
    }
  }
  float len2 = dot(bent, bent);
  frag_color = vec4(len2 > 1e-12 ? bent * inversesqrt(len2) : N,
                    sums.y > 1e-6 ? clamp(sums.x / sums.y, 0.0, 1.0) : 1.0);
}
