/* Wave Texture (Cycles' svm_node_tex_wave, svm_wave in kernel/svm/wave.h), operation for
 * operation; the numpy twin is addon/reference/wave.py. Bands along an axis or the diagonal, rings
 * about an axis or a point; a sine, saw or triangle profile of the phase, displaced by the
 * normalised fBM of node_tex_noise.glsl; its sine wave_sin (C's sinf: Cycles' at every |x|), within
 * an ulp or two of Cycles', measured in tests/test_texture_wave.py. */

#define WAVE_BANDS 0
#define WAVE_RINGS 1
/* the direction of the bands (X, Y, Z, DIAGONAL) or the rings' axis (X, Y, Z, SPHERICAL) */
#define WAVE_X 0
#define WAVE_Y 1
#define WAVE_Z 2
#define WAVE_DIAGONAL 3
#define WAVE_SPHERICAL 3
#define WAVE_SIN 0
#define WAVE_SAW 1
#define WAVE_TRI 2
/* the saw's and triangle's phase over 2 pi as the Blender reading the file takes it (the reader's
 * wave_phase): Cycles 4.5 and 5.0 times the reciprocal (their kernel's fast math), 4.2 divided */
#define WAVE_PHASE_RECIPROCAL 0
#define WAVE_PHASE_DIVIDE 1

/* The phase rounded as Cycles rounds it (PRECISE): a shader compiler may fold consecutive
 * products by literals into one (Mesa computes (x 0.999999) 20 as x 19.99998: another rounding,
 * 8e-3 after the sine at |x| = 1e4). */

/* A linked Detail beyond this many octaves is drawn with this many: Cycles loops on (64 octaves
 * of lacunarity 2 are far below a float's precision; a GPU's loop must end) */
#define WAVE_MAX_DETAIL 64.0

/* 2/pi's first 288 bits, the binary fraction 0.A2F9836E ... (computed from pi to 400 bits) */
const uint WAVE_TWO_OVER_PI[9] = uint[](0xA2F9836Eu, 0x4E441529u, 0xFC2757D1u, 0xF534DDC0u, 0xDB629599u,
                                        0x3C439041u, 0xFE5163ABu, 0xDEBBC561u, 0xB7246E3Au);

/* 32 bits of 2/pi from its bit j on (bit 1 weighs 1/2; bits j < 1 are 0) */
uint wave_two_over_pi(int j)
{
  int i = j - 1;
  if (i <= -32) {
    return 0u;
  }
  if (i < 0) {
    return WAVE_TWO_OVER_PI[0] >> uint(-i);
  }
  int k = i >> 5, shift = i & 31;
  uint word = WAVE_TWO_OVER_PI[k] << uint(shift);
  return shift == 0 ? word : word | (WAVE_TWO_OVER_PI[k + 1] >> uint(32 - shift));
}

/* a x b as two 32-bit words (16-bit halves: no extended multiply needed) */
void wave_multiply(uint a, uint b, out uint high, out uint low)
{
  uint a0 = a & 0xFFFFu, a1 = a >> 16, b0 = b & 0xFFFFu, b1 = b >> 16;
  uint middle = a1 * b0 + ((a0 * b0) >> 16);      /* < 2^32: no carry lost */
  uint middle2 = a0 * b1 + (middle & 0xFFFFu);
  low = a * b;
  high = a1 * b1 + (middle >> 16) + (middle2 >> 16);
}

/* sin(x) to a float's precision at every |x|, as C's sinf (which Cycles calls): a GPU's sin() loses
 * precision with |x| (llvmpipe's is off by 1.7 at 1e8; many GPUs' far sooner). |x| 2/pi reduced
 * mod 4 exactly (Payne and Hanek: x's 24-bit mantissa times 96 bits of 2/pi from x's exponent on,
 * in 32-bit integers), the remainder to the nearest quadrant times pi/2, in [-pi/4, pi/4], into
 * Cephes' sinf and cosf polynomials. */
