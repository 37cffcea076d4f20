/* What camera rays see where no surface is: the world along each pixel's ray (through the
 * inverse view-projection: a perspective camera's rays fan out, an orthographic camera's are
 * parallel, as in Cycles). The empirical models clamp it to [0, 1] like everything they output. */

void main()
{
  vec2 ndc = gl_FragCoord.xy / viewport.xy * 2.0 - 1.0;
  vec4 near = inverse_view_projection * vec4(ndc, -1.0, 1.0);
  vec4 far = inverse_view_projection * vec4(ndc, 1.0, 1.0);
  vec3 c = world_radiance(far.xyz / far.w - near.xyz / near.w, false);
#ifdef SL_CLAMP
  c = clamp(c, 0.0, 1.0);
#endif
#ifdef SL_HALF_TARGET
  c = min(c, vec3(65504.0));
#endif
  frag_color = vec4(c, 1.0);
}
