/* The closure nodes drawn beside the Principled BSDF's lobes, by the physically based model's
 * Principled set (glsl/node_closure_bsdfs.glsl gives their inputs per fragment: MaterialData's
 * closure rows), each only in programs whose materials use it:
 *   SL_DIFFUSE_ROUGHNESS  the Diffuse BSDF's Roughness: Cycles' Oren-Nayar (bsdf_oren_nayar.h) of the
 *                         Blender that read the graph (materials/surface.py's oren_nayar: one
 *                         SL_OREN_NAYAR_<RULE>), in place of the base's Lambert: Fujii's improved
 *                         Oren-Nayar with the OpenPBR energy-preserving multiple-scattering term
 *                         (FUJII_MULTISCATTER: 4.5, 5.0), or alone (FUJII: 4.2);
 *   SL_VELVET             the Sheen BSDF's Ashikhmin distribution (bsdf_ashikhmin_velvet.h);
 *   SL_TOON               the Toon BSDF's Diffuse and Glossy components (bsdf_toon.h).
 * (The Sheen BSDF's Microfiber distribution is the Principled BSDF's sheen: principled.glsl.)
 * Each lobe's f (n.l) is Cycles' bsdf eval (which holds the light's cosine); twins in
 * addon/reference/closures.py. Lights: each lobe at the light's direction (an area or sphere light
 * at its representative direction, as the surface's diffuse lobe); the world: each lobe's
 * directional albedo times the world's light around its direction (docs/limits.md). */

#ifdef SL_CLOSURE_BSDFS

/* Fujii's G(theta) (bsdf_oren_nayar_G): the directional albedo's Oren-Nayar part, E = A pi + B G;
 * below cos 1e-6 tan(theta) is unstable (Cycles falls back to its Taylor expansion there). */
float oren_nayar_G(float cos_theta)
{
  if (cos_theta < 1e-6) {
    return (0.5 * PI - 2.0 / 3.0) - cos_theta;
  }
  float sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
  float theta = acos_accurate(cos_theta);
  return sin_theta * (theta - 2.0 / 3.0 - sin_theta * cos_theta) +
         2.0 / 3.0 * (sin_theta / cos_theta) * (1.0 - sin_theta * sin_theta * sin_theta);
}

/* Ashikhmin's velvet f (n.l) for a view at cos_v and a light at cos_l with half vector h
 * (bsdf_ashikhmin_velvet_eval; 1 / sigma^2 given): D the inverted Gaussian of cot^2 of n.h, G
 * Cook-Torrance's V-cavity, f (n.l) = D G / (4 n.v). 0 off both hemispheres and where h lies along
 * n (sin^2 of n.h vanishing, where Cycles returns 0 too). */
float velvet_eval(float cos_v, float cos_l, float cos_nh, float cos_hl, float inv_sigma2)
{
  if (!(cos_v > 0.0 && cos_l > 0.0) || !(abs(cos_nh) < 1.0 - 1e-5 && cos_hl > 1e-5)) {
    return 0.0;
  }
  float ratio = max(cos_nh / cos_hl, 1e-5); /* Cycles' own floor of the V-cavity's ratio */
  float G = min(1.0, 2.0 * ratio * min(cos_v, cos_l));
  float sin2 = 1.0 - cos_nh * cos_nh;
  float D = exp(-cos_nh * cos_nh / sin2 * inv_sigma2) * inv_sigma2 * INV_PI / (sin2 * sin2);
  return 0.25 * D * G / cos_v;
}

/* The toon's intensity at `angle` from its axis (bsdf_toon_get_intensity): 1 within Size, then a
 * linear ramp over Smooth (both in radians), 0 beyond. */
float toon_intensity(float size, float smooth_, float angle)
{
  if (angle < size) {
    return 1.0;
  }
  return angle < size + smooth_ && smooth_ != 0.0 ? 1.0 - (angle - size) / smooth_ : 0.0;
}

/* The toon's f (n.l) at `angle` from its axis (bsdf_diffuse_toon_eval / bsdf_glossy_toon_eval):
 * its intensity over the cone it samples, of half-angle min(Size + Smooth, pi / 2), uniformly
 * (pdf 1 / (2 pi (1 - cos))); 1 - cos as 2 sin^2(x / 2), exact for the Size floor's 1.6e-5 rad. */
float toon_eval(vec2 shape, float angle)
{
  float cone = min(shape.x + shape.y, 0.5 * PI);
  if (!(angle < cone)) {
    return 0.0;
  }
  float s = sin(0.5 * cone);
  return toon_intensity(shape.x, shape.y, angle) / (4.0 * PI * s * s);
}

/* The toon's directional albedo: its intensity integrated over the cone it samples, over the cone's
 * solid angle (1 where Smooth is 0: the eval is the sampling's pdf). In closed forms free of
 * cancellation (Size's floor is 1.6e-5 rad, where 1 - cos rounds to 0 in float32): the inner cap
 * 2 sin^2(size / 2); the ramp int_0^w (1 - u / smooth) sin(size + u) du over the w = cone - size it
 * has below the horizon, sin(size) Re J + cos(size) Im J with J its integral of e^(iu). */
