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
 * random walk lights a flat slab; shadow edges are not diffused (docs/limits.md).
 *
 * Cycles' Random Walk methods light the subsurface by a walk from where the camera's ray enters
 * (refracted through a rough interface of the entry's IOR and roughness) to where it leaves, a Lambert
 * BSDF there: the light leaving is the Lambert base's times R / albedo, R the medium's reflectance for
 * the ray's entry direction, which the Anisotropy (a forward-scattering medium: more) and the entry's
 * IOR and roughness (a steep entry: less, a grazing one: more) change. subsurface_walk_at gives that
 * factor per channel at the view, from a table of R / albedo (subsurface_table: Monte Carlo walks of
 * Cycles' medium in a half-space, addon/reference/subsurface.py's compute_walk_table) over the
 * albedo, the Anisotropy and the entry cosine, weighted by the refracted rays' cosines. */

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
  /* the random walk's reflectance over its Lambert base at the view (subsurface_walk_at) */
  return color * s.subsurface_walk * subsurface_ramp(dot(s.n, l), s.subsurface_radius, s.curvature);
}
#endif

#ifdef SL_SUBSURFACE
/* The weights of the walk table's entry nodes (w0: the cosines (k / 6)^2 for k = 0..3, w1: k = 4..6 and
 * the diffuse entry) for a view at cos_v entering through an interface of IOR eta and GGX roughness
 * alpha, `share` of the rays entering diffusely (Random Walk (Skin): half), as Cycles'
 * subsurface_entry_bounce draws them: a microfacet normal from the view's visible normals
 * (microfacet_ggx_sample_vndf, Heitz 2018: its disk's points, here a quadrature of
 * SL_WALK_RINGS x SL_WALK_SPOKES points even in area over the half t.x >= 0, whose mirror image
 * across the plane of incidence refracts at the same cosine), the ray refracted through it by 1 / eta
 * (no total reflection: eta >= 1.01), lost where the view is at or below the horizon or the ray leaves
 * above the surface; each ray's cosine mu spread linearly in sqrt(mu) over its two nodes. Twin:
 * addon/reference/subsurface.py's entry_weights. */
void subsurface_entry_weights(float cos_v, float eta, float alpha, float share, out vec4 w0, out vec4 w1)
{
  float w[SL_WALK_MUS + 1];
  for (int k = 0; k <= SL_WALK_MUS; k++) {
    w[k] = 0.0;
  }
  if (cos_v > 0.0) {
    float sin_v = sqrt(max(1.0 - cos_v * cos_v, 0.0));
    /* the view stretched to the hemisphere's configuration (in the plane of incidence, xz); its length
     * is at least cos_v > 0 */
    float len = sqrt(alpha * alpha * sin_v * sin_v + cos_v * cos_v);
    float wx = alpha * sin_v / len;
    float wz = cos_v / len;
    bool tilted = wx * wx > 1e-7; /* Cycles' frame about it; along n any frame (the lobe is round) */
    float neta = 1.0 / eta;
    float each = (1.0 - share) / float(SL_WALK_RINGS * SL_WALK_SPOKES);
    for (int i = 0; i < SL_WALK_RINGS; i++) {
      float r = sqrt((float(i) + 0.5) / float(SL_WALK_RINGS));
      for (int j = 0; j < SL_WALK_SPOKES; j++) {
        float phi = PI * ((float(j) + 0.5) / float(SL_WALK_SPOKES) - 0.5);
        float tx = r * cos(phi);
        float ty = mix(sqrt(max(1.0 - tx * tx, 0.0)), r * sin(phi), 0.5 * (1.0 + wz));
        float tz = sqrt(max(1.0 - tx * tx - ty * ty, 0.0));
        vec3 h = tilted ? vec3(-wz * ty + wx * tz, tx, wx * ty + wz * tz) : vec3(tx, ty, tz);
        h = vec3(alpha * h.x, alpha * h.y, max(h.z, 0.0));
        float h2 = dot(h, h);
        /* a microfacet normal of no length (alpha 0 at the disk's rim: not one of these points) */
        h = h2 > 0.0 ? h * inversesqrt(h2) : vec3(0.0, 0.0, 1.0);
        float cos_hi = h.x * sin_v + h.z * cos_v;
        float root = sqrt(max(1.0 - neta * neta * (1.0 - cos_hi * cos_hi), 0.0));
        float wo_z = -neta * cos_v + (neta * cos_hi - max(root, 1e-7)) * h.z; /* Cycles' floor of the root */
        if (wo_z < 0.0) {
          float x = sqrt(-wo_z) * float(SL_WALK_MUS - 1);
          int k = min(int(floor(x)), SL_WALK_MUS - 2);
          float f = x - float(k);
          w[k] += each * (1.0 - f);
          w[k + 1] += each * f;
        }
      }
    }
  }
  w[SL_WALK_MUS] = share;
  w0 = vec4(w[0], w[1], w[2], w[3]);
  w1 = vec4(w[4], w[5], w[6], w[7]);
}

