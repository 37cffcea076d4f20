/* The subsurface's mean free path per channel (m) as Cycles' bssrdf_setup_radius sets it up
 * (kernel/closure/bssrdf.h), one function per method (the Principled BSDF's Subsurface Method, the
 * Subsurface Scattering node's): Radius x Scale, at least 0, over 4 pi for Christensen-Burley and
 * Random Walk; for Random Walk (Skin) times sqrt(3 (1 - alpha')), alpha' the single-scattering albedo
 * of the dipole that reflects the albedo (the base colour) at the IOR (within [1.01, 3.8], as
 * bssrdf_setup clamps it). Twin: addon/reference/subsurface.py's mean_free_path. */

vec3 subsurface_path(vec3 radius, float scale)
{
  return max(radius * scale, vec3(0.0)) * (0.25 * INV_PI);
}

/* Cycles' bssrdf_dipole_compute_Rd */
float subsurface_dipole_rd(float alpha_prime, float fourthird_a)
{
  float s = sqrt(3.0 * (1.0 - alpha_prime));
  return 0.5 * alpha_prime * (1.0 + exp(-fourthird_a * s)) * exp(-s);
}

/* Cycles' bssrdf_dipole_compute_alpha_prime: 12 bisection steps (0 below 1e-4, 0.999999 from 0.995) */
float subsurface_dipole_alpha_prime(float rd, float fourthird_a)
{
  if (rd < 1e-4) {
    return 0.0;
  }
  if (rd >= 0.995) {
    return 0.999999;
  }
  float x0 = 0.0;
  float x1 = 1.0;
  float xmid = 0.5;
  for (int i = 0; i < 12; i++) {
    xmid = 0.5 * (x0 + x1);
    if (subsurface_dipole_rd(xmid, fourthird_a) < rd) {
      x0 = xmid;
    }
    else {
      x1 = xmid;
    }
  }
  return xmid;
}

vec3 subsurface_path_skin(vec3 radius, float scale, vec3 albedo, float ior)
{
  float eta = clamp(ior, 1.01, 3.8);
  float inv_eta = 1.0 / eta;
  float f_dr = inv_eta * (-1.440 * inv_eta + 0.710) + 0.668 + 0.0636 * eta;
  float fourthird_a = (4.0 / 3.0) * (1.0 + f_dr) / (1.0 - f_dr);
  vec3 a = clamp(albedo, 0.0, 1.0);
  vec3 alpha_prime = vec3(subsurface_dipole_alpha_prime(a.r, fourthird_a),
                          subsurface_dipole_alpha_prime(a.g, fourthird_a),
                          subsurface_dipole_alpha_prime(a.b, fourthird_a));
  return max(radius * scale, vec3(0.0)) * sqrt(3.0 * (1.0 - alpha_prime));
}

/* The random walk's row (MaterialData's subsurface_walk: glsl/subsurface.glsl's subsurface_walk_at), one
 * function per method, as Cycles' svm_node_closure_bsdf and bssrdf_setup set the BSSRDF up: the
 * Anisotropy within [0, 0.9], the entry's IOR within [1.01, 3.8], its GGX alpha, the diffuse entry's
 * share. Twin: addon/reference/subsurface.py's walk_row. */

/* Christensen-Burley: no walk (an IOR of 0; Cycles' disk reflects the albedo as Lambert does) */
vec4 subsurface_walk_burley(float anisotropy)
{
  return vec4(clamp(anisotropy, 0.0, 0.9), 0.0, 0.0, 0.0);
}

/* Random Walk: the ray enters through the interface of this IOR and GGX alpha */
vec4 subsurface_walk_random(float anisotropy, float ior, float alpha)
{
  return vec4(clamp(anisotropy, 0.0, 0.9), clamp(ior, 1.01, 3.8), clamp(alpha, 0.0, 1.0), 0.0);
}

/* Random Walk (Skin): of its own IOR, a fixed roughness (alpha 1) and half the rays entering diffusely
 * (subsurface_entry_bounce) */
vec4 subsurface_walk_skin(float anisotropy, float ior)
{
  return vec4(clamp(anisotropy, 0.0, 0.9), clamp(ior, 1.01, 3.8), 1.0, 0.5);
}

/* The Principled BSDF's Random Walk entry: its IOR as the Specular IOR Level adjusts it (Cycles' eta: F0
 * times 2 level, ior_from_F0 of it with F0 within [0, 0.99], inverted below an IOR of 1), alpha its
 * Roughness within [0, 1] squared (-1: subsurface_walk_at takes the material's roughness, which the
 * closures' mean gives) */
vec4 subsurface_walk_principled(float anisotropy, float ior, float level)
{
  float eta = ior;
  if (level != 0.5) {
    float r = (ior - 1.0) / (ior + 1.0);
    float s = sqrt(clamp(r * r * 2.0 * level, 0.0, 0.99));
    eta = (1.0 + s) / (1.0 - s);
    eta = ior < 1.0 ? 1.0 / eta : eta;
  }
  return vec4(clamp(anisotropy, 0.0, 0.9), clamp(eta, 1.01, 3.8), -1.0, 0.0);
}

/* The Subsurface Scattering node (Cycles' svm_node_closure_bsdf, CLOSURE_BSSRDF_*: a BSSRDF of its
 * colour as albedo and weight, no specular layer): a diffuse base of its colour wholly below the
 * surface, `path` its mean free path (subsurface_path*), `walk` its random walk (subsurface_walk_*: the
 * node's Roughness is the entry's alpha itself) */
Closure closure_subsurface(vec4 color, vec3 path, vec4 walk, vec3 n)
{
  Closure c = closure_bsdf(max(color.rgb, 0.0), 0.0, 1.0, 0.0, n);
  c.lobes.subsurface = 1.0;
  c.lobes.subsurface_radius = path;
  c.lobes.subsurface_walk = walk;
  return c;
}
