/* The anisotropic GGX lobe (SL_ANISOTROPY: compiled only into the Principled set's programs whose
 * materials have an anisotropic Principled, Glossy or Metallic BSDF), as Cycles 5.0 evaluates it
 * (kernel/closure/bsdf_microfacet.h: bsdf_aniso_D, bsdf_aniso_lambda, the height-correlated
 * 1 / (1 + Lambda_i + Lambda_o); Heitz 2014, "Understanding the Masking-Shadowing Function in
 * Microfacet-Based BRDFs", eqs. 85-86 and 72 with alpha_o^2 = alpha_x^2 cos^2 phi +
 * alpha_y^2 sin^2 phi). The seed's isotropic D (eq. 1.15) and Smith G (eqs. 1.16-1.17) are its
 * alpha_x = alpha_y case. Its inputs (the stretch k, the rotated tangent) come from
 * node_anisotropy.glsl; twin: addon/reference/anisotropy.py. */

#ifdef SL_ANISOTROPY
/* The lobe at a shading point (surface.glsl's AnisotropicLobe) about the unit normal n, from the
 * tangent t (any length: Cycles' make_orthonormals_tangent, y = normalize(n x t), x = y x n, so the
 * tangent's part along n drops out), the isotropic lobe's alpha and the stretch k: alpha_x =
 * alpha k, alpha_y = alpha / k, each at most 1 (bsdf_microfacet_ggx_setup saturates them). A
 * tangent of no direction across n (zero, or along n: Cycles' frame is NaN there) gives the
 * isotropic lobe in any frame. */
AnisotropicLobe anisotropic_lobe(vec3 n, vec3 t, float alpha, float stretch)
{
  AnisotropicLobe a;
  vec3 y = cross(n, t);
  float y2 = dot(y, y);
  /* guards the frame: t zero, or within ~1e-3 rad of n (float32's cross product loses the
   * direction below) */
  bool framed = y2 > 1e-6 * dot(t, t) && y2 > 1e-30;
  if (!framed) {
    vec3 other = abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    y = cross(n, other);
    y2 = dot(y, y);
  }
  a.y = y * inversesqrt(y2);
  a.x = cross(a.y, n);
  /* k: 1 without a frame; a BSDF-less closure's mean (0) is none either; within the Glossy
   * BSDF's extremes 1 / 100 .. 100 (its Anisotropy +-0.99) */
  float k = framed && stretch > 0.0 ? clamp(stretch, 0.01, 100.0) : 1.0;
  a.alpha_x = min(alpha * k, 1.0);
  a.alpha_y = min(alpha / k, 1.0);
  return a;
}

/* The isotropic lobe of roughness alpha about n (a coat: Cycles' coat is isotropic). */
AnisotropicLobe anisotropic_none(vec3 n, float alpha)
{
  return anisotropic_lobe(n, vec3(0.0), alpha, 1.0);
}

/* The perceptual roughness the lobe's isotropic approximations and its multiple-scattering
 * compensation take: (alpha_x alpha_y)^(1/4), as Cycles' microfacet_ggx_preserve_energy and
 * bsdf_microfacet_estimate_albedo (the isotropic roughness, unless a clamp at 1 shortened an axis). */
float anisotropic_roughness(AnisotropicLobe a)
{
  return sqrt(sqrt(a.alpha_x * a.alpha_y));
}

/* D(h) for the unit half vector h (Cycles' bsdf_aniso_D): 1 / (pi ax ay (hx^2 / ax^2 + hy^2 / ay^2 +
 * hz^2)^2). (ax, ay <= 1: the sum is at least |h|^2 = 1, never 0.) */
float D_GGXAnisotropic(AnisotropicLobe a, vec3 n, vec3 h)
{
  vec3 s = vec3(dot(h, a.x) / a.alpha_x, dot(h, a.y) / a.alpha_y, dot(h, n));
  float d = dot(s, s);
  return 1.0 / (PI * a.alpha_x * a.alpha_y * d * d);
}

/* Smith's Lambda towards the unit w (Cycles' bsdf_aniso_lambda): (sqrt(1 + (ax^2 wx^2 + ay^2 wy^2)
 * / wz^2) - 1) / 2, for w above the surface (wz > 0). */