float toon_albedo(vec2 shape)
{
  float size = min(shape.x, 0.5 * PI);
  float cone = min(shape.x + shape.y, 0.5 * PI);
  float s = sin(0.5 * cone);
  float h = sin(0.5 * size);
  float ramp = 0.0;
  if (shape.y > 0.0 && cone > size) {
    float w = cone - size;
    float hw = sin(0.5 * w);
    float re = sin(w) - (w * sin(w) - 2.0 * hw * hw) / shape.y;
    float im = 2.0 * hw * hw - (sin(w) - w * cos(w)) / shape.y;
    ramp = sin(size) * re + cos(size) * im;
  }
  return (2.0 * h * h + ramp) / (2.0 * s * s);
}

/* The share of a cone of half-angle `c` about an axis at cos_axis from n that lies above the horizon:
 * the solid angle of two spherical caps' intersection (the cone's and the hemisphere's; Tovchigrechko &
 * Vakser 2001) over the cone's, 2 (pi - acos(cos g / sin c) - cos c acos(-cot g cot c)) / (2 pi (1 - cos c)),
 * g the axis' angle from n; 1 wholly above, 0 wholly below. */
float cone_above_horizon(float cos_axis, float c)
{
  float g = acos_accurate(cos_axis);
  if (g + c <= 0.5 * PI) {
    return 1.0;
  }
  if (g - c >= 0.5 * PI) {
    return 0.0;
  }
  float sin_c = max(sin(c), 1e-6); /* c > 0 here: the cone straddles the horizon */
  float sin_g = max(sin(g), 1e-6);
  float half_cap = sin(0.5 * c);
  float omega = 2.0 * (PI - acos_accurate(cos_axis / sin_c) -
                       cos(c) * acos_accurate(-cos_axis * cos(c) / (sin_g * sin_c)));
  return saturate(omega / (4.0 * PI * half_cap * half_cap));
}

/* The closure lobes at the view (surface.glsl's ClosureBsdfLobes, made once per shading point by
 * make_surface) from MaterialData's closure rows, as Cycles' setups take them: Oren-Nayar's A and B
 * of sigma = roughness and its multiple scattering's colour times 1 - E(v) (bsdf_oren_nayar_setup; the
 * colour per closure: node_closure.glsl's closure_diffuse), its directional albedo at the view; the
 * velvet's 1 / sigma^2 of sigma at least 0.01 (bsdf_ashikhmin_velvet_setup); the toons' Size and
 * Smooth times pi / 2 (bsdf_toon_setup_common). */
ClosureBsdfLobes closure_bsdfs_at(vec3 n, vec3 v, vec3 base_color, MaterialData m)
{
  ClosureBsdfLobes b;
#  ifdef SL_DIFFUSE_ROUGHNESS
  float sigma = saturate(m.closure_bsdfs.y);
  vec3 k = oren_nayar_coefficients(sigma);
  b.on_a = k.x;
  b.on_b = k.y;
  b.on_polygon = vec3(0.0); /* at each light's direction until a polygon is shaded (shade_polygon_light) */
  float e_v = k.x * PI + k.y * oren_nayar_G(max(dot(n, v), 0.0));
#    ifdef SL_OREN_NAYAR_FUJII
  /* Blender 4.2's Cycles: Lambert at roughness 0 only (svm_node_closure_bsdf), Fujii's single
   * scattering alone (4.2's bsdf_oren_nayar_get_intensity: rho (A + B t) n.l), whose albedo is E(v) */
  b.oren_nayar = sigma > 0.0;
  b.on_ms = vec3(0.0);
  b.on_albedo = b.oren_nayar ? base_color * e_v : base_color;
#    else
  /* Cycles 4.5 and 5.0 draw a Diffuse BSDF of roughness below 1e-5 as Lambert (bsdf_diffuse_setup) */
  b.oren_nayar = sigma >= 1e-5;
  b.on_ms = b.oren_nayar ? max(m.diffuse_ms.rgb, 0.0) * (1.0 - e_v) : vec3(0.0);
  /* int f (n.l) d omega_l: E(v) of the single scattering, pi (1 - E_avg) of the multiple's 1 - E(l) */
  b.on_albedo = b.oren_nayar ? base_color * e_v + PI * b.on_ms * (1.0 - k.z) : base_color;
#    endif
#  endif
#  ifdef SL_VELVET
  b.velvet = max(m.velvet.rgb, 0.0);
  float velvet_sigma = max(m.closure_bsdfs.z, 0.01);
  b.velvet_inv_sigma2 = 1.0 / (velvet_sigma * velvet_sigma);
#  endif
#  ifdef SL_TOON
  b.toon_diffuse = max(m.toon_diffuse.rgb, 0.0);
  b.toon_diffuse_shape = vec2(clamp(m.toon_diffuse.w, 1e-5, 1.0), saturate(m.toon_smooth.x)) * (0.5 * PI);
  b.toon_glossy = max(m.toon_glossy.rgb, 0.0);
  b.toon_glossy_shape = vec2(clamp(m.toon_glossy.w, 1e-5, 1.0), saturate(m.toon_smooth.y)) * (0.5 * PI);
#  endif
  return b;
}

