/* Noise Texture (Cycles' svm_node_tex_noise, kernel/svm/noisetex.h) and the Perlin noise and
 * fractals under it and under the Wave Texture (kernel/svm/noise.h, fractal_noise.h), operation
 * for operation; the numpy twin is addon/reference/noise.py.
 *
 * Coordinates are a vec4 p of `dims` components (1D: p.x = W; 2D: x, y; 3D: x, y, z; 4D: x, y,
 * z, W), the others 0 and never read. fma() marks the products Cycles' CPU kernel (AVX2, built
 * with -ffast-math) fuses with a sum: with them the twin equals Cycles' output bit for bit. A
 * GPU whose fma() rounds twice (Mesa's llvmpipe lowers it to a product and a sum) differs by float
 * rounding (2.3e-6 at most undistorted), measured in tests/test_texture_noise.py. node_float.glsl's
 * float_fma, one rounding from plain operations, in fma()'s place gave Cycles' bits there too (0 in
 * every case) but cost the Noise Texture 1.9-2.1x its time on llvmpipe (float64 arithmetic: 1.6x,
 * and Metal has none); a GPU whose fma() is its fused instruction gives those bits at no cost. So
 * fma() stays. Compiled into a program only where its graph
 * uses a Noise or Wave Texture (codegen.OPTIONAL_LIBRARY); the lattice hashes are node_hash.glsl's. */

/* the Noise Texture's types (Cycles' NodeNoiseType, our order) */
#define NOISE_FBM 0
#define NOISE_MULTIFRACTAL 1
#define NOISE_HYBRID_MULTIFRACTAL 2
#define NOISE_RIDGED_MULTIFRACTAL 3
#define NOISE_HETERO_TERRAIN 4

/* Cycles' floorfrac: the lattice cell of x and the fraction x - floor(x) (exact) */
int perlin_cell(float x, out float fraction)
{
  float cell = floor(x);
  fraction = x - cell;
  return int(cell);
}

/* Cycles' mix(a, b, t) = a + t (b - a), fused as its SIMD kernel's */
float perlin_lerp(float a, float b, float t) { return fma(t, b - a, a); }

/* Cycles' SIMD fade (float4, madd): 6 t^5 - 15 t^4 + 10 t^3 as t^2 (t (t (6 t - 15) + 10)) */
float perlin_fade(float t) { return (t * t) * (t * fma(t, fma(t, 6.0, -15.0), 10.0)); }

float perlin_negate_if(float value, uint condition) { return condition != 0u ? -value : value; }

/* Cycles' grad2, grad3, grad4: the gradient the hash picks dotted with the corner's offset */
float perlin_grad2(uint hash, float x, float y)
{
  uint h = hash & 7u;
  float u = h < 4u ? x : y;
  float v = 2.0 * (h < 4u ? y : x);
  return perlin_negate_if(u, h & 1u) + perlin_negate_if(v, h & 2u);
}

float perlin_grad3(uint hash, float x, float y, float z)
{
  uint h = hash & 15u;
  float u = h < 8u ? x : y;
  float v = h < 4u ? y : ((h == 12u || h == 14u) ? x : z);
  return perlin_negate_if(u, h & 1u) + perlin_negate_if(v, h & 2u);
}

float perlin_grad4(uint hash, float x, float y, float z, float w)
{
  uint h = hash & 31u;
  float u = h < 24u ? x : y;
  float v = h < 16u ? y : z;
  float s = h < 8u ? z : w;
  return perlin_negate_if(u, h & 1u) + perlin_negate_if(v, h & 2u) + perlin_negate_if(s, h & 4u);
}

/* Cycles' perlin_1d, a scalar function: grad1's slope g (1 .. 8, signed) times the offset, mixed
 * as its compiler fused it (the product a = g t inside both of its uses) */
float perlin_1d(float x)
{
  float t;
  int cell = perlin_cell(x, t);
  float u = ((t * t) * t) * fma(t, fma(t, 6.0, -15.0), 10.0);
  uint h0 = hash_uint(uint(cell)) & 15u;
  uint h1 = hash_uint(uint(cell + 1)) & 15u;
  float g = perlin_negate_if(1.0 + float(h0 & 7u), h0 & 8u);
  float b = perlin_negate_if(1.0 + float(h1 & 7u), h1 & 8u) * (t - 1.0);
  return fma(g, t, u * fma(-g, t, b));
}