float Lambda_GGXAnisotropic(AnisotropicLobe a, vec3 n, vec3 w)
{
  vec3 s = vec3(a.alpha_x * dot(w, a.x), a.alpha_y * dot(w, a.y), dot(w, n));
  return 0.5 * (length(s) / s.z - 1.0);
}

/* The height-correlated visibility G2 / (4 n.v n.l) = 1 / (4 n.v n.l (1 + Lambda_v + Lambda_l)),
 * written as Heitz's 0.5 / (n.l |(ax vx, ay vy, n.v)| + n.v |(ax lx, ay ly, n.l)|) (the form
 * Filament's V_SmithGGXCorrelated_Anisotropic takes: no 1 / n.v to overflow at grazing). n.v is
 * the surface's (floored at MIN_COS), n.l > 0 (shade_direct returns before). */
float V_SmithGGXCorrelatedAnisotropic(AnisotropicLobe a, vec3 n, vec3 v, float NoV, vec3 l, float NoL)
{
  vec2 vt = vec2(dot(v, a.x), dot(v, a.y));
  float t2 = dot(vt, vt);
  /* v at or below the horizon (its n.v floored): its part along the surface as the floored
   * cosine's, |vt|^2 = 1 - n.v^2, as the round lobe's Lambda(n.v) takes it (2 % apart at n.v = -0.2
   * otherwise); a no-op above it */
  vt *= t2 > 0.0 ? sqrt(max(1.0 - NoV * NoV, 0.0) / t2) : 0.0;
  float lv = length(vec3(a.alpha_x * vt.x, a.alpha_y * vt.y, NoV));
  float ll = length(vec3(a.alpha_x * dot(l, a.x), a.alpha_y * dot(l, a.y), NoL));
  return 0.5 / (NoL * lv + NoV * ll);
}

/* D V of the lobe towards l with half vector h (what principled_direct multiplies by F). */
float anisotropic_DV(AnisotropicLobe a, vec3 n, vec3 v, float NoV, vec3 l, float NoL, vec3 h)
{
  return D_GGXAnisotropic(a, n, h) * V_SmithGGXCorrelatedAnisotropic(a, n, v, NoV, l, NoL);
}

/* The normal the lobe's isotropic stand-ins reflect about (the world's prefiltered light, a sphere
 * light's representative point): Filament's bent normal for anisotropic reflections (Filament's
 * getReflectedVector, after McAuley's and Revie's "bent reflection vector"): the normal leaned, by
 * the anisotropy |ax - ay| / (ax + ay) times saturate(5 r), towards the one that faces v within
 * the plane across the lobe's long axis, where a stretched lobe spreads its reflection. */
vec3 anisotropic_bent_normal(AnisotropicLobe a, vec3 n, vec3 v, float roughness)
{
  float anisotropy = (a.alpha_x - a.alpha_y) / (a.alpha_x + a.alpha_y);
  vec3 across = anisotropy >= 0.0 ? a.y : a.x; /* the short axis: the long one's plane is across it */
  vec3 facing = v - across * dot(v, across);   /* v within the plane of n and the long axis */
  float f2 = dot(facing, facing);
  float bend = abs(anisotropy) * saturate(5.0 * roughness);
  /* v along the short axis (f2 -> 0): nothing to lean towards */
  vec3 bent = f2 > 1e-12 ? mix(n, facing * inversesqrt(f2), bend) : n;
  float b2 = dot(bent, bent);
  return b2 > 1e-12 ? bent * inversesqrt(b2) : n; /* n and facing opposite at bend 1/2 */
}

/* The reflection of v about the bent normal. */
vec3 anisotropic_reflection(Surface s)
{
  return reflect(-s.v, anisotropic_bent_normal(s.aniso, s.n, s.v, s.roughness));
}

/* v with its height above the surface floored as the surface floors n.v (NoV): below the horizon its
 * part along the surface scaled to the floored cosine's, as V_SmithGGXCorrelatedAnisotropic takes it;
 * along n (no part along the surface): n. A no-op above the floor. */
