/* One prefiltered level of the atlas (rect: x, y, width, height in texels; drawn with the
 * viewport set to it): the environment seen by a GGX lobe of alpha = r^2 around each texel's
 * direction, with n = v = r as the split sum assumes (Karis 2013), from params.z samples of
 * the lobe (Hammersley points) weighted by n.l. Filtered importance sampling (Krivanek &
 * Colbert 2008, "Real-time Shading with Filtered Importance Sampling"): each sample reads the
 * downsampled level whose texels cover the solid angle the sample stands for, 1 / (N pdf),
 * trilinearly from the chain (all levels in one texture, rectangles in chain.rect) -- a bright
 * small source is spread over the lobe instead of sparkling. alpha 0 copies level 0. */

void main()
{
  vec2 uv = (gl_FragCoord.xy - rect.xy) / rect.zw;
  vec3 n = equirect_direction(uv);
  float alpha = params.x;
  if (alpha <= 0.0) {
    frag_color = vec4(chain_level(source, int(params.y), uv), 1.0);
    return;
  }
  vec3 up = abs(n.z) < 0.999 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
  vec3 tx = normalize(cross(up, n));
  vec3 ty = cross(n, tx);
  float a2 = alpha * alpha;
  int samples = int(params.z);
  vec3 sum = vec3(0.0);
  float weight = 0.0;
  for (int i = 0; i < samples; i++) {
    float xi1 = float(i) / float(samples);
    float xi2 = radical_inverse(uint(i));
    /* GGX half vectors (Walter et al. 2007, eq. 35-36) */
    float phi = 2.0 * PI * xi1;
    float cos_t = sqrt((1.0 - xi2) / (1.0 + (a2 - 1.0) * xi2));
    float sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    vec3 h = tx * (sin_t * cos(phi)) + ty * (sin_t * sin(phi)) + n * cos_t;
    vec3 l = 2.0 * cos_t * h - n;
    float NoL = dot(n, l);
    if (NoL > 0.0) {
      /* pdf of l with n = v: D(h) / 4 */
      float t = cos_t * cos_t * (a2 - 1.0) + 1.0;
      float pdf = a2 / (PI * t * t) * 0.25;
      sum += chain_lookup(source, l, chain_lod(l, pdf, samples, 1.0)) * NoL;
      weight += NoL;
    }
  }
  frag_color = vec4(sum / max(weight, 1e-6), 1.0);
}
