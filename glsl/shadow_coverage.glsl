/* A partly covering caster in a shadow map (SL_SHADOW_COVERAGE): its coverage at the fragment
 * (1 - the Closure's transparency: a node graph's, SL_SHADOW_GRAPH, evaluated as the shading
 * programs evaluate it; else the material's constant Alpha) against a threshold per texel.
 *
 * Cycles' shadow rays pass through a transparent closure, the light attenuated by its
 * transparency (the product over the surfaces crossed). A depth map stores a caster or none per
 * texel, so a coverage c keeps a share c of the texels (SL_SHADOW_DITHER: a 4 x 4 ordered dither
 * of the map's texels, Bayer's matrix, c rounded to 1/16): the receivers' percentage-closer filter
 * (glsl/shadows.glsl) averages them towards the light c lets through. A mask (c 0 or 1) is exact
 * either way. Without SL_SHADOW_DITHER, a fragment casts where c >= 1/2. */

#ifdef SL_SHADOW_GRAPH
/* The graph's coverage where a shadow ray from a receiver meets the caster: Cycles' incoming
 * direction I = -ray.D points away from the light (towards the receivers), so the side the light
 * sees is the back the ray hits (backfacing), and the normal is turned towards I, as Cycles'
 * shader_setup_from_ray does for the ray's side. */
float shadow_coverage()
{
#  ifdef SL_SHADOW_ORTHOGRAPHIC
  /* the clip depth's gradient: the direction the sun's light travels */
  vec3 i = normalize(vec3(shadow_view_projection[0][2], shadow_view_projection[1][2],
                          shadow_view_projection[2][2]));
#  else
  vec3 i = normalize(world_position - light_origin.xyz);
#  endif
  bool lit_side_outward = facing_outward(); /* the outward side faces the light */
  vec3 n = shading_normal(world_position);
  n = lit_side_outward ? -n : n;
  Closure surface;
  material_graph(graph_inputs(n, i, lit_side_outward), surface);
  return clamp(1.0 - surface.transparency, 0.0, 1.0);
}
#else
/* a material of no node graph: its Alpha (the material block's) */
float shadow_coverage()
{
  return shadow_alpha;
}
#endif

#ifdef SL_SHADOW_DITHER
/* Bayer's 4 x 4 ordered-dither matrix, thresholds (k + 1/2) / 16: coverage c keeps round(16 c)
 * of each 4 x 4 block of texels, 0 none (every threshold is above 0), 1 all (every one below 1). */
const float BAYER_4[16] = float[16](0.0, 8.0, 2.0, 10.0, 12.0, 4.0, 14.0, 6.0,
                                    3.0, 11.0, 1.0, 9.0, 15.0, 7.0, 13.0, 5.0);

float shadow_coverage_threshold()
{
  ivec2 t = ivec2(gl_FragCoord.xy) & 3;
  return (BAYER_4[t.y * 4 + t.x] + 0.5) / 16.0;
}
#else
float shadow_coverage_threshold()
{
  return 0.5;
}
#endif