vec3 anisotropic_view_above(vec3 n, vec3 v, float NoV)
{
  vec3 vt = v - n * dot(v, n);
  float t2 = dot(vt, vt);
  return t2 > 1e-20 ? n * NoV + vt * sqrt(max(1.0 - NoV * NoV, 0.0) / t2) : n;
}

/* The view (above the horizon) in the lobe's hemisphere configuration, in the lobe's frame (x, y, n):
 * normalize(ax v.x, ay v.y, v.n) (Heitz 2018, section 3.2): the axis of its visible normals' cosine. */
vec3 anisotropic_view_stretched(AnisotropicLobe a, vec3 n, vec3 v)
{
  return normalize(vec3(a.alpha_x * dot(v, a.x), a.alpha_y * dot(v, a.y), dot(v, n)));
}

#  ifdef SL_LTC
/* Lights with a size: the lobe's integral over a light's polygon, int_P D V (n.l) dl (F = 1), by its
 * visible normals. The distribution of visible normals of anisotropic GGX is a clamped cosine about
 * the view stretched back to the hemisphere configuration, v_h = normalize(ax v.x, ay v.y, v.n),
 * moved by the linear map diag(ax, ay, 1) (Heitz 2018, "Sampling the GGX Distribution of Visible
 * Normals", sections 3-4: the standard configuration's visible normals). Reflected
 * through h = (l + v) / |l + v| (dl = 4 (v.h) dh), the lobe is f (n.l) dl = D_v(h) G2 / G1(v) dh: so
 * over the light's half vectors, mapped by diag(1 / ax, 1 / ay, 1), the visible normals' integral is
 * a clamped cosine's over a spherical polygon -- in closed form (Arvo 1995's edge terms, lights.glsl's
 * polygon_form_factor), exact for any alpha_x, alpha_y, view and tangent, with no fitted table.
 * Approximated: a great arc between two light directions has a curved image in half-vector space, so
 * each edge is split into pieces of at most ANISOTROPIC_PIECE radians as seen from the point (the
 * image of each piece taken as a great arc); and G2 / G1(v) = (1 + Lambda_v) / (1 + Lambda_v +
 * Lambda_l) is taken once, at the clipped outline's length-weighted mean direction. The polygon is
 * clipped at the surface's horizon first (Sutherland-Hodgman; above it every half vector faces both
 * the normal and the view, so no further clipping is needed). Twin: anisotropy.polygon_integral.
 * Against quadrature of the lobe over test_ltc.py's lights (small and large, at the mirror
 * direction, to the side, across the horizon; n.v 0.2-0.9; tests/test_anisotropy.py): 2.0 % mean,
 * 10 % worst (a light holding much of the lobe: G2 / G1(v) varies over it); the round lobe's
 * linearly transformed cosines err 3.7 % / 25 % at roughness 0.3 on the same lights. float32: where
 * a direction nears -v (a grazing view's mirror direction) h = u + v cancels, and a narrow lobe's
 * integral over a light that fills the sky there moves by up to ~2 % (tests/test_stability.py's
 * sweeps hold the GPU to the twin within that spread). */

/* Pieces an edge is split into: chords of at most this length between unit directions (~ the
 * angle, radians), at most ANISOTROPIC_PIECES of them. Against quadrature on tests/test_anisotropy.py's
 * area-light sphere (a 0.6 m square 1.5 m away, edges ~0.37 rad; mean error over the lit pixels' mean):
 * whole edges 6.8 %, pieces of 0.4 1.7 %, 0.2 0.43 %, 0.15 0.28 %, 0.1 0.15 %. */
#    define ANISOTROPIC_PIECE 0.15
#    define ANISOTROPIC_PIECES 16

/* A unit light direction u's half vector with v, in the lobe's hemisphere configuration:
 * (h.x / ax, h.y / ay, h.n), h = u + v (unnormalised: the edge terms take directions only). */
vec3 anisotropic_stretched_half(AnisotropicLobe a, vec3 n, vec3 v, vec3 u)
{
  vec3 h = u + v;
  return vec3(dot(h, a.x) / a.alpha_x, dot(h, a.y) / a.alpha_y, dot(h, n));
}