#  ifdef SL_DIFFUSE_ROUGHNESS
/* Oren-Nayar's t towards a light at n.l = NoL, l.v = LoV (bsdf_oren_nayar_get_intensity): l.v - n.l n.v
 * over max(n.l, n.v) where positive. */
float oren_nayar_t(float NoL, float NoV, float LoV)
{
  float nl = max(NoL, 0.0);
  float t = LoV - nl * NoV;
  return t > 0.0 ? t / (max(nl, NoV) + 1.175494e-38) : t; /* Cycles' FLT_MIN: both cosines 0 */
}

/* The diffuse base of colour rho towards a light at cos_l, l.v = LoV, without n.l: Lambert's rho / pi,
 * or Oren-Nayar's (bsdf_oren_nayar_get_intensity over n.l) rho (A + B t) + E_ms (1 - E(v)) (1 - E(l)),
 * E(l) = A pi + B G(n.l) its directional albedo towards the light, t oren_nayar_t's -- or the light
 * polygon's mean of it where one is being shaded (on_polygon: oren_nayar_polygon's) --; Blender 4.2's
 * without the multiple scattering (SL_OREN_NAYAR_FUJII: closure_bsdfs_at). */
vec3 oren_nayar_diffuse(Surface s, vec3 rho, float NoL, float LoV)
{
  if (!s.bsdfs.oren_nayar) {
    return rho * INV_PI;
  }
  bool polygon = s.bsdfs.on_polygon.z > 0.0;
  float t = polygon ? s.bsdfs.on_polygon.x : oren_nayar_t(NoL, max(dot(s.n, s.v), 0.0), LoV);
#    ifdef SL_OREN_NAYAR_FUJII
  return rho * (s.bsdfs.on_a + s.bsdfs.on_b * t);
#    else
  float e_l = s.bsdfs.on_a * PI + s.bsdfs.on_b * oren_nayar_G(polygon ? s.bsdfs.on_polygon.y : max(NoL, 0.0));
  return rho * (s.bsdfs.on_a + s.bsdfs.on_b * t) + s.bsdfs.on_ms * (1.0 - e_l);
#    endif
}

#    ifdef SL_LTC
/* Oren-Nayar's t (oren_nayar_t) over a light's polygon, each point weighted by the light's cosine n.l
 * where above the horizon (polygon_point's 16 points, each by the solid angle it stands for): the mean
 * that the diffuse lobe's f, linear in t, times the polygon's exact clipped irradiance then integrates;
 * (mean t, 1), or (0, 0) where no point lies above the horizon (t at the light's direction then). Its
 * multiple scattering's 1 - E(l), smooth in n.l, is taken at the light's direction. At the light's
 * irradiance-weighted direction alone, Diffuse Roughness 1 under a 0.6 m square light 0.6 m from a
 * sphere erred by up to 9.5 % at the silhouette facing it (1.8 % mean there), where the view grazes and
 * t = (l.v - n.l n.v) / n.l changes across the light (tests/test_principled_diffuse_roughness.py). */
vec3 oren_nayar_polygon(Surface s, LightPolygon poly)
{
  if (!s.bsdfs.oren_nayar) {
    return vec3(0.0);
  }
  float NoV = max(dot(s.n, s.v), 0.0);
  vec3 normal = polygon_normal(poly);
  vec3 sum = vec3(0.0);
  for (int i = 0; i < 16; i++) {
    float w;
    vec3 l = polygon_point(poly, normal, i, w);
    float NoL = dot(s.n, l);
    if (NoL > 0.0) {
      sum += (w * NoL) * vec3(oren_nayar_t(NoL, NoV, dot(l, s.v)), NoL, 1.0);
    }
  }
  return sum.z > 0.0 ? vec3(sum.xy / sum.z, 1.0) : vec3(0.0);
}
#    endif
#  endif

/* The velvet's and the toons' f (n.l) towards l per unit irradiance, each lobe times its colour:
 * rgb the diffuse lobes' (velvet and Diffuse toon, Cycles' diffuse passes), the second the Glossy
 * toon's. */
void closure_bsdfs_direct(Surface s, vec3 l, out vec3 diffuse, out vec3 glossy)
{
  diffuse = vec3(0.0);
  glossy = vec3(0.0);
  float NoL = dot(s.n, l);
  float NoV = dot(s.n, s.v);
#  ifdef SL_VELVET
  vec3 sum = l + s.v;
  if (dot(sum, sum) > 0.0) {
    vec3 h = normalize(sum);
    diffuse += s.bsdfs.velvet * velvet_eval(NoV, NoL, dot(s.n, h), abs(dot(l, h)), s.bsdfs.velvet_inv_sigma2);
  }
#  endif
#  ifdef SL_TOON
  if (NoL >= 0.0) {
    diffuse += s.bsdfs.toon_diffuse * toon_eval(s.bsdfs.toon_diffuse_shape, acos_accurate(min(NoL, 1.0)));
  }
  if (NoV > 0.0 && NoL > 0.0) {
    vec3 r = 2.0 * NoV * s.n - s.v; /* the view reflected */
    glossy = s.bsdfs.toon_glossy * toon_eval(s.bsdfs.toon_glossy_shape, acos_accurate(saturate(dot(r, l))));
  }
#  endif
}