/* One table node's row (R / albedo at the entry nodes) dotted with the entry weights: texel (2 i, j)
 * holds entry nodes 0-3 of albedo node i and Anisotropy node j, texel (2 i + 1, j) nodes 4-7. */
float subsurface_walk_node(int i, int j, vec4 w0, vec4 w1)
{
  return dot(texelFetch(subsurface_table, ivec2(2 * i, j), 0), w0) +
         dot(texelFetch(subsurface_table, ivec2(2 * i + 1, j), 0), w1);
}

/* The walk's light over its Lambert base per channel of `albedo`, for the Anisotropy g and the entry
 * weights: the table bilinear between its nodes, even in sqrt(albedo) and in g, both clamped to it
 * (g to Cycles' [0, 0.9], bssrdf_setup's). Twin: walk_lookup / walk_factor. */
vec3 subsurface_walk_factor(vec3 albedo, float g, vec4 w0, vec4 w1)
{
  float y = clamp(g, 0.0, 0.9) * (float(SL_WALK_GS - 1) / 0.9);
  int j0 = min(int(floor(y)), SL_WALK_GS - 1);
  int j1 = min(j0 + 1, SL_WALK_GS - 1);
  float fy = y - float(j0);
  vec3 out_factor;
  for (int c = 0; c < 3; c++) {
    float x = sqrt(clamp(albedo[c], 0.0, 1.0)) * float(SL_WALK_ALBEDOS - 1);
    int i0 = min(int(floor(x)), SL_WALK_ALBEDOS - 1);
    int i1 = min(i0 + 1, SL_WALK_ALBEDOS - 1);
    float fx = x - float(i0);
    float low = mix(subsurface_walk_node(i0, j0, w0, w1), subsurface_walk_node(i1, j0, w0, w1), fx);
    float high = mix(subsurface_walk_node(i0, j1, w0, w1), subsurface_walk_node(i1, j1, w0, w1), fx);
    out_factor[c] = mix(low, high, fy);
  }
  return out_factor;
}

/* The random walk's factor at the view (surface.glsl's Surface.subsurface_walk): MaterialData's
 * subsurface_walk row (x the Anisotropy, y the entry's IOR, z its GGX alpha (below 0: the material's
 * `roughness` squared, the Principled BSDF's), w the diffuse entry's share: node_subsurface.glsl's
 * subsurface_walk_*), clamped as Cycles' bssrdf_setup clamps them; 1 for Christensen-Burley (an IOR of
 * 0: no walk; Cycles' disk reflects the albedo as Lambert does). */
vec3 subsurface_walk_at(vec3 n, vec3 v, vec3 albedo, vec4 walk, float roughness)
{
  if (!(walk.y > 0.0)) {
    return vec3(1.0);
  }
  float base = clamp(roughness, 0.0, 1.0);
  float alpha = walk.z < 0.0 ? base * base : walk.z;
  vec4 w0, w1;
  subsurface_entry_weights(dot(n, v), clamp(walk.y, 1.01, 3.8), clamp(alpha, 0.0, 1.0),
                           clamp(walk.w, 0.0, 1.0), w0, w1);
  return subsurface_walk_factor(albedo, walk.x, w0, w1);
}
#endif
