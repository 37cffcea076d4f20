/* Gradient Texture (Cycles' svm_gradient and svm_node_tex_gradient, svm/gradient.h): one function
 * per type, each the gradient at p clamped to [0, 1] (Cycles' saturatef). Where Cycles' CPU
 * kernel rounds a product and a sum once, float_fma does (node_float.glsl): the same bits. */

float node_tex_gradient_linear(vec3 p) { return clamp(p.x, 0.0, 1.0); }

float node_tex_gradient_quadratic(vec3 p)
{
  float r = max(p.x, 0.0); /* (Cycles': 0, not x^2, left of 0) */
  return clamp(r * r, 0.0, 1.0);
}

/* 3t - 2tr, t = r^2 (3t fused into the difference) */
float node_tex_gradient_easing(vec3 p)
{
  float r = clamp(p.x, 0.0, 1.0); /* (Cycles': the curve on [0, 1] only) */
  float t = r * r;
  return clamp(float_fma(3.0, t, -(2.0 * t * r)), 0.0, 1.0);
}

float node_tex_gradient_diagonal(vec3 p) { return clamp((p.x + p.y) * 0.5, 0.0, 1.0); }

/* the angle about z in turns, 0 along -x: atan2(y, x) / 2 pi + 1/2, the division by the constant
 * a product by its reciprocal (1 / M_2PI_F in float), fused into the sum */
float node_tex_gradient_radial(vec3 p)
{
  return clamp(float_fma(float_atan2(p.y, p.x), 0.15915494, 0.5), 0.0, 1.0);
}

/* 1 - |p|, biased by 1e-6 so that a unit vector gives exactly 0 (Cycles' comment); not below 0 */
float gradient_sphere(vec3 p)
{
  return max(0.999999 - sqrt(float_fma(p.z, p.z, float_fma(p.x, p.x, p.y * p.y))), 0.0);
}

float node_tex_gradient_spherical(vec3 p) { return clamp(gradient_sphere(p), 0.0, 1.0); }

float node_tex_gradient_quadratic_sphere(vec3 p)
{
  float r = gradient_sphere(p);
  return clamp(r * r, 0.0, 1.0);
}