#  if defined(SL_LTC) && (defined(SL_VELVET) || defined(SL_TOON))
/* The velvet's and the toons' f (n.l) per unit irradiance (closure_bsdfs_direct) averaged over a light's
 * polygon, each of polygon_point's 16 points weighted by the solid angle it stands for. A narrow toon
 * cone or a smooth velvet's grazing peak changes across a light that covers a few degrees: at the
 * light's direction alone the Toon Diffuse of Size 0.1 under a 0.5 m light 1.5 m away erred by 64 %,
 * the velvet of roughness 0.1 by 61 % (tests/test_closure_nodes.py's stand-ins). */
void closure_bsdfs_polygon(Surface s, LightPolygon poly, out vec3 diffuse, out vec3 glossy)
{
  diffuse = vec3(0.0);
  glossy = vec3(0.0);
  vec3 normal = polygon_normal(poly);
  float total = 0.0;
  for (int i = 0; i < 16; i++) {
    float w;
    vec3 l = polygon_point(poly, normal, i, w);
    if (w <= 0.0) {
      continue;
    }
    vec3 dd, gg;
    closure_bsdfs_direct(s, l, dd, gg);
    diffuse += w * dd;
    glossy += w * gg;
    total += w;
  }
  if (total > 0.0) {
    diffuse /= total;
    glossy /= total;
  }
}
#  endif

/* The velvet's and the toons' f (n.l) per unit irradiance from `light` (its direction `l`): averaged over
 * an area or sphere light (closure_bsdfs_polygon), at `l` from a point, spot or sun. */
void closure_bsdfs_light(Surface s, LightData light, vec3 l, out vec3 diffuse, out vec3 glossy)
{
#  if defined(SL_LTC) && (defined(SL_VELVET) || defined(SL_TOON))
  int kind = int(light.position_kind.w);
#    ifdef SL_HAS_AREA
  if (kind == LIGHT_AREA && light.shape.z > 0.0) {
    closure_bsdfs_polygon(s, area_polygon(light, s.p), diffuse, glossy);
    return;
  }
#    endif
#    if defined(SL_HAS_POINT) || defined(SL_HAS_SPOT)
  if ((kind == LIGHT_POINT || kind == LIGHT_SPOT) && light.shape.x > 0.0) {
    closure_bsdfs_polygon(s, sphere_polygon(light, s.p, AREA_ELLIPSE_SIDES), diffuse, glossy);
    return;
  }
#    endif
#  endif
  closure_bsdfs_direct(s, l, diffuse, glossy);
}

#  ifdef SL_VELVET
/* The velvet's directional albedo at the view: its f (n.l) integrated over the hemisphere by a
 * midpoint rule in t = sqrt(cos theta) (cos theta = t^2: denser towards the horizon, where a smooth
 * velvet's lobe lies) and phi, 16 x 8 points over the half the lobe is symmetric in (the world's
 * light only: 128 evaluations a fragment; within 4 % of a fine quadrature where the albedo exceeds
 * 0.01: tests/test_closure_nodes.py). */
float velvet_albedo(Surface s)
{
  float NoV = max(dot(s.n, s.v), MIN_COS);
  vec3 v = vec3(sqrt(max(1.0 - NoV * NoV, 0.0)), 0.0, NoV);
  float sum = 0.0;
  for (int i = 0; i < 16; i++) {
    float t = (float(i) + 0.5) / 16.0;
    float cos_l = t * t;
    float sin_l = sqrt(1.0 - cos_l * cos_l);
    float weight = 2.0 * t; /* d cos = 2 t dt */
    for (int j = 0; j < 8; j++) {
      float phi = PI * (float(j) + 0.5) / 8.0;
      vec3 l = vec3(sin_l * cos(phi), sin_l * sin(phi), cos_l);
      vec3 h = normalize(l + v);
      /* per unit solid angle: the eval holds n.l, d omega = d cos d phi */
      sum += weight * velvet_eval(NoV, cos_l, h.z, abs(dot(l, h)), s.bsdfs.velvet_inv_sigma2);
    }
  }
  return sum * (2.0 * PI / 128.0); /* both halves of phi: 2 x (1 / 16) x (pi / 8) per point */
}
#  endif

/* The perceptual roughness of the prefiltered world (ibl.glsl's levels: a GGX lobe about the direction,
 * n = v, weighted by n.l) whose light is spread about as a uniform cone of half-angle c is: the one
 * whose median angle is the cone's, 1 - cos theta_m = (1 - cos c) / 2. A fit of sqrt(alpha) =
 * sqrt(tan(c / 2 sqrt 2)) (the narrow lobes' limit, l at twice the half vector's median atan alpha)
 * times a quadratic, within 0.021 of the median-matched roughness for c up to 1.14 (roughness 1's
 * median, 65.5 degrees: wider cones take roughness 1). */
float cone_roughness(float c)
{
  float t = min(c, 1.144);
  return min(sqrt(tan(t * 0.35355339)) * (1.0583 + t * (0.5579 * t - 0.2543)), 1.0);
}