/* p / |p|, and 0 for 0 (a light edge-on through the shading point; two opposite directions'
 * midpoint) rather than NaN */
vec3 anisotropic_unit(vec3 p)
{
  return p * inversesqrt(max(dot(p, p), 1e-36));
}

/* theta g . z of the spherical edge from direction a to b (any lengths): the angle between them
 * times the unit normal of their plane, along z (Arvo 1995); 0 for parallel ones. */
float anisotropic_edge_term(vec3 a, vec3 b, vec3 z)
{
  vec3 c = cross(a, b);
  float s = length(c);
  return s > 0.0 ? atan2_accurate(s, dot(a, b)) / s * dot(c, z) : 0.0;
}

/* The integral over the polygon `poly` seen from the shading point (anisotropy.glsl's header): n the
 * unit normal, v the view, NoV its floored cosine. */
float anisotropic_polygon(AnisotropicLobe a, vec3 n, vec3 v, float NoV, LightPolygon poly)
{
  v = anisotropic_view_above(n, v, NoV);
  vec3 v_h = anisotropic_view_stretched(a, n, v);
  /* near unit scale, as polygon_form_factor takes it: a micrometre light's corners normalised */
  float extent = max(max(length(poly.to_centre), length(poly.x_half)), length(poly.y_half));
  float scale = exp2(-floor(log2(max(extent, 1e-30))));
  vec3 t = poly.to_centre * scale;
  /* each edge clipped at the horizon (Sutherland-Hodgman, streamed) and, once round, the horizon's
   * own edge from where the outline leaves the upper half-space to where it comes back; each taken in
   * pieces: the edge terms in the hemisphere configuration, the outline's mean */
  float sum = 0.0;
  vec3 mean = vec3(0.0);
  vec3 c_a = t + polygon_offset(poly, poly.sides - 1) * scale;
  float h_a = dot(c_a, n);
  vec3 leaves = n;  /* where the outline leaves the upper half-space, and where it returns */
  vec3 returns = n;
  bool left = false;
  int i = 0;
  do { /* tested at the end (glsl/README.md): a polygon has 4 sides or more */
    vec3 c_b = t + polygon_offset(poly, min(i, poly.sides - 1)) * scale;
    float h_b = dot(c_b, n);
    bool above_a = h_a > 0.0;
    bool above_b = h_b > 0.0;
    /* where the edge meets the horizon (taken only where it crosses it, h_a != h_b) */
    vec3 x = c_a + (c_b - c_a) * (h_a / (above_a != above_b ? h_a - h_b : 1.0));
    left = left || (above_a && !above_b);
    leaves = above_a && !above_b ? x : leaves;
    returns = !above_a && above_b ? x : returns;
    /* the edge's part above the horizon; last, the horizon's own edge (where the outline left it) */
    bool horizon = i == poly.sides;
    bool on = horizon ? left : above_a || above_b;
    vec3 p_a = horizon ? leaves : (above_a ? c_a : x);
    vec3 p_b = horizon ? returns : (above_b ? c_b : x);
    /* an edge wholly below adds nothing: taken along n, a point (an edge through the shading point
     * itself, a light edge-on, has no direction: a zero vector, not NaN) */
    vec3 u_a = on ? anisotropic_unit(p_a) : n;
    vec3 u_b = on ? anisotropic_unit(p_b) : n;
    float chord = length(u_b - u_a);
    int pieces = clamp(int(ceil(chord / ANISOTROPIC_PIECE)), 1, ANISOTROPIC_PIECES);
    float step = 1.0 / float(pieces);
    vec3 w = anisotropic_stretched_half(a, n, v, u_a);
    int j = 1;
    do {
      vec3 w_next = anisotropic_stretched_half(a, n, v, anisotropic_unit(mix(u_a, u_b, float(j) * step)));
      sum += anisotropic_edge_term(w, w_next, v_h);
      /* the outline's mean, each piece's midpoint weighted by its length (an edge of no length, a
       * corner on the horizon, weighs nothing: G2 / G1(v) stays continuous as it crosses) */
      mean += on ? mix(u_a, u_b, (float(j) - 0.5) * step) * (chord * step) : vec3(0.0);
      w = w_next;
    } while (++j <= pieces);
    c_a = c_b;
    h_a = h_b;
  } while (++i <= poly.sides && i <= AREA_ELLIPSE_SIDES);
  /* the visible normals' share over it: the clamped cosine about v_h over the polygon, F.v_h with
   * F = sum / (2 pi), over the hemisphere's projected area pi (1 + v_h.z) / 2 */
  float visible = abs(sum) / (PI * (1.0 + v_h.z));
  float NoL = dot(mean, n);
  if (NoL <= 0.0) {
    return 0.0; /* an outline along the horizon: no area */
  }
  float lambda_v = Lambda_GGXAnisotropic(a, n, v);
  return visible * (1.0 + lambda_v) / (1.0 + lambda_v + Lambda_GGXAnisotropic(a, n, normalize(mean)));
}
#  endif