/* Cycles' SIMD perlin_2d: the corners lerped along x, then y */
float perlin_2d(vec2 p)
{
  float fx, fy;
  int x = perlin_cell(p.x, fx), y = perlin_cell(p.y, fy);
  uint x0 = uint(x), x1 = uint(x + 1), y0 = uint(y), y1 = uint(y + 1);
  float u = perlin_fade(fx), v = perlin_fade(fy);
  float a = perlin_lerp(perlin_grad2(hash_uint2(x0, y0), fx, fy), perlin_grad2(hash_uint2(x1, y0), fx - 1.0, fy), u);
  float b = perlin_lerp(perlin_grad2(hash_uint2(x0, y1), fx, fy - 1.0),
                        perlin_grad2(hash_uint2(x1, y1), fx - 1.0, fy - 1.0), u);
  return perlin_lerp(a, b, v);
}

/* one x edge of the 3D lattice cell (y + j, z + k): its two corners lerped along x */
float perlin_edge_3d(uvec3 c, vec3 f, uint j, uint k, float u)
{
  float y = f.y - float(j), z = f.z - float(k);
  return perlin_lerp(perlin_grad3(hash_uint3(c.x, c.y + j, c.z + k), f.x, y, z),
                     perlin_grad3(hash_uint3(c.x + 1u, c.y + j, c.z + k), f.x - 1.0, y, z), u);
}

/* Cycles' SIMD perlin_3d: lerps along x, then y, then z */
float perlin_3d(vec3 p)
{
  vec3 f;
  uvec3 c = uvec3(perlin_cell(p.x, f.x), perlin_cell(p.y, f.y), perlin_cell(p.z, f.z));
  float u = perlin_fade(f.x), v = perlin_fade(f.y), w = perlin_fade(f.z);
  float z0 = perlin_lerp(perlin_edge_3d(c, f, 0u, 0u, u), perlin_edge_3d(c, f, 1u, 0u, u), v);
  float z1 = perlin_lerp(perlin_edge_3d(c, f, 0u, 1u, u), perlin_edge_3d(c, f, 1u, 1u, u), v);
  return perlin_lerp(z0, z1, w);
}

/* a corner pair of the 4D lattice cell (x + i, y + j, z + k; w and w + 1) lerped along w, as the
 * AVX2 kernel's quad_mix does before the trilinear mix */
float perlin_wpair_4d(uvec4 c, vec4 f, uint i, uint j, uint k, float s)
{
  float x = f.x - float(i), y = f.y - float(j), z = f.z - float(k);
  return perlin_lerp(perlin_grad4(hash_uint4(c.x + i, c.y + j, c.z + k, c.w), x, y, z, f.w),
                     perlin_grad4(hash_uint4(c.x + i, c.y + j, c.z + k, c.w + 1u), x, y, z, f.w - 1.0), s);
}

float perlin_edge_4d(uvec4 c, vec4 f, uint j, uint k, float u, float s)
{
  return perlin_lerp(perlin_wpair_4d(c, f, 0u, j, k, s), perlin_wpair_4d(c, f, 1u, j, k, s), u);
}

/* Cycles' AVX2 perlin_4d: lerps along w, then x, y, z */
float perlin_4d(vec4 p)
{
  vec4 f;
  uvec4 c = uvec4(perlin_cell(p.x, f.x), perlin_cell(p.y, f.y), perlin_cell(p.z, f.z), perlin_cell(p.w, f.w));
  float u = perlin_fade(f.x), v = perlin_fade(f.y), t = perlin_fade(f.z), s = perlin_fade(f.w);
  float z0 = perlin_lerp(perlin_edge_4d(c, f, 0u, 0u, u, s), perlin_edge_4d(c, f, 1u, 0u, u, s), v);
  float z1 = perlin_lerp(perlin_edge_4d(c, f, 0u, 1u, u, s), perlin_edge_4d(c, f, 1u, 1u, u, s), v);
  return perlin_lerp(z0, z1, t);
}

/* C's fmodf(x, 1e5), exact at every magnitude (Cycles' snoise_1d and snoise_2d): |x| less 1e5 x
 * 2^k for k down to 0 where it fits (long division: each step exact, m <= r < 2 m), x's sign */
float noise_fmodf(float x)
{
  float r = abs(x);
  if (r >= 1.0e5) {
    float m = 1.0e5 * exp2(floor(log2(r * 1.0e-5)));
    m = m > r ? 0.5 * m : (2.0 * m <= r ? 2.0 * m : m); /* log2's rounding, either way */
    for (int i = 0; i < 128 && r >= 1.0e5; i++) {         /* 128: FLT_MAX / 1e5 < 2^112 */
      if (r >= m) {
        r -= m;
      }
      m *= 0.5;
    }
  }
  return x < 0.0 ? -r : r;
}