#  ifdef SL_DIFFUSE_ROUGHNESS
/* The diffuse base's light from the world, times pi (principled_environment's rho x irradiance), from the
 * irradiance about n and about the view's tangent t_v either way (`e_towards`, `e_away`; all three
 * `irradiance` where the view lies along n): Lambert's colour times the irradiance about n; Oren-Nayar's A
 * term and multiple scattering likewise (their light is the cosine's), its B term B times the integral of
 * its weight w(l) = (n.l) t, t = l.v - (n.l)(n.v) over max(n.l, n.v) where positive (negative where the
 * light is on the far side: it darkens forward scattering), against the world's light taken as linear in
 * the direction, L0 + L1.l, read from the three irradiances (E(d) = pi L0 + 2 pi / 3 L1.d):
 * int w L = G L0 + 2/3 L1.(int w l), int w l in the plane of n and t_v, G(n.v) = int w (its uniform
 * world's value: exact there). Fits of 3/2 int w l (quadrature, n.v 0.01-0.99, within 0.036):
 * 2.133 (1 - n.v)^0.6 along t_v, 0.450 (1 - n.v)^0.89 along n. Against Cycles in the forest world, the
 * irradiance about n alone drew roughness 1 14.7 % too dark (the light behind the viewer it reflects
 * back; tests/test_closure_nodes.py). Twin: reference/closures.py's oren_nayar_world. */
vec3 oren_nayar_world(Surface s, vec3 irradiance, vec3 e_towards, vec3 e_away)
{
  if (!s.bsdfs.oren_nayar) {
    return s.base_color * irradiance;
  }
  float NoV = max(dot(s.n, s.v), 0.0);
  float G = oren_nayar_G(NoV);
  float along_t = 2.133 * pow(1.0 - NoV, 0.6);
  float along_n = 0.450 * pow(1.0 - NoV, 0.89);
  /* pi L0 from the two tangents' mean; pi (2/3) L1.d = E(d) - pi L0 */
  vec3 mean = 0.5 * (e_towards + e_away);
  vec3 b_light = G * mean + along_n * (irradiance - mean) + along_t * 0.5 * (e_towards - e_away);
  /* the multiple scattering's albedo: on_albedo's rest beside the single scattering's A pi + B G */
  vec3 multiple = s.bsdfs.on_albedo - s.base_color * (s.bsdfs.on_a * PI + s.bsdfs.on_b * G);
  /* a world far from linear (a small bright source on the far side) can take the B term below 0: no
   * negative light from it (Cycles' B term, against any world, darkens by less than the A term lights) */
  b_light = max(b_light, 0.0);
  return s.base_color * (s.bsdfs.on_a * PI * irradiance + s.bsdfs.on_b * b_light) + multiple * irradiance;
}
#  endif

#  ifdef SL_VELVET
/* Point i of the 6 x 8 the velvet's world light is read at (velvet_world_radiance): its direction in the
 * frame (the tangent towards v, n x it, n) at t = sqrt(cos theta) midpoints (as velvet_albedo's) and 8
 * azimuths over the whole circle (the world is not symmetric about the view's plane), and its weight, the
 * velvet's f (n.l) there times t (d cos theta = 2 t dt). Twin: reference/closures.py's velvet_world_points. */
float velvet_world_point(float NoV, float inv_sigma2, int i, out vec3 local)
{
  float t = (float(i / 8) + 0.5) / 6.0;
  float cos_l = t * t;
  float sin_l = sqrt(1.0 - cos_l * cos_l);
  float phi = PI * (float(i % 8) + 0.5) / 4.0;
  local = vec3(sin_l * cos(phi), sin_l * sin(phi), cos_l);
  vec3 v = vec3(sqrt(max(1.0 - NoV * NoV, 0.0)), 0.0, NoV);
  vec3 h = normalize(local + v);
  return t * velvet_eval(NoV, cos_l, h.z, abs(dot(local, h)), inv_sigma2);
}
#  endif

#  ifdef SL_TOON
/* Point i of the TOON_WORLD_SAMPLES a toon's cone (Size and Smooth `shape`, radians) reads the world at
 * (toon_world_radiance): spread over the cone by solid angle (Vogel's disc mapped to the cap by area,
 * 1 - cos theta = r^2 (1 - cos c)), its direction in the cone's frame (z its axis); returns the toon's
 * intensity there. Twin: reference/closures.py's toon_world_points. */
#    define TOON_WORLD_SAMPLES 16
float toon_world_point(vec2 shape, int i, out vec3 local)
{
  float half_cap = sin(0.5 * min(shape.x + shape.y, 0.5 * PI));
  vec2 d = vogel_disc(i, TOON_WORLD_SAMPLES);
  float r = length(d); /* >= sqrt(1/2 / N): never 0 */
  float one_minus_cos = 2.0 * r * r * half_cap * half_cap;
  float sin_t = sqrt(max(one_minus_cos * (2.0 - one_minus_cos), 0.0));
  local = vec3(d * (sin_t / r), 1.0 - one_minus_cos);
  /* its angle by atan (llvmpipe's asin strays by 4e-4 rad, which a ramp of Smooth 0.03 makes 1.6e-2) */
  return toon_intensity(shape.x, shape.y, atan(sin_t, local.z));
}
#  endif

