/* Each pixel's deferred group as a depth (deferred_depth), for the groups' passes to test against
 * (glsl/deferred.vert.glsl): the far plane where no deferred group's surface is (the G-buffer's
 * group -1: none, or shaded forward). */

void main()
{
  float group = texelFetch(gbuffer_normal, ivec2(gl_FragCoord.xy), 0).w;
  gl_FragDepth = group >= 0.0 ? deferred_depth(int(group)) : 1.0;
}
