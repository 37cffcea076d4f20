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
 * albedo, the Anisotropy and the entry cosine, weighted by the refracted rays' cosines. The same walks
 * give the walk's drift along the entering ray (n.l taken where it leaves on average:
 * subsurface_drift_cosine) and its gain on a convex surface (subsurface_walk_curved); a light's size
 * smooths the terminator (subsurface_ramp_sized) and a close light's own falloff over the profile's
 * spread is taken to second order (subsurface_curved_light). */

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
vec3 subsurface_ramp(vec3 NoL, vec3 d, float curvature)
{
  vec3 rho = d * curvature;
  /* the ramp's approximation holds for profiles narrow against the radius: beyond rho = 1 (a profile
   * as wide as the object) it would add more than the whole sphere's light */
  rho = min(rho, vec3(1.0));
  vec3 a = abs(NoL);
  /* rho = 0 (a flat surface, or a channel of no radius): the ramp exactly */
  vec3 near = vec3(0.0);
  for (int c = 0; c < 3; c++) {
    float r = rho[c];
    if (r > 0.0) {
      near[c] = 0.25 * r * subsurface_bickley(a[c] / r) + 0.75 * (3.0 * r) * subsurface_bickley(a[c] / (3.0 * r));
    }
  }
  return max(NoL, vec3(0.0)) + near;
}

/* Ki_3(y) / pi, y >= 0: the integral of Ki_2 from y to infinity over pi (Ki_3' = -Ki_2), the ramp's
 * excess integrated across the terminator (subsurface_ramp_sized). Our rational fit, 5.5e-5 of
 * Ki_3(0) = pi / 4 at most over y in [0, 40] (tests/test_subsurface.py holds it to a quadrature),
 * exact at 0 with its slope -Ki_2(0) = -1 there. */
float subsurface_bickley3(float y)
{
  /* far past the profile (a width of 1e-30 m): its value underflows, y^2 would overflow */
  y = min(y, 80.0);
  return exp(-y) * (0.78539816 + y * (1.28824763 + 0.10408297 * y)) / (PI * (1.0 + y * (1.91348736 + 0.45483162 * y)));
}

/* subsurface_ramp under a light of angular radius asin(size) (subsurface_light_shape): the light's
 * disc spreads n.l over its points (a semicircle distribution of radius size about the centre's n.l),
 * here a box of the same variance, n.l +- sqrt(3) / 2 size, whose average of the point's ramp is the
 * horizon-clipped irradiance of the light, (x + w)^2 / (4 w) across it: within 1.5-2 % of the exact
 * cap's (Snyder's) at sizes 0.05-0.3 and 10 % at 0.6, relative and floored at a quarter of the size
 * (the plain size as the box's half-width: 13-15 %); convolved with the profile it is the box average
 * of subsurface_ramp: the ramp's part in closed form, the profile's excess by its antiderivative (the
 * Bickley function one order up, subsurface_bickley3). A size of 0 (a point, a sun): the point's. */
vec3 subsurface_ramp_sized(vec3 NoL, vec3 d, float curvature, float size)
{
  /* a light smaller than 1e-4 (or none): the point's ramp (the box's difference quotient loses
   * float32 precision below) */
  if (!(size > 1e-4)) {
    return subsurface_ramp(NoL, d, curvature);
  }
  size *= 0.8660254; /* the box's half-width: the disc's variance */
  vec3 rho = min(d * curvature, vec3(1.0)); /* clamped as subsurface_ramp clamps it */
  vec3 out_ramp;
  for (int c = 0; c < 3; c++) {
    float x = NoL[c];
    /* max(x, 0) averaged over [x - size, x + size] */
    float ramp = x >= size ? x : (x <= -size ? 0.0 : (x + size) * (x + size) / (4.0 * size));
    float r = rho[c];
    float near = 0.0;
    if (r > 0.0) {
      /* the excess's antiderivative from 0 (odd in x) at both ends of the box */
      float ends[2];
      for (int k = 0; k < 2; k++) {
        float e = k == 0 ? x + size : x - size;
        float a = abs(e);
        float part = 0.25 * r * r * (0.25 - subsurface_bickley3(a / r)) +
                     0.75 * (9.0 * r * r) * (0.25 - subsurface_bickley3(a / (3.0 * r)));
        ends[k] = e < 0.0 ? -part : part;
      }
      near = (ends[0] - ends[1]) / (2.0 * size);
    }
    out_ramp[c] = ramp + near;
  }
  return out_ramp;
}