#  if defined(SL_ENV_UNIFORM) || defined(SL_ENV_MAP)
#    ifdef SL_DIFFUSE_ROUGHNESS
/* The diffuse base's light from the world, times pi: oren_nayar_world of the irradiance about n and the
 * irradiance about the view's tangent either way. */
vec3 oren_nayar_environment(Surface s, vec3 irradiance)
{
  if (!s.bsdfs.oren_nayar) {
    return s.base_color * irradiance;
  }
  vec3 tangent = s.v - s.n * max(dot(s.n, s.v), 0.0);
  float t_len2 = dot(tangent, tangent);
  vec3 e_towards = irradiance; /* the view along n: no tangent, the B term's weight is symmetric */
  vec3 e_away = irradiance;
  if (t_len2 > 1e-12) {
    tangent *= inversesqrt(t_len2);
    float occlusion = env_occlusion_diffuse();
    e_towards = env_irradiance(env_bent_normal(tangent)) * occlusion;
    e_away = env_irradiance(env_bent_normal(-tangent)) * occlusion;
  }
  return oren_nayar_world(s, irradiance, e_towards, e_away);
}
#    endif

#    ifdef SL_VELVET
/* The world's radiance as the velvet weights it, over its own weight: its f (n.l) at 6 x 8 points over the
 * whole hemisphere (velvet_world_point), the world read at each prefiltered at the roughness whose lobe
 * covers its cell (env_footprint_roughness; never a level holding the suns, which light the velvet as lights:
 * at roughness 0.5 for every cell, the horizon's cells read the ground below it, 5 % too dark in the forest
 * world). The velvet's light lies
 * towards the horizon at grazing views (its sine's peak), where the irradiance about n, weighted by the
 * cosine, looks away: in the forest world that drew it 26 % too dark (tests/test_closure_nodes.py). */
