/* Single-precision arithmetic rounded as Cycles' CPU kernel rounds it, for the procedural
 * textures that must give Cycles' bits. Cycles' kernels are compiled with fast math and, on a
 * CPU with FMA (its AVX2 kernel), fuse a product into the sum that is its only use: a * b + c
 * rounded once. GLSL's fma() need not round once (Mesa's llvmpipe computes a * b, then + c), so
 * float_fma builds the fused result from float operations that round as written (PRECISE, glsl/node_inputs.glsl). */

/* Dekker's split (Dekker 1971, "A floating-point technique for extending the available
 * precision"): a = hi + lo, each half of 12 bits or fewer, so that products of halves are exact.
 * (|a| < 2^115: 4097 a stays finite.) */
void float_split(float a, out float hi, out float lo)
{
  PRECISE float c = 4097.0 * a;
  PRECISE float h = c - (c - a);
  PRECISE float l = a - h;
  hi = h;
  lo = l;
}

/* a * b + c rounded once: Dekker's exact product p + e, Knuth's two-sum of p and c (s + t
 * exactly), then s + (t + e). Equal to a fused multiply-add but where t + e's own rounding moves
 * s + (t + e) across a rounding boundary (a tie within 2^-24 of an ulp: not met in the tests). */
float float_fma(float a, float b, float c)
{
  float ah, al, bh, bl;
  float_split(a, ah, al);
  float_split(b, bh, bl);
  PRECISE float p = a * b;
  PRECISE float e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
  PRECISE float s = p + c;
  PRECISE float v = s - p;
  PRECISE float t = (p - (s - v)) + (c - v);
  PRECISE float r = s + (t + e);
  /* NaN from the split where |a| or |b| >= 2^115 or the product overflows (4097 x, or the halves'
   * products, infinite): there the plain product and sum, as large as the fused result */
  return isnan(r) ? p + c : r;
}

vec3 float_fma(vec3 a, vec3 b, vec3 c)
{
  return vec3(float_fma(a.x, b.x, c.x), float_fma(a.y, b.y, c.y), float_fma(a.z, b.z, c.z));
}

/* a * b + c, the product rounded before the sum: where Cycles' kernel does not fuse them (a GPU
 * may, unasked) */
vec3 float_mul_add(vec3 a, float b, float c)
{
  PRECISE vec3 p = a * b;
  PRECISE vec3 r = p + c;
  return r;
}

/* C's fmodf (the remainder of a / b with a's sign), exact as C's is, for |a / b| < 2^24: the
 * quotient truncated, a - q b rounded once (it is representable: exact), b added back where
 * a / b rounded up to the next integer. (The Math node's modulo is math_fmod: Cycles computes
 * that one otherwise.) */
float float_fmod(float a, float b)
{
  float q = trunc(a / b);
  float r = float_fma(-q, b, a);
  return (r != 0.0 && (r < 0.0) != (a < 0.0)) ? r + sign(a) * abs(b) : r;
}

/* atan(x) within about an ulp of C's atanf, where GLSL's atan need only be within 4096 ulp
 * (Mesa's llvmpipe: 340 ulp, measured). Cephes' atanf (Moshier, "Methods and Programs for
 * Mathematical Functions", 1989): |x| reduced to [0, tan(pi / 8)] about 0, pi / 4 or pi / 2, its
 * odd polynomial; the base angle added in two parts (float's pi / 4 and what it lacks). */
float float_atan(float x)
{
  PRECISE float t = abs(x);
  PRECISE float base_hi = 0.0, base_lo = 0.0;
  if (t > 2.4142137) { /* tan(3 pi / 8) */
    base_hi = 1.5707964;
    base_lo = -4.3711388e-8;
    t = -1.0 / t;
  }
  else if (t > 0.41421357) { /* tan(pi / 8) */
    base_hi = 0.7853982;
    base_lo = -2.1855694e-8;
    t = (t - 1.0) / (t + 1.0);
  }
  PRECISE float z = t * t;
  PRECISE float p = (((0.0805374449538 * z - 0.138776856032) * z + 0.199777106478) * z - 0.333329491539) *
                    z * t;
  PRECISE float r = base_hi + ((base_lo + p) + t);
  return x < 0.0 ? -r : r;
}

/* atan2(y, x) as C's atan2f: the angle of (x, y) in [-pi, pi], +-0 or +-pi at the origin (where
 * GLSL's atan(y, x) is undefined) */
float float_atan2(float y, float x)
{
  bool y_negative = (floatBitsToUint(y) >> 31) != 0u;
  if (x == 0.0 && y == 0.0) {
    float zero_or_pi = (floatBitsToUint(x) >> 31) != 0u ? 3.1415927 : 0.0;
    return y_negative ? -zero_or_pi : zero_or_pi;
  }
  if (abs(y) > abs(x)) { /* +-pi / 2 - atan(x / y): the ratio below 1 */
    PRECISE float a = float_atan(x / y);
    PRECISE float r = 1.5707964 + (-4.3711388e-8 + (y_negative ? a : -a));
    return y_negative ? -r : r;
  }
  PRECISE float a = float_atan(y / x);
  if (x > 0.0) {
    return a;
  }
  PRECISE float r = 3.1415927 + (-8.7422777e-8 + (y_negative ? -a : a));
  return y_negative ? -r : r;
}