float wave_sin(float x)
{
  uint bits = floatBitsToUint(x);
  int exponent = int((bits >> 23) & 0xFFu);
  if (exponent == 0) { /* zero, subnormals: sin x = x */
    return x;
  }
  if (exponent == 255) { /* infinities, NaN: NaN */
    return x - x;
  }
  uint mantissa = (bits & 0x7FFFFFu) | 0x800000u;
  int e = exponent - 150; /* |x| = mantissa x 2^e */
  int j = e - 1;          /* the bits of 2/pi before j add whole multiples of 4 */
  uint h0, l0, h1, l1, h2, l2;
  wave_multiply(mantissa, wave_two_over_pi(j + 64), h0, l0);
  wave_multiply(mantissa, wave_two_over_pi(j + 32), h1, l1);
  wave_multiply(mantissa, wave_two_over_pi(j), h2, l2);
  /* |x| 2/pi = P 2^-94 (mod 4), P = mantissa x the 96 bits: its words 1 and 2 (3 adds multiples of 4) */
  uint p1 = h0 + l1;
  uint p2 = h1 + l2 + (p1 < h0 ? 1u : 0u);
  uint quadrant = p2 >> 30;
  uint high = (p2 << 2) | (p1 >> 30); /* the fraction's bits, 64 of them */
  uint low = (p1 << 2) | (l0 >> 30);
  quadrant += high >> 31;             /* to the nearest quadrant: the fraction then in [-1/2, 1/2) */
  int signed_high = int(high);
  float f1 = float(signed_high >> 8) * 5.9604644775390625e-8;                     /* 2^-24, exact */
  float f2 = float(((high & 0xFFu) << 16) | (low >> 16)) * 3.552713678800501e-15; /* 2^-48, exact */
  float r = f1 * 1.5707964 + (f2 * 1.5707964 + f1 * -4.371139e-8); /* x pi/2, pi/2 in two floats */
  float z = r * r;
  float sine = r + r * z * (-1.6666654611e-1 + z * (8.3321608736e-3 + z * -1.9515295891e-4));
  float cosine = 1.0 - 0.5 * z + z * z * (4.166664568298827e-2 + z * (-1.388731625493765e-3 + z * 2.443315711809948e-5));
  float v = (quadrant & 1u) != 0u ? cosine : sine;
  v = (quadrant & 2u) != 0u ? -v : v;
  return x < 0.0 ? -v : v;
}

/* n / 2 pi rounded once, as Blender 4.2's Cycles divides: a GPU's division may be a product with the
 * reciprocal (Mesa's is), so the quotient q = n (1 / 2 pi) is corrected by its remainder n - q 2 pi,
 * exact in one fused multiply-add (float_fma: it is representable), times the reciprocal (Markstein's
 * correction step; "IA-64 and Elementary Functions", 2000). 2 pi and its reciprocal as float32 round
 * them, Cycles' M_2PI_F. */
float wave_divide_two_pi(float n)
{
  PRECISE float q = n * 0.15915494309189535;
  return float_fma(float_fma(-q, 6.283185307179586, n), 0.15915494309189535, q);
}

float node_tex_wave(vec3 co, float scale, float distortion, float detail, float detail_scale, float detail_roughness,
                    float phase, int type, int direction, int profile, int phase_rule)
{
  /* Cycles: "prevent precision issues on unit coordinates", its co x scale fused into the sum */
  PRECISE vec3 p = fma(co, vec3(scale), vec3(1.0e-6)) * 0.999999;
  PRECISE float n;
  if (type == WAVE_BANDS) {
    n = direction == WAVE_DIAGONAL ? ((p.x + p.y) + p.z) * 10.0 : p[direction] * 20.0;
  }
  else {
    vec3 r = p * vec3(direction != WAVE_X, direction != WAVE_Y, direction != WAVE_Z);
    /* Cycles' len(): the square root of SSE4's dot product, summed (x^2 + y^2) + z^2 */
    n = sqrt((r.x * r.x + r.y * r.y) + r.z * r.z) * 20.0;
  }
  n += phase;
  if (distortion != 0.0) {
    float octaves = detail < WAVE_MAX_DETAIL ? detail : WAVE_MAX_DETAIL; /* (a NaN Detail too) */
    float fbm = noise_fractal(vec4(p * detail_scale, 0.0), 3, NOISE_FBM, octaves, detail_roughness, 2.0, 0.0, 0.0, true);
    n = fma(distortion, fma(fbm, 2.0, -1.0), n);
  }
  if (profile == WAVE_SIN) {
    return 0.5 + 0.5 * wave_sin(n - 1.5707963267948966);
  }
  /* Cycles' n / M_2PI_F, compiled (-ffast-math) as n x 1 / (2 pi) by 4.5 and 5.0 */
  n = phase_rule == WAVE_PHASE_DIVIDE ? wave_divide_two_pi(n) : n * 0.15915494309189535;
  if (profile == WAVE_SAW) {
    return n - floor(n);
  }
  return abs(n - floor(n + 0.5)) * 2.0;
}
