/* The irradiance map (drawn with the viewport set to its rectangle of the atlas): for each
 * texel's normal n, E(n) = sum over the texels of a downsampled environment of
 * L max(n.l, 0) dOmega -- the cosine convolution computed exactly for that image (no spherical
 * harmonic truncation), the downsampling averaging each texel's light over its solid angle. */

vec3 irradiance(vec3 n)
{
  ivec4 src = ivec4(chain.rect[int(params.y)]);
  float dphi = 2.0 * PI / float(src.z);
  /* a row's texel directions (equirect_direction at the texel centres) turn by -dphi from one
   * texel to the next: their longitude's cosine and sine follow by that rotation instead of a
   * cos and a sin per texel (float32 drift over a row: ~1e-6) */
  float cd = cos(dphi), sd = sin(dphi);
  float c0 = cos(PI - 0.5 * dphi), s0 = sin(PI - 0.5 * dphi);
  vec3 sum = vec3(0.0);
  for (int y = 0; y < src.w; y++) {
    /* the row's solid angle per texel: (2 pi / w)(cos theta_top - cos theta_bottom) */
    float z0 = -cos(PI * float(y) / float(src.w));
    float z1 = -cos(PI * float(y + 1) / float(src.w));
    float omega = dphi * (z1 - z0);
    float theta = PI * (1.0 - (float(y) + 0.5) / float(src.w));
    float along = n.z * cos(theta), across = sin(theta);
    float c = c0, s = s0;
    for (int x = 0; x < src.z; x++) {
      float cosine = along + across * (n.x * c + n.y * s);  /* n.l */
      sum += texelFetch(source, src.xy + ivec2(x, y), 0).rgb * (max(cosine, 0.0) * omega);
      float turned = c * cd + s * sd;
      s = s * cd - c * sd;
      c = turned;
    }
  }
  return sum;
}

void main()
{
  vec3 e = irradiance(equirect_direction(bordered_level_uv(rect)));  /* drawn with its border */
  float pole = bordered_level_pole(rect);
  if (pole != 0.0) {  /* the border beyond a pole: 2 P - T (environment.glsl bordered_level_pole) */
    e = 2.0 * irradiance(vec3(0.0, 0.0, pole)) - e;
  }
  frag_color = vec4(e, 1.0);
}