/* The lobe's visible normals seen from a view, for sampling them (anisotropic_sample): the view above
 * the horizon, its stretched direction and a frame about it (Heitz 2018, section 4.1), Lambda(v). */
struct AnisotropicView {
  vec3 v;
  vec3 v_h;       /* in the lobe's frame (x, y, n) */
  vec3 t1;
  vec3 t2;
  float lambda_v;
  float NoV;
};

AnisotropicView anisotropic_view(AnisotropicLobe a, vec3 n, vec3 v, float NoV)
{
  AnisotropicView w;
  w.v = anisotropic_view_above(n, v, NoV);
  w.v_h = anisotropic_view_stretched(a, n, w.v);
  /* v_h along n: any frame about it */
  w.t1 = w.v_h.z < 0.9999 ? normalize(vec3(-w.v_h.y, w.v_h.x, 0.0)) : vec3(1.0, 0.0, 0.0);
  w.t2 = cross(w.v_h, w.t1);
  w.lambda_v = Lambda_GGXAnisotropic(a, n, w.v);
  w.NoV = NoV;
  return w;
}

/* The lobe's visible normal at the point p of the unit disc (Heitz 2018, "Sampling the GGX Distribution
 * of Visible Normals", listing 1: the hemisphere configuration's projected disc in the frame (t1, t2)
 * about v_h, its far half compressed by (1 + v_h.z) / 2, lifted and stretched back). Returns the light
 * direction l the half vector reflects v to; pdf: its density per steradian of l, D_v(h) / (4 v.h) =
 * D G1(v) / (4 n.v); weight: f (n.l) / pdf with F = 1, G2 / G1(v) = (1 + Lambda_v) / (1 + Lambda_v +
 * Lambda_l), 0 where l is below the horizon. */
vec3 anisotropic_sample_disc(AnisotropicLobe a, vec3 n, AnisotropicView w, vec2 p, out float pdf, out float VoH,
                             out float weight)
{
  float s = 0.5 * (1.0 + w.v_h.z);
  p.y = (1.0 - s) * sqrt(max(1.0 - p.x * p.x, 0.0)) + s * p.y;
  vec3 n_h = p.x * w.t1 + p.y * w.t2 + sqrt(max(1.0 - dot(p, p), 0.0)) * w.v_h;
  vec3 h = normalize(a.x * (a.alpha_x * n_h.x) + a.y * (a.alpha_y * n_h.y) + n * max(n_h.z, 0.0));
  VoH = dot(w.v, h);
  vec3 l = 2.0 * VoH * h - w.v;
  float NoL = dot(n, l);
  pdf = D_GGXAnisotropic(a, n, h) / ((1.0 + w.lambda_v) * 4.0 * w.NoV);
  weight = NoL > 0.0 ? (1.0 + w.lambda_v) / (1.0 + w.lambda_v + Lambda_GGXAnisotropic(a, n, l)) : 0.0;
  return l;
}