/* Cycles' SSE fmod (snoise_3d, snoise_4d): x - trunc(x x 1e-5) x 1e5, its -ffast-math kernel's
 * division as a product by the reciprocal, the last product fused (one rounding). Exact here too
 * where fma() rounds twice: the quotient's top 12 bits and the rest each times 1e5 exactly, x less
 * the first exact (within a factor 2 of x), the second subtraction the one rounding. */
float noise_fmod_sse(float x)
{
  float q = trunc(x * 1.0e-5);
  float high = uintBitsToFloat(floatBitsToUint(q) & 0xFFFFF000u);
  return (x - high * 1.0e5) - (q - high) * 1.0e5;
}

/* Cycles' snoise_*d coordinate wrap: the noise repeats every 1e5 (against float precision), and
 * components |p| >= 1e6, whose float spacing is >= 0.0625, are shifted by half a cell (a lattice
 * point's noise is 0) */
vec4 noise_wrap(vec4 p, int dims)
{
  vec4 correction = 0.5 * vec4(greaterThanEqual(abs(p), vec4(1.0e6)));
  if (dims <= 2) {
    return vec4(noise_fmodf(p.x), noise_fmodf(p.y), 0.0, 0.0) + correction;
  }
  return vec4(noise_fmod_sse(p.x), noise_fmod_sse(p.y), noise_fmod_sse(p.z), noise_fmod_sse(p.w)) + correction;
}

/* Perlin noise of p's first `dims` components, wrapped as Cycles' snoise */
float noise_perlin(vec4 p, int dims)
{
  vec4 q = noise_wrap(p, dims);
  if (dims == 1) {
    return perlin_1d(q.x);
  }
  if (dims == 2) {
    return perlin_2d(q.xy);
  }
  return dims == 3 ? perlin_3d(q.xyz) : perlin_4d(q);
}

/* Cycles' noise_scale1..4: the OSL developers' measured output scales, to about [-1, 1] */
float noise_scale(int dims) { return dims == 1 ? 0.25 : (dims == 2 ? 0.6616 : (dims == 3 ? 0.9820 : 0.8344)); }

/* Cycles' snoise_*d: signed noise */
float snoise(vec4 p, int dims) { return noise_scale(dims) * noise_perlin(p, dims); }

/* Cycles' five fractals (fractal_noise.h: noise_fbm, noise_multi_fractal,
 * noise_hybrid_multi_fractal, noise_ridged_multi_fractal, noise_hetero_terrain) as one loop over
 * the octaves with one noise evaluation in it, each type's sums as Cycles' (the twin keeps them
 * apart): a shader compiler inlines the noise, of every dimension, once per call, not once per
 * type and sum. Octaves 0 .. int(detail), then one more weighted by Detail's fraction (the
 * ridged fractal has none).
 * - fBM: octaves of snoise, amplitude x roughness and frequency x lacunarity from one to the
 *   next; normalised to [0, 1] by the amplitudes' sum where asked;
 * - Multifractal: the product of (1 + amplitude x snoise);
 * - Hybrid: (snoise + offset) x amplitude, each weighted by the previous ones x gain while the
 *   weight stays above 0.001;
 * - Ridged: (offset - |snoise|)^2, each weighted by the previous signal x gain in [0, 1];
 * - Hetero Terrain: each octave's (snoise + offset) x amplitude scaled by the value so far. */