/* How a light is seen from p, for the subsurface (subsurface_direct): x the sine of the angular radius
 * of the sphere it is seen as (subsurface_ramp_sized): a point or spot light of radius r, r / d (a
 * sphere) or r / sqrt(d^2 + r^2) (Cycles' disc facing the point: soft falloff); an area light, the
 * disc of its area as seen from p (its area times the cosine at the light, over pi), likewise; a sun,
 * and a true point, 0; y 1 / its distance (a sun's 0: subsurface_curved_light). */
vec2 subsurface_light_shape(LightData light, vec3 p)
{
  int kind = int(light.position_kind.w);
  if (kind == LIGHT_SUN) {
    return vec2(0.0);
  }
  vec3 to_light = light.position_kind.xyz - p;
  float d2 = dot(to_light, to_light);
  float r2 = 0.0;
  float disc = light.shape.y; /* 1: a disc facing p, 0: a sphere */
#ifdef SL_HAS_AREA
  if (kind == LIGHT_AREA) {
    /* behind the light (a cosine below 0): no light to size */
    float facing = d2 > 0.0 ? max(dot(light.direction_cone.xyz, -to_light) * inversesqrt(d2), 0.0) : 0.0;
    r2 = area_light_area(light) * facing * INV_PI;
    disc = 1.0;
  }
#endif
  if (kind == LIGHT_POINT || kind == LIGHT_SPOT) {
    r2 = light.shape.x * light.shape.x;
  }
  /* at or inside the light: the whole hemisphere; at its centre no distance (E_Point's: no light) */
  float sine = r2 > 0.0 ? sqrt(min(r2 / max(d2 + disc * r2, 1e-30), 1.0)) : 0.0;
  return vec2(sine, d2 > 0.0 ? inversesqrt(d2) : 0.0);
}

/* The irradiance's own curvature over the profile's spread, per channel, added to the pre-integrated
 * falloff (which holds n.l linear about the point): a point light at distance 1 / u seen at cosine c on
 * a surface of curvature k (a sphere) has, averaged over points spread by sigma^2 = 7 d^2 per axis (the
 * profile's second moment), irradiance E (c + sigma^2 q), q = -(u + k c)(3 c u + k) + (1 - c^2)
 * (7.5 c u^2 + 3 k u) (to second order; a sun, u = 0: -k^2 c, a cosine's curvature): near a close
 * light's brightest point the walks leave where it is dimmer (on the sphere of radius 0.9 m under a
 * point light 1 m off, -1.9 % of the light at Scale 0.2). Faded out within 4 widths of the terminator
 * (the ramp's own there) and held to widths of 0.1 of the radius or distance. */
vec3 subsurface_curved_light(float c, vec3 d, float curvature, float u)
{
  float k = max(curvature, 0.0);
  float q = -(u + k * c) * (3.0 * c * u + k) + (1.0 - c * c) * (7.5 * c * u * u + 3.0 * k * u);
  /* the widths of the profile against the surface's and the light's curvature */
  float reach = k + u;
  vec3 rho = min(d * reach, vec3(0.1));
  vec3 fade = clamp(c / max(4.0 * rho, vec3(1e-6)), 0.0, 1.0);
  /* sigma^2 = 7 d^2, d held to 0.1 / reach (a reach of 0: no curvature to take) */
  vec3 sigma2 = reach > 0.0 ? 7.0 * (rho * rho) / (reach * reach) : vec3(0.0);
  return sigma2 * (q * fade);
}

/* The ramp at one n.l for every channel. */
vec3 subsurface_ramp(float NoL, vec3 d, float curvature)
{
  return subsurface_ramp(vec3(NoL), d, curvature);
}

/* n.l per channel where the walk leaves on average: `drift` (Surface.subsurface_drift, in units of
 * the mean free path d) times d away from the viewer along the surface, where the normal has turned
 * by the curvature times that distance (d times the curvature clamped to 1, as subsurface_ramp clamps
 * it), so n.l by that times the light's cosine to the drift's direction (first order). A camera's ray
 * entering at a grazing angle walks on forward: near a terminator it leaves farther towards the unlit
 * side (or the lit one), which the profile's pre-integration about the entry point does not see. Twin:
 * drift_cosine. */