/* Sample i of `count` of the lobe's visible normals (anisotropic_sample_disc) at the i-th point of a
 * Fibonacci lattice on the unit square ((i + 1/2) / count, i times the golden ratio's fraction of a
 * turn) taken to the disc (radius sqrt, angle): over 630 Principled lobes and views its 32 points hold
 * the lobe's albedo to 0.79 % mean, a Hammersley set's to 1.2 %; its 16 points over 576: 1.4 % mean,
 * 6.1 % worst; tests/test_anisotropy.py's twenty: 2.2 % mean. */
vec3 anisotropic_sample(AnisotropicLobe a, vec3 n, AnisotropicView w, int i, int count, out float pdf,
                        out float VoH, out float weight)
{
  float r = sqrt((float(i) + 0.5) / float(count));
  float phi = 2.0 * PI * fract(float(i) * 0.61803399 + 0.5);
  return anisotropic_sample_disc(a, n, w, r * vec2(cos(phi), sin(phi)), pdf, VoH, weight);
}

/* The point of the unit disc's diameter with the share u of the disc's area on its one side: s = sin phi
 * with phi + sin(2 phi) / 2 = pi (u - 1/2) (a disc segment's area), by three steps of Newton's method
 * from phi / 2 (within 3e-4 of a strip's share for 16 strips). */
float anisotropic_disc_quantile(float u)
{
  float c = PI * (u - 0.5);
  float phi = 0.5 * c;
  int k = 0;
  do { /* tested at the end (glsl/README.md) */
    /* 1 + cos(2 phi) > 0.3 for the strips' u within 1/16 .. 15/16 (|phi| < 1.0): no division by 0 */
    phi -= (phi + 0.5 * sin(2.0 * phi) - c) / (1.0 + cos(2.0 * phi));
  } while (++k < 3);
  return sin(phi);
}

/* Strip i of `count` (anisotropic_environment): anisotropic_sample_disc at the point of the disc's diameter
 * along the lobe's long axis (x where alpha_x >= alpha_y, else y, in the disc's frame (t1, t2)) at the
 * strip's middle share. */
vec3 anisotropic_strip_sample(AnisotropicLobe a, vec3 n, AnisotropicView w, int i, int count, out float pdf,
                              out float VoH, out float weight)
{
  vec3 long_axis = a.alpha_x >= a.alpha_y ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
  vec2 d = vec2(dot(long_axis, w.t1), dot(long_axis, w.t2));
  float d2 = dot(d, d);
  /* the long axis along v_h (a view grazing along it) has no part on the disc: any direction */
  d = d2 > 1e-12 ? d * inversesqrt(d2) : vec2(1.0, 0.0);
  float along = anisotropic_disc_quantile((float(i) + 0.5) / float(count));
  return anisotropic_sample_disc(a, n, w, along * d, pdf, VoH, weight);
}

#  if defined(SL_ENV_UNIFORM) || defined(SL_ENV_MAP)
/* The world's light through the lobe, in the split sum's place: the lobe's own albedo (F = 1) times the
 * mean radiance it sees. No split-sum table holds an anisotropic lobe (its albedo strays 6.5 % mean, up
 * to 57 %, from the round lobe's of the same (alpha_x alpha_y)^(1/4) over 576 Principled lobes and
 * views), and the prefiltered world is round.
 * The radiance: the lobe's visible normals (Heitz 2018's disc, anisotropic_sample_disc) cut across its
 * long axis into ANISOTROPIC_WORLD_STRIPS strips of equal share at most, one per aspect alpha_long /
 * alpha_short (rounded up), each read once at its midpoint on the disc's diameter along the long axis
 * from the prefiltered world at the roughness whose GGX lobe covers the strip: 1 / (N pdf) sr (Krivanek
 * & Colbert 2008's filtered importance sampling on the prefiltered levels: a lobe of alpha covers ~4 pi
 * alpha^2 sr at its peak), at least the short axis's alpha (the strip spans the lobe's width); their mean
 * weighted by G2 / G1(v). A strip spans the lobe's narrow width and about as much along it, so one
 * round read covers it: the reads go along the long axis only, as many as the lobe is long (where
 * Filament and the glTF viewer read once about a bent normal).
 * The albedo: the mean G2 / G1(v) over ANISOTROPIC_WORLD_ALBEDO visible normals of a Fibonacci lattice
 * (no reads: 1.4 % mean, 6.1 % worst against quadrature over 576 lobes and views; the strips' own
 * midpoints miss the disc's rim, where the light falls under the horizon, and overestimate it by 12-14 %).
 * Against Cycles, forest and city worlds, metal spheres of roughness 0.2 / 0.35 / 0.6 and Anisotropic
 * 0.5-1 (rotation 0, 0.125, 0.25), mean error over the sphere: 4.05 % (worst 7.0 %; the round lobe's
 * split sum 4.6 %, 6.5 %), where 32 visible normals over the disc, each read, erred 4.1 % (7.4 %) at
 * 5.6-6.3x the round lobe's cost on a plane under the world; these 2.2-2.8x (Anisotropic 0.5-1). A read takes levels on the side of the
 * suns' split (world_sun_specular) that the lobe's own roughness takes: sharper ones would see a sun
 * the lights already draw. */
