/* The Math node (ShaderNodeMath): one function per operation, a, b, c its three values; each as
 * Cycles evaluates it (intern/cycles/kernel/svm/math_util.h's svm_math and util/math_base.h's
 * safe_* helpers): a division by zero gives 0, a root or logarithm of what has none 0, a negative
 * number to a fractional power 0, asin/acos clamp their argument. GLSL's own pow, mod and atan
 * differ from C's at those points; the helpers below follow C. */

float math_safe_divide(float a, float b)
{
  return b != 0.0 ? a / b : 0.0;
}

/* C's powf as Cycles' compatible_powf evaluates it on a GPU: x^0 = 1, a negative base to an
 * integer power keeps its sign by the power's parity, 0^y = 0 */
float math_compatible_pow(float x, float y)
{
  if (y == 0.0) {
    return 1.0;
  }
  if (x < 0.0) {
    float p = pow(-x, y);
    return mod(-y, 2.0) == 0.0 ? p : -p;
  }
  return x == 0.0 ? 0.0 : pow(x, y);
}

/* C's fmodf: the remainder takes the dividend's sign (GLSL's mod takes the divisor's). In float,
 * as Cycles 5 computes it: where a / b rounds to an integer the remainder is 0 (C's exact fmodf,
 * as Cycles 4.5 gives it, is then nearly b: tests/test_material_nodes.py counts those pixels) */
float math_fmod(float a, float b)
{
  return a - b * trunc(a / b);
}

float math_add(float a, float b, float c) { return a + b; }
float math_subtract(float a, float b, float c) { return a - b; }
float math_multiply(float a, float b, float c) { return a * b; }
float math_divide(float a, float b, float c) { return math_safe_divide(a, b); }
float math_multiply_add(float a, float b, float c) { return a * b + c; }

float math_power(float a, float b, float c)
{
  return (a < 0.0 && b != trunc(b)) ? 0.0 : math_compatible_pow(a, b);
}

float math_logarithm(float a, float b, float c)
{
  return (a <= 0.0 || b <= 0.0) ? 0.0 : math_safe_divide(log(a), log(b));
}

float math_sqrt(float a, float b, float c) { return sqrt(max(a, 0.0)); }
float math_inverse_sqrt(float a, float b, float c) { return a > 0.0 ? 1.0 / sqrt(a) : 0.0; }
float math_absolute(float a, float b, float c) { return abs(a); }
float math_exponent(float a, float b, float c) { return exp(a); }
float math_minimum(float a, float b, float c) { return min(a, b); }
float math_maximum(float a, float b, float c) { return max(a, b); }
float math_less_than(float a, float b, float c) { return a < b ? 1.0 : 0.0; }
float math_greater_than(float a, float b, float c) { return a > b ? 1.0 : 0.0; }

/* Cycles' compatible_signf: 0 at 0 */
float math_sign(float a, float b, float c) { return a == 0.0 ? 0.0 : (a < 0.0 ? -1.0 : 1.0); }

/* equal within c, at least FLT_EPSILON */
float math_compare(float a, float b, float c)
{
  return (a == b || abs(a - b) <= max(c, 1.1920929e-7)) ? 1.0 : 0.0;
}

/* Cycles' smoothminf (a polynomial smooth minimum of width c) */
float math_smooth_min(float a, float b, float c)
{
  if (c != 0.0) {
    float h = max(c - abs(a - b), 0.0) / c;
    return min(a, b) - h * h * h * c * (1.0 / 6.0);
  }
  return min(a, b);
}

float math_smooth_max(float a, float b, float c) { return -math_smooth_min(-a, -b, c); }
float math_round(float a, float b, float c) { return floor(a + 0.5); }
float math_floor(float a, float b, float c) { return floor(a); }
float math_ceil(float a, float b, float c) { return ceil(a); }
float math_trunc(float a, float b, float c) { return a >= 0.0 ? floor(a) : ceil(a); }
float math_fraction(float a, float b, float c) { return a - floor(a); }
float math_modulo(float a, float b, float c) { return b != 0.0 ? math_fmod(a, b) : 0.0; }
float math_floored_modulo(float a, float b, float c) { return b != 0.0 ? a - floor(a / b) * b : 0.0; }

/* Cycles' wrapf(value, max, min) */
float math_wrap(float a, float b, float c)
{
  float range = b - c;
  return range != 0.0 ? a - range * floor((a - c) / range) : c;
}

float math_snap(float a, float b, float c) { return floor(math_safe_divide(a, b)) * b; }

/* Cycles' pingpongf */
float math_pingpong(float a, float b, float c)
{
  if (b == 0.0) {
    return 0.0;
  }
  float x = (a - b) / (b * 2.0);
  return abs((x - floor(x)) * b * 2.0 - b);
}

float math_sine(float a, float b, float c) { return sin(a); }
float math_cosine(float a, float b, float c) { return cos(a); }
float math_tangent(float a, float b, float c) { return tan(a); }
float math_sinh(float a, float b, float c) { return sinh(a); }
float math_cosh(float a, float b, float c) { return cosh(a); }
float math_tanh(float a, float b, float c) { return tanh(a); }
/* asin and acos through atan: Mesa's llvmpipe evaluates GLSL's asin to 2e-4 of Cycles' asinf
 * (measured on this node's test), its atan to 1.6e-6 */
float math_arcsine(float a, float b, float c)
{
  float x = clamp(a, -1.0, 1.0);
  return atan(x, sqrt(max(1.0 - x * x, 0.0)));
}

float math_arccosine(float a, float b, float c)
{
  float x = clamp(a, -1.0, 1.0);
  return atan(sqrt(max(1.0 - x * x, 0.0)), x);
}
float math_arctangent(float a, float b, float c) { return atan(a); }

/* C's atan2f(a, b), 0 at the origin */
float math_arctan2(float a, float b, float c) { return (a == 0.0 && b == 0.0) ? 0.0 : atan(a, b); }

float math_radians(float a, float b, float c) { return a * (3.14159265358979 / 180.0); }
float math_degrees(float a, float b, float c) { return a * (180.0 / 3.14159265358979); }
