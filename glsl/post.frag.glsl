/* Resolve and display pass. Averages the SL_SAMPLES x SL_SAMPLES texels under each output pixel
 * (an ordered-grid supersampling box filter: every sample has equal weight, exactly Cycles' Box
 * pixel filter in the limit), then, for the display output (SL_DISPLAY), exposes and tone maps. */

void main()
{
  ivec2 base = ivec2(gl_FragCoord.xy) * SL_SAMPLES;
  vec4 sum = vec4(0.0);
  for (int y = 0; y < SL_SAMPLES; y++) {
    for (int x = 0; x < SL_SAMPLES; x++) {
      sum += texelFetch(hdr_image, base + ivec2(x, y), 0);
    }
  }
  vec4 radiance = sum / float(SL_SAMPLES * SL_SAMPLES);
#ifdef SL_DISPLAY
  vec3 y = tonemap(max(radiance.rgb, 0.0) * exposure_scale);
#  ifdef SL_TRANSFER_GAMMA22
  y = transfer_gamma22(y);
#  endif
  frag_color = vec4(y, radiance.a);
#else
  frag_color = radiance;
#endif
}