vec3 subsurface_drift_cosine(float NoL, vec3 n, vec3 v, vec3 l, vec3 drift, vec3 d, float curvature)
{
  vec3 tangent = (n * dot(n, v)) - v; /* away from the viewer along the surface */
  float len2 = dot(tangent, tangent);
  /* the view along n: the walk drifts nowhere on average */
  float toward = len2 > 1e-12 ? dot(tangent, l) * inversesqrt(len2) : 0.0;
  return vec3(NoL) + drift * min(d * curvature, vec3(1.0)) * toward;
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

vec3 subsurface_walk_curved(Surface s); /* below */

/* The subsurface's f (n.l) towards l per unit irradiance (Cycles' svm_node_closure_bsdf: the BSSRDF
 * takes Subsurface Weight of the diffuse base, its albedo the base colour): the base's colour under
 * the dielectric layer, times the weight, over pi, times the convolved falloff, under a light seen as
 * `light` (subsurface_light_shape: its sine and inverse distance). */
vec3 subsurface_direct(Surface s, vec3 l, vec2 light)
{
  vec3 color = s.base_color * ((1.0 - s.metalness) * saturate(1.0 - s.layers.layer) * s.subsurface * INV_PI);
#  ifdef SL_TRANSMISSION
  /* under what the glass's share leaves, as the diffuse (Cycles' svm_node_closure_bsdf weighs its
   * subsurface by 1 - Transmission Weight, kernel/svm/closure.h) */
  color *= 1.0 - s.transmission.share;
#  endif
  /* the random walk's reflectance over its Lambert base at the view on the surface's curvature
   * (subsurface_walk_curved), its light taken where it leaves on average (subsurface_drift_cosine) */
  vec3 NoL = subsurface_drift_cosine(dot(s.n, l), s.n, s.v, l, s.subsurface_drift, s.subsurface_radius,
                                     s.curvature);
  vec3 falloff = subsurface_ramp_sized(NoL, s.subsurface_radius, s.curvature, light.x) +
                 subsurface_curved_light(dot(s.n, l), s.subsurface_radius, s.curvature, light.y);
  /* the second-order term is not to take more than the light there */
  return color * subsurface_walk_curved(s) * max(falloff, vec3(0.0));
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
void subsurface_entry_weights(float cos_v, float eta, float alpha, float share, out vec4 w0, out vec4 w1,
                              out vec4 f0, out vec4 f1)
{
  float w[SL_WALK_MUS + 1];
  float f_[SL_WALK_MUS + 1]; /* the drift's: each ray's weight times its part along the surface */
  for (int k = 0; k <= SL_WALK_MUS; k++) {
    w[k] = 0.0;
    f_[k] = 0.0;
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
        float nk = neta * cos_hi - max(root, 1e-7); /* Cycles' floor of the root */
        vec3 wo = vec3(-neta * sin_v, 0.0, -neta * cos_v) + nk * h;
        if (wo.z < 0.0) {
          float x = sqrt(-wo.z) * float(SL_WALK_MUS - 1);
          int k = min(int(floor(x)), SL_WALK_MUS - 2);
          float f = x - float(k);
          w[k] += each * (1.0 - f);
          w[k + 1] += each * f;
          /* its component along the surface away from the viewer (-x: the table holds the drift per
           * unit sine); its mirror image across the plane of incidence cancels its sideways part */
          f_[k] -= each * (1.0 - f) * wo.x;
          f_[k + 1] -= each * f * wo.x;
        }
      }
    }
  }
  w[SL_WALK_MUS] = share;
  w0 = vec4(w[0], w[1], w[2], w[3]);
  w1 = vec4(w[4], w[5], w[6], w[7]);
  /* the diffuse entry's rays come from every azimuth: no drift */
  f0 = vec4(f_[0], f_[1], f_[2], f_[3]);
  f1 = vec4(f_[4], f_[5], f_[6], 0.0);
}

/* One table node's row dotted with the entry weights: per albedo node i and Anisotropy node j, texels
 * (6 i + part, j) and (6 i + part + 1, j) hold entry nodes 0-3 and 4-7 of R / albedo (part 0), of the
 * drift's moment per unit sine (part 2; node 7 none) and of the convex gain per unit rho (part 4):
 * gpu_library's subsurface_table. */
float subsurface_walk_node(int i, int j, int part, vec4 w0, vec4 w1)
{
  return dot(texelFetch(subsurface_table, ivec2(6 * i + part, j), 0), w0) +
         dot(texelFetch(subsurface_table, ivec2(6 * i + part + 1, j), 0), w1);
}

/* One part of the table (subsurface_walk_node) per channel of `albedo` at Anisotropy g, bilinear
 * between its nodes, even in sqrt(albedo) and in g, both clamped to it (g to Cycles' [0, 0.9],
 * bssrdf_setup's). Twin: walk_lookup. */
