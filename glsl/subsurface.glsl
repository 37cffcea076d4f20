/* The Translucent BSDF and the Principled BSDF's subsurface (and the Subsurface Scattering node), for
 * the physically based model's Principled set: SL_TRANSLUCENT, SL_SUBSURFACE. Twin:
 * addon/reference/subsurface.py; the approximation and its measured error: docs/shading/pbr.md,
 * docs/limits.md.
 *
 * The subsurface is pre-integrated in the forward shader (no screen-space pass): the light a point
 * receives is the irradiance around it convolved with Cycles' Christensen-Burley profile (Christensen
 * & Burley 2015, "Approximate Reflectance Profiles for Efficient Subsurface Scattering"; Cycles'
 * bssrdf_burley_eval, kernel/closure/bssrdf.h), taken per light on the surface's curvature: near a
 * light's terminator the irradiance falls as a ramp, max(0, n.l), whose convolution with the profile
 * has a closed form (subsurface_ramp), so light reaches past the terminator by the profile's width
 * over the radius of curvature. A flat surface (no curvature) is lit as by Lambert's law, as Cycles'
 * random walk lights a flat slab; shadow edges are not diffused (docs/limits.md). */

#if defined(SL_SUBSURFACE) || defined(SL_TRANSLUCENT)
/* Cycles' bsdf_translucent_eval: a Lambertian lobe on the far side of the normal, f (n.l) per unit
 * irradiance = colour max(-n.l, 0) / pi (lit from behind). */
vec3 translucent_direct(vec3 color, vec3 n, vec3 l)
{
  return color * (max(-dot(n, l), 0.0) * INV_PI);
}
#endif

#ifdef SL_SUBSURFACE
/* Ki_2(y) / pi, the Bickley-Naylor function of order 2 over pi, y >= 0: the ramp max(0, x)'s
 * convolution with a 2D kernel exp(-r) / (2 pi r) exceeds the ramp by it at |x| = y (the kernel's
 * points lie at an exponential distance r in a uniform direction psi: E[max(0, r cos psi - y)] =
 * int_0^{pi/2} cos psi exp(-y / cos psi) dpsi / pi). Our rational fit, 2.7e-4 of Ki_2(0) = 1 at
 * most over y in [0, 40] (tests/test_subsurface.py holds it to a quadrature), exact at 0. */
float subsurface_bickley(float y)
{
  return exp(-y) * (1.0 + y * (2.79411438 + 0.3249977 * y)) / (PI * (1.0 + y * (3.33465849 + 1.20353839 * y)));
}

/* The irradiance's falloff max(0, n.l) convolved with Cycles' Burley profile of width d (m) on a
 * surface of curvature `curvature` (1/m): the profile's density (e^{-r/d} + e^{-r/3d}) / (8 pi d r)
 * is 1/4 of the kernel of scale d and 3/4 of the kernel of scale 3d, each adding its scale over the
 * radius of curvature times subsurface_bickley to the ramp (the irradiance near the terminator is
 * n.l ~ z / R at a distance z along the surface; beyond a few widths the ramp itself). Per channel. */
vec3 subsurface_ramp(float NoL, vec3 d, float curvature)
{
  vec3 rho = d * curvature;
  /* the ramp's approximation holds for profiles narrow against the radius: beyond rho = 1 (a profile
   * as wide as the object) it would add more than the whole sphere's light */
  rho = min(rho, vec3(1.0));
  float a = abs(NoL);
  /* rho = 0 (a flat surface, or a channel of no radius): the ramp exactly */
  vec3 near = vec3(0.0);
  for (int c = 0; c < 3; c++) {
    float r = rho[c];
    if (r > 0.0) {
      near[c] = 0.25 * r * subsurface_bickley(a / r) + 0.75 * (3.0 * r) * subsurface_bickley(a / (3.0 * r));
    }
  }
  return vec3(max(NoL, 0.0)) + near;
}

/* The curvature (1/m) of the surface of interpolated normal n at p: how fast the normal turns along
 * the surface, from screen derivatives, |dn| / |dp| over both screen axes (a sphere's 1 / radius; a
 * flat face's 0). Every fragment of the quad must run it (derivatives). */
float subsurface_curvature(vec3 n, vec3 p)
{
  vec3 nx = dFdx(n);
  vec3 ny = dFdy(n);
  vec3 px = dFdx(p);
  vec3 py = dFdy(p);
  float dp2 = dot(px, px) + dot(py, py);
  /* a fragment whose quad spans no distance (degenerate): no curvature measured */
  return dp2 > 1e-30 ? sqrt((dot(nx, nx) + dot(ny, ny)) / dp2) : 0.0;
}

/* The subsurface's f (n.l) towards l per unit irradiance (Cycles' svm_node_closure_bsdf: the BSSRDF
 * takes Subsurface Weight of the diffuse base, its albedo the base colour): the base's colour under
 * the dielectric layer, times the weight, over pi, times the convolved falloff. */
vec3 subsurface_direct(Surface s, vec3 l)
{
  vec3 color = s.base_color * ((1.0 - s.metalness) * saturate(1.0 - s.layers.layer) * s.subsurface * INV_PI);
#  ifdef SL_TRANSMISSION
  /* under what the glass's share leaves, as the diffuse (Cycles' svm_node_closure_bsdf weighs its
   * subsurface by 1 - Transmission Weight, kernel/svm/closure.h) */
  color *= 1.0 - s.transmission.share;
#  endif
  return color * subsurface_ramp(dot(s.n, l), s.subsurface_radius, s.curvature);
}
#endif
