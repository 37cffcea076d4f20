/* The world's lighting field baked into one equirectangular image (each texel: the radiance in
 * its centre's direction), the input of the downsampled levels, the irradiance and the
 * prefiltered levels; target.z = 1 clamps the brightest texels (split off as suns). */

void main()
{
  frag_color = vec4(world_radiance(equirect_direction(gl_FragCoord.xy / target.xy), target.z > 0.5), 1.0);
}