#    define ANISOTROPIC_WORLD_STRIPS 8
#    define ANISOTROPIC_WORLD_ALBEDO 16

vec3 anisotropic_environment(AnisotropicLobe a, vec3 n, vec3 v, float NoV)
{
  AnisotropicView w = anisotropic_view(a, n, v, NoV);
#    ifdef SL_ENV_MAP
  float suns = world_sun_specular(anisotropic_roughness(a));
  int clamped = int(env.info.y);
  bool split = clamped < int(env.info.x);
  float r0 = env_level_roughness(max(clamped - 1, 0));
  float r1 = env_level_roughness(min(clamped, int(env.info.x) - 1));
#    endif
  float narrow = min(a.alpha_x, a.alpha_y);
  int strips = clamp(int(ceil(max(a.alpha_x, a.alpha_y) / narrow)), 1, ANISOTROPIC_WORLD_STRIPS);
  vec3 radiance = vec3(0.0);
  float weights = 0.0;
  int i = 0;
  do { /* tested at the end (glsl/README.md) */
    float pdf, VoH, weight;
    vec3 l = anisotropic_strip_sample(a, n, w, i, strips, pdf, VoH, weight);
    /* a lobe of alpha^2 = 1 / (4 pi N pdf), at least the short axis's; a far tail's D underflows to 0 in
     * float32: the roughest */
    float alpha2 = max(1.0 / (4.0 * PI * float(strips) * max(pdf, 1e-30)), narrow * narrow);
    float roughness = clamp(sqrt(sqrt(alpha2)), MIN_PERCEPTUAL_ROUGHNESS, 1.0);
#    ifdef SL_ENV_MAP
    if (split) {
      roughness = mix(min(roughness, r0), max(roughness, r1), suns);
    }
#    endif
    radiance += weight > 0.0 ? env_prefiltered(l, roughness) * weight : vec3(0.0);
    weights += weight;
  } while (++i < strips);
  float albedo = 0.0;
  int k = 0;
  do { /* tested at the end (glsl/README.md) */
    float pdf, VoH, weight;
    anisotropic_sample(a, n, w, k, ANISOTROPIC_WORLD_ALBEDO, pdf, VoH, weight);
    albedo += weight;
  } while (++k < ANISOTROPIC_WORLD_ALBEDO);
  /* every strip's light under the horizon (a grazing view of a rough lobe): no light to weigh */
  return weights > 0.0 ? radiance / weights * (albedo / float(ANISOTROPIC_WORLD_ALBEDO)) : vec3(0.0);
}
#  endif

/* The lobe of a sphere light's widened stand-in (lights.glsl's size_lobe_weights: alpha_wide^2 =
 * alpha^2 + theta^2): each axis widened by the disc alike, in quadrature. */
AnisotropicLobe anisotropic_widened(AnisotropicLobe a, float alpha, float alpha_wide)
{
  float theta2 = max(alpha_wide * alpha_wide - alpha * alpha, 0.0);
  a.alpha_x = min(sqrt(a.alpha_x * a.alpha_x + theta2), 1.0);
  a.alpha_y = min(sqrt(a.alpha_y * a.alpha_y + theta2), 1.0);
  return a;
}
#endif
