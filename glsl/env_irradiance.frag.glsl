/* The irradiance map (drawn with the viewport set to its rectangle of the atlas): for each
 * texel's normal n, E(n) = sum over the texels of a downsampled environment of
 * L max(n.l, 0) dOmega -- the cosine convolution computed exactly for that image (no spherical
 * harmonic truncation), the downsampling averaging each texel's light over its solid angle. */

void main()
{
  vec2 uv = (gl_FragCoord.xy - rect.xy) / rect.zw;
  uv = vec2(fract(uv.x), clamp(uv.y, 0.5 / rect.w, 1.0 - 0.5 / rect.w));  /* the border, as the levels' */
  vec3 n = equirect_direction(uv);
  ivec4 src = ivec4(chain.rect[int(params.y)]);
  float dphi = 2.0 * PI / float(src.z);
  vec3 sum = vec3(0.0);
  for (int y = 0; y < src.w; y++) {
    /* the row's solid angle per texel: (2 pi / w)(cos theta_top - cos theta_bottom) */
    float z0 = -cos(PI * float(y) / float(src.w));
    float z1 = -cos(PI * float(y + 1) / float(src.w));
    float omega = dphi * (z1 - z0);
    for (int x = 0; x < src.z; x++) {
      vec3 l = equirect_direction((vec2(x, y) + 0.5) / vec2(src.zw));
      float c = dot(n, l);
      if (c > 0.0) {
        sum += texelFetch(source, src.xy + ivec2(x, y), 0).rgb * (c * omega);
      }
    }
  }
  frag_color = vec4(sum, 1.0);
}
