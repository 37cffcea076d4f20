/* The world's lighting field baked into one equirectangular level (each texel: the radiance in
 * its centre's direction), the input of the downsampled levels, the irradiance and the
 * prefiltered levels; params.x = 1 clamps the brightest texels (split off as suns).
 *
 * Drawn into its rectangle `rect` of the chain texture with the level's border (the viewport one
 * texel wider on every side; addon/reference/environment.py chain_layout): a border column is the opposite
 * column's direction baked again (the same numbers, so the same value), a border row above or
 * below holds 2 P - the edge row's texel, P the edge row's mean, from `poles` (texel 1 north, 0
 * south; environment.glsl bordered_level_pole). A level wider than the chain's widest is baked
 * on its own (rect its whole target, no border) and halved down to it.
 *
 * SL_POLES: the pass that makes `poles` (a 2 x 1 target): each texel the mean of the world's
 * radiance over the texel centres of the level's bottom (x = 0) or top (x = 1) row, taken in the
 * same order and from the same directions as the bake's texels there. */

vec3 baked(vec2 uv)
{
  return world_radiance(equirect_direction(uv), params.x > 0.5);
}

void main()
{
#ifdef SL_POLES
  float h = rect.w;
  int width = int(rect.z);
  float v = gl_FragCoord.x < 1.0 ? 0.5 / h : 1.0 - 0.5 / h;
  vec3 sum = vec3(0.0);
  for (int x = 0; x < width; x++) {
    sum += baked(vec2((float(x) + 0.5) / rect.z, v));
  }
  frag_color = vec4(sum / rect.z, 1.0);
#else
  vec3 c = baked(bordered_level_uv(rect));
  float pole = bordered_level_pole(rect);
  if (pole != 0.0) {
    c = 2.0 * texelFetch(poles, ivec2(pole > 0.0 ? 1 : 0, 0), 0).rgb - c;
  }
  frag_color = vec4(c, 1.0);
#endif
}