vec3 velvet_world_radiance(Surface s)
{
  float NoV = max(dot(s.n, s.v), MIN_COS);
  vec3 x_axis = s.v - s.n * dot(s.n, s.v);
  vec3 other = abs(s.n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
  x_axis = dot(x_axis, x_axis) > 1e-12 ? normalize(x_axis) : normalize(cross(other, s.n)); /* v along n */
  vec3 y_axis = cross(s.n, x_axis);
  float floor_roughness = env_sunless_roughness();
  vec3 sum = vec3(0.0);
  float weight = 0.0;
  for (int i = 0; i < 48; i++) {
    vec3 l;
    float f = velvet_world_point(NoV, s.bsdfs.velvet_inv_sigma2, i, l);
    /* the cell's solid angle 2 t dt dphi, t = sqrt(l.z): the share 1 / (48 pdf) of the footprint */
    float cell = 2.0 * sqrt(l.z) * (1.0 / 6.0) * (PI / 4.0);
    sum += f * env_prefiltered(l.x * x_axis + l.y * y_axis + l.z * s.n,
                               env_footprint_roughness(1.0 / (48.0 * cell), 48, floor_roughness));
    weight += f;
  }
  return weight > 0.0 ? sum / weight : env_irradiance(s.n) * INV_PI; /* no velvet: its colour is 0 too */
}
#    endif

#    ifdef SL_TOON
/* The world's radiance through a toon's cone (Size and Smooth `shape`, radians) about `axis`, weighted by its
 * intensity (its ramp) and, above n's horizon only (Cycles' eval: n.l > 0), over its weight: its
 * TOON_WORLD_SAMPLES points (toon_world_point), each reading the prefiltered world at its share of the cone
 * (env_footprint_roughness), no smoother than `floor_roughness`; where no point carries weight (a cone below
 * the horizon, which reflects nothing then) the world at the axis. The world prefiltered at the GGX lobe of
 * the cone's median angle alone (cone_roughness), a lobe peaked where the cone is flat, drew the toons 7 %
 * too dark in the forest world (tests/test_closure_nodes.py). */
vec3 toon_world_radiance(vec3 n, vec3 axis, vec2 shape, float floor_roughness)
{
  float half_cap = sin(0.5 * min(shape.x + shape.y, 0.5 * PI));
  float cap = 2.0 * half_cap * half_cap; /* the cone's 1 - cos, free of cancellation */
  float roughness = env_footprint_roughness(1.0 / (2.0 * PI * cap), TOON_WORLD_SAMPLES, floor_roughness);
  vec3 other = abs(axis.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
  vec3 x = normalize(cross(other, axis));
  vec3 y = cross(axis, x);
  vec3 sum = vec3(0.0);
  float weight = 0.0;
  for (int i = 0; i < TOON_WORLD_SAMPLES; i++) {
    vec3 local;
    float w = toon_world_point(shape, i, local);
    vec3 l = x * local.x + y * local.y + axis * local.z;
    w = dot(n, l) > 0.0 ? w : 0.0;
    sum += w * env_prefiltered(l, roughness);
    weight += w;
  }
  return weight > 0.0 ? sum / weight : env_prefiltered(axis, roughness);
}
#    endif

/* The world's light on the velvet and the toons: each lobe's directional albedo times the world's
 * light it sees (velvet_world_radiance, toon_world_radiance), the Glossy toon's times the share of its
 * cone above the horizon (its solid angle's, the ramp taken as flat). The diffuse lobes take the suns split
 * off the world as lights (their levels hold none); the Glossy toon as the specular lobe does
 * (world_sun_specular of the surface's roughness). */
vec3 closure_bsdfs_environment(Surface s, vec2 weights)
{
  vec3 c = vec3(0.0);
#    ifdef SL_VELVET
  c += s.bsdfs.velvet * velvet_albedo(s) * velvet_world_radiance(s) * (env_occlusion_diffuse() * weights.x);
#    endif
#    ifdef SL_TOON
  float sunless = env_sunless_roughness();
  if (max(s.bsdfs.toon_diffuse.r, max(s.bsdfs.toon_diffuse.g, s.bsdfs.toon_diffuse.b)) > 0.0) {
    vec2 shape_d = s.bsdfs.toon_diffuse_shape;
    float roughness_d = cone_roughness(min(shape_d.x + shape_d.y, 0.5 * PI)); /* its occlusion's cone */
    c += s.bsdfs.toon_diffuse * toon_albedo(shape_d) * toon_world_radiance(s.n, s.n, shape_d, sunless) *
         (env_occlusion_specular(s.n, s.n, roughness_d * roughness_d) * weights.x);
  }
  if (max(s.bsdfs.toon_glossy.r, max(s.bsdfs.toon_glossy.g, s.bsdfs.toon_glossy.b)) > 0.0) {
    vec2 shape_g = s.bsdfs.toon_glossy_shape;
    vec3 r = reflect(-s.v, s.n);
    float cone = min(shape_g.x + shape_g.y, 0.5 * PI);
    float roughness = cone_roughness(cone);
    /* the cone's part below the horizon reflects nothing (Cycles' eval: n.l > 0) */
    float above = cone_above_horizon(dot(s.n, r), cone);
    float floor_g = world_sun_specular(s.roughness) > 0.5 ? sunless : MIN_PERCEPTUAL_ROUGHNESS;
    c += s.bsdfs.toon_glossy * toon_albedo(shape_g) * toon_world_radiance(s.n, r, shape_g, floor_g) *
         (above * env_occlusion_specular(s.n, r, roughness * roughness) * weights.y);
  }
#    endif
  return c;
}
#  endif
#endif

#ifdef SL_GLOSSY
/* The Glossy BSDF (node_closure_bsdfs.glsl) in the Principled set's metal lobe: Cycles 5.0 gives it no
 * Fresnel but its colour (bsdf_microfacet.h's MicrofacetFresnel::NONE; Multiscatter GGX's
 * compensation takes the colour as its average Fresnel), and GGX, Beckmann or Ashikhmin-Shirley. */

/* Ashikhmin & Shirley 2000's isotropic lobe as Cycles evaluates it (bsdf_ashikhmin_shirley_eval; its
 * Fresnel left out): (e + 1) / (8 pi) (n.h)^e over (l.h) max(n.v, n.l), e = 2 / alpha^2 - 2, the
 * cosines floored at 1e-6 as Cycles floors them; f = this times the colour. */
float D_V_AshikhminShirley(float NoV, float NoL, float NoH, float LoH, float alpha)
{
  if (alpha <= 1e-4) {
    return 0.0; /* Cycles' mirror limit of the lobe: none */
  }
  float e = 2.0 / (alpha * alpha) - 2.0;
  float pump = 1.0 / max(1e-6, max(LoH, 1e-6) * max(max(NoV, NoL), 1e-6));
  return (e + 1.0) / (8.0 * PI) * pow(max(NoH, 1e-6), e) * pump;
}

#  ifdef SL_LAYERS /* the Principled set's (its metal lobe's compensation) */
/* The metal lobe's Fresnel times its compensation: the Principled BSDF's F82-tint `F` (its albedo
 * for the world's split sum) and compensation M beside the Glossy BSDFs' share of the lobe, their
 * colour (times `albedo`, the lobe's own albedo for the world's split sum, 1 towards a light) and its
 * compensation; the share of uncompensated lobes (GGX, Beckmann, Ashikhmin-Shirley) without it, spread
 * over both where both are mixed. */
vec3 glossy_metal(Surface s, vec3 F, vec3 M, float albedo)
{
  float colour_share = s.glossy.x;
  float uncompensated = s.glossy.y;
  vec3 glossy = max(s.base_color, 0.0) * albedo * mix(s.layers.glossy_M, vec3(1.0), uncompensated);
  return (1.0 - colour_share) * F * mix(M, vec3(1.0), uncompensated) + colour_share * glossy;
}

/* The specular lobe's directional albedo (F = 1) at (n.v, roughness) with the Glossy BSDFs' shares of
 * Beckmann (Smith height-correlated) and Ashikhmin-Shirley in place of GGX's `E_ggx`: ms_table's rows
 * after the Principled set's own (gpu_library.albedo_table: Beckmann's table, then
 * closures.ashikhmin_shirley_albedo_table's). What the lights' linearly transformed cosines and the
 * world's split sum take as the lobe's magnitude: Beckmann reflects up to 1.6x GGX's at roughness 1,
 * Ashikhmin-Shirley down to 0.5x. */
float glossy_albedo(Surface s, float E_ggx, float NoV, float roughness)
{
  float beckmann = s.glossy.z;
  float ashikhmin = s.glossy.w;
  if (beckmann + ashikhmin <= 0.0) {
    return E_ggx;
  }
  float b = beckmann > 0.0 ? ms_albedo_rows(NoV, roughness, SL_MS_SIZE + 1) : 0.0;
  float a = ashikhmin > 0.0 ? ms_albedo_rows(NoV, roughness, 2 * SL_MS_SIZE + 1) : 0.0;
  return (1.0 - beckmann - ashikhmin) * E_ggx + beckmann * b + ashikhmin * a;
}

#    ifdef SL_LTC
float pbr_lobe(Surface s, vec3 l); /* model_pbr.glsl */

/* The ratio the estimator (ltc.glsl's ltc_lobe_integral) takes, f (n.l) over the linearly transformed
 * cosine's density D, where the Glossy BSDFs' Beckmann or Ashikhmin-Shirley lobes hold a share of the
 * specular lobe (false elsewhere: GGX's own ratio at the light's irradiance-weighted direction, its long
 * tails keeping it well conditioned there): the D-weighted mean of f / D over the light, sum f w / sum D w
 * over polygon_point's 16 points (w the solid angle each stands for) and the cosine's own mean direction
 * over the light, M F (F its vector form factor in the cosine's space, mapped back by M = adj(M^-1), a
 * positive multiple: det M^-1 > 0), weighted as one point more -- where the lobe is narrower than the
 * points' spacing, its peak: a Gaussian peak narrower than the light vanishes towards the light's centre
 * while the light still holds half of it. Out: the two sums, whose ratio ltc_lobe_integral takes. Against
 * quadrature of Beckmann's f (n.l) over square lights of half-angles 0.03-0.3 rad at 0-2.5 half-angles
 * from the mirror direction (n.v 0.3-0.95; relative to the larger of the integral and 1 % of the albedo;
 * tests/test_closure_nodes.py), mean / worst error at roughness 0.15, 0.3, 0.5: at the light's direction
 * 0.18 / 0.79, 0.13 / 0.76 (0.15, 0.3); at M F alone 0.11 / 0.41, 0.095 / 0.22, 0.059 / 0.26; over the
 * points and M F 0.076 / 0.47, 0.048 / 0.23, 0.025 / 0.16 (Beckmann's own fitted cosine, addon/reference/
 * ltc.py's ltc_BECKMANN, within 0.01 of it: not worth its table). */
bool glossy_ltc_ratio(Surface s, LightPolygon poly, float integral, out float lobe, out float density)
{
  lobe = 0.0;
  density = 0.0;
  if (s.glossy.z + s.glossy.w <= 0.0) {
    return false;
  }
  vec4 m = s.ltc.m;
  mat3 to_cosine = transpose(mat3(m.x * s.ltc.x_axis + m.y * s.n, s.ltc.y_axis, m.z * s.ltc.x_axis + m.w * s.n));
  vec3 F = polygon_form_factor(poly, to_cosine) * INV_PI;
  float len = length(F);
  if (len <= 0.0) {
    return false; /* nothing of the light in the cosine's space: the lobe's integral is 0 too */
  }
  vec3 normal = polygon_normal(poly);
  float w_sum = 0.0;
  for (int i = 0; i < 16; i++) {
    float w;
    vec3 l = polygon_point(poly, normal, i, w);
    vec3 local = vec3(dot(l, s.ltc.x_axis), dot(l, s.ltc.y_axis), dot(l, s.n));
    lobe += w * pbr_lobe(s, l);
    density += w * ltc_density(m, local, 0.0);
    w_sum += w;
  }
  vec3 local = ltc_direction(m, F);
  float w_mean = w_sum / 16.0;
  lobe += w_mean * pbr_lobe(s, local.x * s.ltc.x_axis + local.y * s.ltc.y_axis + local.z * s.n);
  density += w_mean * ltc_density(m, local, ltc_density_floor(integral, min(len, 1.0)));
  return true;
}
#    endif

/* The specular lobe's D V with the Glossy BSDFs' shares of Beckmann (Smith height-correlated, the
 * Beckmann Lambda Cycles uses) and Ashikhmin-Shirley in place of GGX's `DV`. */
float glossy_lobe(Surface s, float DV, float NoL, float NoH, float NxH2, float LoH)
{
  float beckmann = s.glossy.z;
  float ashikhmin = s.glossy.w;
  if (beckmann + ashikhmin <= 0.0) {
    return DV;
  }
  float b = beckmann > 0.0 ? D_Beckmann(NoH, NxH2, s.alpha) * V_SmithBeckmannCorrelated(s.NoV, NoL, s.alpha) : 0.0;
  float a = ashikhmin > 0.0 ? D_V_AshikhminShirley(s.NoV, NoL, NoH, LoH, s.alpha) : 0.0;
  return (1.0 - beckmann - ashikhmin) * DV + beckmann * b + ashikhmin * a;
}
#  endif
#endif
