/* The anisotropic closures' inputs (codegen.OPTIONAL_LIBRARY: compiled only into graphs whose
 * Principled, Glossy or Metallic BSDF can be anisotropic), as Cycles 5.0's svm_node_closure_bsdf
 * (kernel/svm/closure.h) turns Anisotropic / Anisotropy, Rotation and Tangent into the lobe's
 * tangent and its two roughnesses. Both node kinds keep alpha_x alpha_y = alpha^2: the lobe is
 * the isotropic one's alpha stretched by a factor k along the tangent and shrunk by it across,
 * alpha_x = alpha k, alpha_y = alpha / k (glsl/anisotropy.glsl shades it). Twin:
 * addon/reference/anisotropy.py. */

/* The Principled BSDF's (and the Metallic BSDF's) stretch: Anisotropic clamped to [0, 1],
 * aspect = sqrt(1 - 0.9 Anisotropic), alpha_x = alpha / aspect, alpha_y = alpha aspect. */
float principled_anisotropic_stretch(float anisotropic)
{
  return inversesqrt(1.0 - 0.9 * clamp(anisotropic, 0.0, 1.0));
}

/* The Glossy BSDF's stretch: Anisotropy clamped to [-0.99, 0.99]; above 0 alpha_x = alpha (1 - a),
 * alpha_y = alpha / (1 - a), below alpha_x = alpha / (1 + a), alpha_y = alpha (1 + a); isotropic
 * within 1e-4 of 0 (Cycles' threshold). */
float glossy_anisotropic_stretch(float anisotropy)
{
  float a = clamp(anisotropy, -0.99, 0.99);
  if (abs(a) <= 1e-4) {
    return 1.0;
  }
  return a > 0.0 ? 1.0 - a : 1.0 / (1.0 + a);
}

/* p rotated by `angle` radians about the unit `axis`, counter-clockwise seen from its tip
 * (Rodrigues' formula, as Cycles' rotate_around_axis, util/math_float3.h) */
vec3 rotate_about_axis(vec3 p, vec3 axis, float angle)
{
  float c = cos(angle);
  float s = sin(angle);
  return p * c + cross(axis, p) * s + axis * (dot(axis, p) * (1.0 - c));
}

/* A BSDF closure `c` made anisotropic: its lobe stretched by `stretch` (above), its tangent the
 * Tangent input rotated about the BSDF's normal n by Rotation turns (x 2 pi), as Cycles rotates it
 * before the lobe's frame is built. The tangent's direction alone counts (the frame is made
 * perpendicular to the normal when shaded); both are weight-premultiplied as the closure's other
 * inputs, so that Mix and Add Shader mix them linearly (apply_closure_lobes takes the means). */
Closure closure_anisotropic(Closure c, float stretch, vec3 tangent, float rotation, vec3 n)
{
  vec3 t = tangent;
  float len2 = dot(t, t);
  /* no tangent (a zero vector linked, no UV map): no direction; the lobe shades isotropic then */
  t = len2 > 1e-20 ? t * inversesqrt(len2) : vec3(0.0);
  float n2 = dot(n, n);
  if (rotation != 0.0 && n2 > 1e-20) {
    t = rotate_about_axis(t, n * inversesqrt(n2), rotation * 2.0 * PI);
  }
  c.lobes.tangent = c.weight * t;
  c.lobes.stretch = c.weight * stretch;
  return c;
}
