/* One prefiltered level of the atlas (rect: x, y, width, height in texels; drawn with the
 * viewport set to it): the environment seen by a GGX lobe of alpha = r^2 around each texel's
 * direction, with n = v = r as the split sum assumes (Karis 2013), from the lobe's samples with
 * n.l > 0 (Hammersley points, weighted by n.l). Filtered importance sampling (Krivanek &
 * Colbert 2008, "Real-time Shading with Filtered Importance Sampling"): each sample reads the
 * downsampled level whose texels cover the solid angle the sample stands for, 1 / (N pdf),
 * trilinearly from the chain (all levels in one texture, rectangles in chain.rect) -- a bright
 * small source is spread over the lobe instead of sparkling.
 * The texels of a row see one lobe turned about the pole by their longitude, which is u: the
 * samples come per row from `samples`, params.z of them, each as the two reads of the chain
 * that chain_lookup_uv would make for it (addon/reference/environment.py prefilter_reads: level k's x
 * origin, width and y in the texture, the weight on it, and the same for level k + 1, half as
 * wide), so that a texel computes only where in the row it reads; two more rows about the poles
 * give the border rows above and below the level their 2 P - T (environment.glsl
 * bordered_level_pole). alpha 0 (params.x) copies chain level params.y. */

/* The lobe mean of row `row` of the sample table (the level's rows, then the north and the south
 * pole) turned to longitude u: per sample, levels k and k + 1 at fract(u + u offset). */
vec3 lobe_mean(int row, float u)
{
  int count = int(params.z);
  vec3 sum = vec3(0.0);
  for (int i = 0; i < count; i++) {
    vec4 a = texelFetch(samples, ivec2(2 * i, row), 0);
    vec4 b = texelFetch(samples, ivec2(2 * i + 1, row), 0);
    float f = fract(u + a.x);
    sum += textureLod(source, vec2(a.y + f * a.z, a.w), 0.0).rgb * b.x
         + textureLod(source, vec2(b.y + f * (0.5 * a.z), b.w), 0.0).rgb * b.z;
  }
  return sum;
}

void main()
{
  vec2 uv = bordered_level_uv(rect);  /* drawn with the level's border */
  float pole = bordered_level_pole(rect);
  if (params.x <= 0.0) {
    vec3 c = chain_level(source, int(params.y), uv);
    if (pole != 0.0) {  /* the chain's level reaches its pole's value at v = 0 or 1 */
      c = 2.0 * chain_level(source, int(params.y), vec2(uv.x, 0.5 + 0.5 * pole)) - c;
    }
    frag_color = vec4(c, 1.0);
    return;
  }
  int row = clamp(int(gl_FragCoord.y - rect.y), 0, int(rect.w) - 1);
  vec3 c = lobe_mean(row, uv.x);
  if (pole != 0.0) {
    c = 2.0 * lobe_mean(int(rect.w) + (pole > 0.0 ? 0 : 1), uv.x) - c;
  }
  frag_color = vec4(c, 1.0);
}
