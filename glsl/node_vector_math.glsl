/* The Vector Math node (ShaderNodeVectorMath): one function per operation on a, b, c and the
 * scale s, as Cycles' svm_vector_math evaluates each (svm/math_util.h, util/math_float3.h): a
 * division by zero gives 0 per component, a zero vector normalises to itself, a projection on
 * the zero vector is 0. Vector results in .xyz; a dot product, distance or length in .w. */

vec3 vmath_safe_normalize(vec3 a)
{
  float t = length(a);
  return t != 0.0 ? a / t : a;
}

vec3 vmath_divide_each(vec3 a, vec3 b)
{
  return vec3(math_safe_divide(a.x, b.x), math_safe_divide(a.y, b.y), math_safe_divide(a.z, b.z));
}

vec4 vmath_add(vec3 a, vec3 b, vec3 c, float s) { return vec4(a + b, 0.0); }
vec4 vmath_subtract(vec3 a, vec3 b, vec3 c, float s) { return vec4(a - b, 0.0); }
vec4 vmath_multiply(vec3 a, vec3 b, vec3 c, float s) { return vec4(a * b, 0.0); }
vec4 vmath_divide(vec3 a, vec3 b, vec3 c, float s) { return vec4(vmath_divide_each(a, b), 0.0); }
vec4 vmath_multiply_add(vec3 a, vec3 b, vec3 c, float s) { return vec4(a * b + c, 0.0); }
vec4 vmath_cross_product(vec3 a, vec3 b, vec3 c, float s) { return vec4(cross(a, b), 0.0); }

vec4 vmath_project(vec3 a, vec3 b, vec3 c, float s)
{
  float bb = dot(b, b);
  return vec4(bb != 0.0 ? b * (dot(a, b) / bb) : vec3(0.0), 0.0);
}

vec4 vmath_reflect(vec3 a, vec3 b, vec3 c, float s)
{
  vec3 n = vmath_safe_normalize(b);
  return vec4(a - 2.0 * n * dot(a, n), 0.0);
}

/* Snell's law for a unit incident direction a and the normal b, the index ratio s */
vec4 vmath_refract(vec3 a, vec3 b, vec3 c, float s)
{
  vec3 n = vmath_safe_normalize(b);
  float d = dot(n, a);
  float k = 1.0 - s * s * (1.0 - d * d);
  return vec4(k < 0.0 ? vec3(0.0) : s * a - (s * d + sqrt(k)) * n, 0.0);
}

vec4 vmath_faceforward(vec3 a, vec3 b, vec3 c, float s) { return vec4(dot(c, b) < 0.0 ? a : -a, 0.0); }
vec4 vmath_dot_product(vec3 a, vec3 b, vec3 c, float s) { return vec4(0.0, 0.0, 0.0, dot(a, b)); }
vec4 vmath_distance(vec3 a, vec3 b, vec3 c, float s) { return vec4(0.0, 0.0, 0.0, length(a - b)); }
vec4 vmath_length(vec3 a, vec3 b, vec3 c, float s) { return vec4(0.0, 0.0, 0.0, length(a)); }
vec4 vmath_scale(vec3 a, vec3 b, vec3 c, float s) { return vec4(a * s, 0.0); }
vec4 vmath_normalize(vec3 a, vec3 b, vec3 c, float s) { return vec4(vmath_safe_normalize(a), 0.0); }
vec4 vmath_absolute(vec3 a, vec3 b, vec3 c, float s) { return vec4(abs(a), 0.0); }

vec4 vmath_power(vec3 a, vec3 b, vec3 c, float s)
{
  return vec4(math_power(a.x, b.x, 0.0), math_power(a.y, b.y, 0.0), math_power(a.z, b.z, 0.0), 0.0);
}

vec4 vmath_sign(vec3 a, vec3 b, vec3 c, float s)
{
  return vec4(math_sign(a.x, 0.0, 0.0), math_sign(a.y, 0.0, 0.0), math_sign(a.z, 0.0, 0.0), 0.0);
}

vec4 vmath_minimum(vec3 a, vec3 b, vec3 c, float s) { return vec4(min(a, b), 0.0); }
vec4 vmath_maximum(vec3 a, vec3 b, vec3 c, float s) { return vec4(max(a, b), 0.0); }
vec4 vmath_floor(vec3 a, vec3 b, vec3 c, float s) { return vec4(floor(a), 0.0); }
vec4 vmath_ceil(vec3 a, vec3 b, vec3 c, float s) { return vec4(ceil(a), 0.0); }
vec4 vmath_fraction(vec3 a, vec3 b, vec3 c, float s) { return vec4(a - floor(a), 0.0); }

vec4 vmath_modulo(vec3 a, vec3 b, vec3 c, float s)
{
  return vec4(math_modulo(a.x, b.x, 0.0), math_modulo(a.y, b.y, 0.0), math_modulo(a.z, b.z, 0.0), 0.0);
}

vec4 vmath_wrap(vec3 a, vec3 b, vec3 c, float s)
{
  return vec4(math_wrap(a.x, b.x, c.x), math_wrap(a.y, b.y, c.y), math_wrap(a.z, b.z, c.z), 0.0);
}

vec4 vmath_snap(vec3 a, vec3 b, vec3 c, float s) { return vec4(floor(vmath_divide_each(a, b)) * b, 0.0); }
vec4 vmath_sine(vec3 a, vec3 b, vec3 c, float s) { return vec4(sin(a), 0.0); }
vec4 vmath_cosine(vec3 a, vec3 b, vec3 c, float s) { return vec4(cos(a), 0.0); }
vec4 vmath_tangent(vec3 a, vec3 b, vec3 c, float s) { return vec4(tan(a), 0.0); }