vec3 subsurface_walk_lookup(vec3 albedo, float g, int part, vec4 w0, vec4 w1)
{
  float y = clamp(g, 0.0, 0.9) * (float(SL_WALK_GS - 1) / 0.9);
  int j0 = min(int(floor(y)), SL_WALK_GS - 1);
  int j1 = min(j0 + 1, SL_WALK_GS - 1);
  float fy = y - float(j0);
  vec3 value;
  for (int c = 0; c < 3; c++) {
    float x = sqrt(clamp(albedo[c], 0.0, 1.0)) * float(SL_WALK_ALBEDOS - 1);
    int i0 = min(int(floor(x)), SL_WALK_ALBEDOS - 1);
    int i1 = min(i0 + 1, SL_WALK_ALBEDOS - 1);
    float fx = x - float(i0);
    float low = mix(subsurface_walk_node(i0, j0, part, w0, w1), subsurface_walk_node(i1, j0, part, w0, w1), fx);
    float high = mix(subsurface_walk_node(i0, j1, part, w0, w1), subsurface_walk_node(i1, j1, part, w0, w1), fx);
    value[c] = mix(low, high, fy);
  }
  return value;
}

/* One part of the table per channel at its node nearest in sqrt(albedo) and g (the drift's and the
 * convex gain's: smooth in both, a node's step moves them by ~3 %; a quarter of the bilinear lookup's
 * texel reads, which dominate the subsurface's cost). Twin: walk_lookup(nearest=True). */
vec3 subsurface_walk_nearest(vec3 albedo, float g, int part, vec4 w0, vec4 w1)
{
  int j = min(int(floor(clamp(g, 0.0, 0.9) * (float(SL_WALK_GS - 1) / 0.9) + 0.5)), SL_WALK_GS - 1);
  vec3 value;
  for (int c = 0; c < 3; c++) {
    int i = min(int(floor(sqrt(clamp(albedo[c], 0.0, 1.0)) * float(SL_WALK_ALBEDOS - 1) + 0.5)), SL_WALK_ALBEDOS - 1);
    value[c] = subsurface_walk_node(i, j, part, w0, w1);
  }
  return value;
}

/* The random walk's factor at the view (surface.glsl's Surface.subsurface_walk), its mean drift away
 * from the viewer in units of the mean free path (Surface.subsurface_drift) and its gain on a convex
 * surface per unit rho over the factor (Surface.subsurface_gain): MaterialData's subsurface_walk row
 * (x the Anisotropy, y the entry's IOR, z its GGX alpha (below 0: the material's `roughness` squared,
 * the Principled BSDF's), w the diffuse entry's share: node_subsurface.glsl's subsurface_walk_*),
 * clamped as Cycles' bssrdf_setup clamps them; 1, no drift and no gain for Christensen-Burley (an IOR
 * of 0: no walk; Cycles' disk reflects the albedo as Lambert does). Twin: walk_factor. */
vec3 subsurface_walk_at(vec3 n, vec3 v, vec3 albedo, vec4 walk, float roughness, out vec3 drift,
                        out vec3 gain)
{
  drift = vec3(0.0);
  gain = vec3(0.0);
  if (!(walk.y > 0.0)) {
    return vec3(1.0);
  }
  float base = clamp(roughness, 0.0, 1.0);
  float alpha = walk.z < 0.0 ? base * base : walk.z;
  vec4 w0, w1, f0, f1;
  subsurface_entry_weights(dot(n, v), clamp(walk.y, 1.01, 3.8), clamp(alpha, 0.0, 1.0),
                           clamp(walk.w, 0.0, 1.0), w0, w1, f0, f1);
  vec3 factor = subsurface_walk_lookup(albedo, walk.x, 0, w0, w1);
  /* a factor of 0 (an albedo of 0 reflects nothing): no drift or gain to speak of */
  vec3 inv = mix(vec3(0.0), 1.0 / max(factor, vec3(1e-6)), greaterThan(factor, vec3(1e-6)));
  drift = subsurface_walk_nearest(albedo, walk.x, 2, f0, f1) * inv;
  gain = subsurface_walk_nearest(albedo, walk.x, 4, w0, w1) * inv;
  return factor;
}

/* The factor alone. */
vec3 subsurface_walk_at(vec3 n, vec3 v, vec3 albedo, vec4 walk, float roughness)
{
  vec3 drift, gain;
  return subsurface_walk_at(n, v, albedo, walk, roughness, drift, gain);
}

/* The walk's factor at the view on the surface's curvature: a convex surface's nearer boundary lets
 * more of the walks out, R growing by the gain times rho = d x curvature per channel (walked in a
 * ball: addon/reference/subsurface.py's walk_moments), linearly up to rho = 0.1 (at 0.1 the ball's
 * gain is 0.97 of the linear one, at 0.2 0.72, at 1 0.17), held beyond. Twin: convex_gain. */
vec3 subsurface_walk_curved(Surface s)
{
  return s.subsurface_walk * (1.0 + s.subsurface_gain * min(s.subsurface_radius * s.curvature, vec3(0.1)));
}
#endif
