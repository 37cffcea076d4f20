/* The world's lighting field baked into one equirectangular image (each texel: the radiance in
 * its centre's direction), the input of the downsampled levels, the spherical harmonics and the
 * prefiltered levels. */

void main()
{
  frag_color = vec4(world_radiance(equirect_direction(gl_FragCoord.xy / target.xy)), 1.0);
}
