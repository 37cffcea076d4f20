/* What is behind the glass, for the screen-space refraction (glsl/transmission.glsl): the opaque
 * scene and the world copied after they are drawn (addon/frame/passes.py's RefractionPass), and
 * blurred levels of it for rough glass.
 * SL_REFRACTION_COPY: the scene target's colour (`source`) with its depth (`source_depth`) in alpha.
 * SL_REFRACTION_DOWN: a level of half the size of `source`: each texel the mean of four bilinear
 *   reads one source texel off its centre along both axes, a 4 x 4 tent over the source (the reads
 *   kept inside it: the edge texels repeat).
 * SL_REFRACTION_PACK: `source` copied into its rectangle of the levels' texture (origin offset.xy). */

void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
#if defined(SL_REFRACTION_COPY)
  frag_color = vec4(texelFetch(source, p, 0).rgb, texelFetch(source_depth, p, 0).r);
#elif defined(SL_REFRACTION_DOWN)
  ivec2 size = textureSize(source, 0);
  vec2 centre = 2.0 * vec2(p) + 1.0; /* the output texel's centre, in source texels */
  vec3 sum = vec3(0.0);
  for (int k = 0; k < 4; k++) {
    vec2 at = clamp(centre + vec2(k % 2 == 0 ? -1.0 : 1.0, k < 2 ? -1.0 : 1.0), vec2(0.5), vec2(size) - 0.5);
    /* bilinear by hand: the four texels around `at` (no filtering state to rely on) */
    vec2 x = at - 0.5;
    ivec2 i0 = ivec2(floor(x));
    vec2 f = x - vec2(i0);
    ivec2 i1 = min(i0 + 1, size - 1);
    vec3 a = mix(texelFetch(source, i0, 0).rgb, texelFetch(source, ivec2(i1.x, i0.y), 0).rgb, f.x);
    vec3 b = mix(texelFetch(source, ivec2(i0.x, i1.y), 0).rgb, texelFetch(source, i1, 0).rgb, f.x);
    sum += mix(a, b, f.y);
  }
  frag_color = vec4(0.25 * sum, 1.0);
#else
  frag_color = texelFetch(source, p - ivec2(offset.xy), 0);
#endif
}
