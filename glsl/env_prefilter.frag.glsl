/* One prefiltered level of the atlas (rect: x, y, width, height in texels; drawn with the
 * viewport set to it): the environment seen by a GGX lobe of alpha = r^2 around each texel's
 * direction, with n = v = r as the split sum assumes (Karis 2013), from SL_SAMPLES samples of
 * the lobe (Hammersley points) weighted by n.l. Filtered importance sampling (Krivanek &
 * Colbert 2008, "Real-time Shading with Filtered Importance Sampling"): each sample reads the
 * downsampled level whose texels cover the solid angle the sample stands for, 1 / (N pdf),
 * trilinearly from the chain (all levels in one texture, rectangles in chain.rect) -- a bright
 * small source is spread over the lobe instead of sparkling. alpha 0 copies level 0. */

float radical_inverse(uint bits)
{
  bits = (bits << 16u) | (bits >> 16u);
  bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
  bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
  bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
  bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
  return float(bits) * 2.3283064365386963e-10;
}

vec3 chain_texel(ivec4 rect, int x, int y)
{
  x = x - rect.z * int(floor(float(x) / float(rect.z)));
  return texelFetch(source, rect.xy + ivec2(x, clamp(y, 0, rect.w - 1)), 0).rgb;
}

vec3 chain_level(int k, vec2 uv)
{
  ivec4 rect = ivec4(chain.rect[k]);
  vec2 p = uv * vec2(rect.zw) - 0.5;
  vec2 i = floor(p);
  vec2 f = p - i;
  int x = int(i.x), y = int(i.y);
  return mix(mix(chain_texel(rect, x, y), chain_texel(rect, x + 1, y), f.x),
             mix(chain_texel(rect, x, y + 1), chain_texel(rect, x + 1, y + 1), f.x), f.y);
}

vec3 chain_lookup(vec3 d, float lod)
{
  vec2 uv = equirect_uv(d);
  lod = clamp(lod, 0.0, chain.info.x - 1.0);
  int k = int(floor(lod));
  int k1 = min(k + 1, int(chain.info.x) - 1);
  return mix(chain_level(k, uv), chain_level(k1, uv), lod - float(k));
}

void main()
{
  vec2 uv = (gl_FragCoord.xy - rect.xy) / rect.zw;
  vec3 n = equirect_direction(uv);
  float alpha = params.x;
  if (alpha <= 0.0) {
    frag_color = vec4(chain_level(int(params.y), uv), 1.0);
    return;
  }
  vec3 up = abs(n.z) < 0.999 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
  vec3 tx = normalize(cross(up, n));
  vec3 ty = cross(n, tx);
  vec2 base = chain.rect[0].zw;  /* level 0: an equator texel spans (2 pi / w)(pi / h) */
  float a2 = alpha * alpha;
  vec3 sum = vec3(0.0);
  float weight = 0.0;
  for (int i = 0; i < SL_SAMPLES; i++) {
    float xi1 = float(i) / float(SL_SAMPLES);
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
      float omega_s = 1.0 / (float(SL_SAMPLES) * pdf);
      float sin_l = sqrt(max(1.0 - l.z * l.z, 1e-4));
      float omega_p = 2.0 * PI * PI * sin_l / (base.x * base.y);
      sum += chain_lookup(l, 0.5 * log2(omega_s / omega_p) + 1.0) * NoL;
      weight += NoL;
    }
  }
  frag_color = vec4(sum / max(weight, 1e-6), 1.0);
}
