/* A shadow map's depth: the distance from the light's centre (a perspective layer) over the
 * layer's far distance, so that glsl/shadows.glsl compares distances in metres; an orthographic
 * layer's depth (SL_SHADOW_ORTHOGRAPHIC) is already its distance from the near plane over the far
 * one, the rasteriser's own: not written here, so the depth test runs before this shader (unless
 * the caster's coverage is tested, SL_SHADOW_COVERAGE: glsl/shadow_coverage.glsl discards the
 * fragments that let the light through). */

void main()
{
#ifdef SL_SHADOW_COVERAGE
  if (shadow_coverage() < shadow_coverage_threshold()) {
    discard;
  }
#endif
#ifndef SL_SHADOW_ORTHOGRAPHIC
  gl_FragDepth = length(world_position - light_origin.xyz) * light_origin.w;
#endif
  frag_color = vec4(0.0);
}