float noise_fractal(vec4 p, int dims, int type, float detail, float roughness, float lacunarity, float offset,
                    float gain, bool normalize)
{
  int octaves = int(detail);
  float rmd = detail - floor(detail);
  int last = octaves + (rmd != 0.0 && type != NOISE_RIDGED_MULTIFRACTAL ? 1 : 0);
  float scale = noise_scale(dims);
  bool fbm = type == NOISE_FBM;
  /* fBM's sums; the others' value, amplitude and weight, as Cycles starts them */
  float fscale = 1.0, amp = 1.0, maxamp = 0.0, sum = 0.0, sum2 = 0.0;
  float value = type == NOISE_MULTIFRACTAL ? 1.0 : 0.0, weight = 1.0;
  float pwr = (type == NOISE_RIDGED_MULTIFRACTAL || type == NOISE_HETERO_TERRAIN) ? roughness : 1.0;
  for (int i = 0; i <= last; i++) {
    bool partial = i > octaves; /* the octave weighted by Detail's fraction */
    if (type == NOISE_HYBRID_MULTIFRACTAL && !(weight > 0.001)) {
      break;
    }
    float n = noise_perlin(fbm ? fscale * p : p, dims);
    if (fbm) {
      if (partial) {
        sum2 = fma(scale * n, amp, sum);
        break;
      }
      sum = fma(scale * n, amp, sum);
      maxamp += amp;
      amp *= roughness;
      fscale *= lacunarity;
    }
    else if (type == NOISE_MULTIFRACTAL) {
      value *= fma(partial ? rmd * pwr : pwr, scale * n, 1.0);
      pwr *= roughness;
    }
    else if (type == NOISE_HETERO_TERRAIN) {
      float signal = fma(scale, n, offset);
      if (i == 0) {
        value = signal;
      }
      else if (partial) {
        value = fma(rmd, (signal * pwr) * value, value);
      }
      else {
        value = fma(signal * pwr, value, value);
        pwr *= roughness;
      }
    }
    else if (type == NOISE_HYBRID_MULTIFRACTAL) {
      weight = min(weight, 1.0);
      float signal = fma(scale, n, offset) * pwr;
      if (partial) {
        value = fma(rmd * weight, signal, value);
      }
      else {
        pwr *= roughness;
        value = fma(weight, signal, value);
        weight *= gain * signal;
      }
    }
    else { /* ridged */
      float signal = offset - abs(scale * n);
      signal *= signal;
      if (i == 0) {
        value = signal;
      }
      else {
        signal *= weight;
        value = fma(signal, pwr, value);
        pwr *= roughness;
      }
      weight = clamp(signal * gain, 0.0, 1.0); /* the next octave's */
    }
    if (!fbm) { /* (fBM scales the coordinate by its own running frequency, as Cycles') */
      p *= lacunarity;
    }
  }
  if (!fbm) {
    return value;
  }
  if (rmd != 0.0) {
    return normalize ? perlin_lerp(0.5 * sum / maxamp + 0.5, 0.5 * sum2 / (maxamp + amp) + 0.5, rmd)
                     : perlin_lerp(sum, sum2, rmd);
  }
  return normalize ? 0.5 * sum / maxamp + 0.5 : sum;
}

/* Cycles' random_float*_offset: a seed's offset of the coordinates, components in [100, 200]
 * (1D: the hash of the seed; more: of (seed, component)) */
vec4 noise_offset(float seed, int dims)
{
  if (dims == 1) {
    return vec4(100.0 + hash_float_to_float(seed) * 100.0, 0.0, 0.0, 0.0);
  }
  vec4 offset = vec4(0.0);
  for (int i = 0; i < dims; i++) {
    offset[i] = 100.0 + hash_vec2_to_float(vec2(seed, float(i))) * 100.0;
  }
  return offset;
}

/* The Noise Texture's coordinates (Cycles' svm_node_tex_noise, noise_texture_*d): the Vector and
 * W x Scale, moved by snoise at seeds 0 .. dims - 1 x Distortion (the sums fused as Cycles'
 * kernel computes them: 1D's, 2D's x; 3D's and 4D's not) */
vec4 node_noise_coordinates(vec3 co, float w, float scale, float distortion, int dims)
{
  co *= scale;
  w *= scale;
  vec4 p = dims == 1 ? vec4(w, 0.0, 0.0, 0.0) : (dims == 2 ? vec4(co.xy, 0.0, 0.0) : vec4(co, dims == 4 ? w : 0.0));
  if (distortion == 0.0) {
    return p;
  }
  vec4 moved = vec4(0.0);
  for (int i = 0; i < dims; i++) {
    moved[i] = snoise(p + noise_offset(float(i), dims), dims);
  }
  if (dims <= 2) {
    float y = dims == 2 ? p.y + moved.y * distortion : 0.0;
    return vec4(fma(moved.x, distortion, p.x), y, 0.0, 0.0);
  }
  return p + moved * distortion;
}

/* The Noise Texture's Fac: Detail clamped to [0, 15] (16 octaves at most) and Roughness to >= 0,
 * as Cycles' svm_node_tex_noise (its min/max by comparison: a NaN Detail or Roughness gives 0) */
float node_noise_value(vec4 p, int dims, int type, float detail, float roughness, float lacunarity, float offset,
                       float gain, float normalize)
{
  float octaves = detail > 0.0 ? (detail < 15.0 ? detail : 15.0) : 0.0;
  return noise_fractal(p, dims, type, octaves, roughness > 0.0 ? roughness : 0.0, lacunarity, offset, gain,
                       normalize != 0.0);
}

/* The Noise Texture's Color: its Fac, and the fractal at the seeds dims and dims + 1 (one loop:
 * the fractal inlined once) */
vec4 node_noise_color(vec4 p, float value, int dims, int type, float detail, float roughness, float lacunarity,
                      float offset, float gain, float normalize)
{
  vec4 color = vec4(value, 0.0, 0.0, 1.0);
  for (int c = 1; c <= 2; c++) {
    color[c] = node_noise_value(p + noise_offset(float(dims + c - 1), dims), dims, type, detail, roughness,
                                lacunarity, offset, gain, normalize);
  }
  return color;
}
