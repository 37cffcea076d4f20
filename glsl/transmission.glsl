/* Transmission (SL_TRANSMISSION): the Principled BSDF's Transmission Weight, the Glass and Refraction
 * BSDFs. A dielectric interface splits the light between reflection (the Principled set's dielectric
 * lobe, tinted by the Glass BSDF's Color) and transmission by the exact Fresnel; the transmitted
 * part is what lies behind the surface as the rasteriser has it, in screen space (EEVEE's
 * screen-space refraction): a copy of the opaque scene and the world behind it (passes.RefractionPass:
 * its colour and depth, and blurred levels of it for rough glass), read where the refracted ray meets
 * it. A closed object refracts twice: the ray enters at the fragment, crosses the object to the face
 * turned away from the viewer that it meets (the back faces' depth and normals, drawn by the pass)
 * and leaves there refracted again; where it meets none (an open surface, a plane) it refracts once.
 * Lights behind the surface shine through it by the GGX transmission lobe (transmission_ggx).
 * Twin: addon/reference/transmission.py. */

#ifdef SL_TRANSMISSION
/* The first crossing's rays through a curved far face (transmission_exit_rays, used by
 * transmission_exit_light): see transmission_exit_quadrature. */
#define EXIT_RAYS 8
vec3 exit_ray_dir[EXIT_RAYS];    /* each ray's direction inside */
vec3 exit_ray_point[EXIT_RAYS];  /* where it meets the far face */
vec3 exit_ray_normal[EXIT_RAYS]; /* the far face's normal there, facing the inside */
float exit_ray_weight[EXIT_RAYS]; /* what of the view crosses in along it, times the far face's
                                   * compensation (white) */
float exit_curved;               /* 0: the lobes' mean (a flat far face) .. 1: the quadrature */
/* What the lights through the glass share, light for light (transmission_prepare_lights: once per
 * shading point, not per light -- on the CPU rasteriser every light's code runs at every pixel): the
 * near face's compensation at the view, the far face's along the view ray refracted in, and what the
 * first crossing's spread loses at the far face. */
vec3 glass_near_compensation;
vec3 glass_far_compensation;
float exit_loss;


/* The glass at the shading point (surface.glsl's TransmissionLobe) from MaterialData's rows: its
 * share of the whole surface (the glass share of the non-metallic part times 1 - metalness, as
 * Cycles' svm_node_closure_bsdf weighs its Transmission component), IOR, tints. */
TransmissionLobe transmission_at(MaterialData m, float metalness)
{
  TransmissionLobe t;
  t.share = saturate(m.transmission.x);
  t.weight = t.share * (1.0 - metalness);
  t.fresnel = m.transmission.y > 0.5;
  t.eta = max(m.transmission.z, 1e-5);
  t.tint = max(m.transmission_tint.rgb, 0.0);
  t.reflection_tint = max(m.reflection_tint.rgb, 0.0);
  /* no way through traced yet (transmission_trace, in the programs drawn by the refraction pass) */
  t.inside = vec3(0.0);
  t.inner = vec3(0.0);
  t.exit_p = vec3(0.0);
  t.exit_n = vec3(0.0);
  t.exit = false;
  t.behind = vec3(0.0);
  exit_curved = 0.0; /* (no quadrature until transmission_exit_rays) */
  glass_near_compensation = vec3(1.0); /* (until transmission_prepare_lights) */
  glass_far_compensation = vec3(1.0);
  exit_loss = 1.0;
  return t;
}

/* The fraction of light crossing a smooth dielectric interface at cos_i (> 0, the side it comes
 * from) into a medium of relative IOR eta (inside over outside): 1 - F, F the exact Fresnel
 * (brdf.glsl's F_Dielectric, Walter et al. 2007 eq. 22), 0 under total internal reflection; all of
 * it without Fresnel (the Refraction BSDF, but for total internal reflection as Cycles'). */
float transmission_fraction(float cos_i, float eta, bool fresnel)
{
  float F = F_Dielectric(eta, cos_i);
  return fresnel ? 1.0 - F : (F >= 1.0 ? 0.0 : 1.0);
}

/* Rough glass's single-scattering albedo for light arriving at n.v = mu on glass of relative IOR eta
 * and perceptual `roughness`: Cycles' ggx_glass_E and ggx_glass_Eavg tables (their _inv tables at
 * 1 / eta for eta < 1), read as its microfacet_ggx_preserve_energy reads them (trilinear on the grid
 * i / (N - 1) over roughness, mu and z = sqrt(|eta - 1| / (eta + 1))), and the transmitted part of E
 * alone, T. Our tables (addon/reference/transmission.py's compute_glass_albedo_tables,
 * scripts/glass_albedo_table.py) are rows of s_table after the S table (gpu_library.s_table), the
 * roughness along x: E at rows N^2 (1 + inverse) + mu + N z, Eavg at rows 3 N^2 + N inverse + z, T at
 * rows 3 N^2 + 2 N + N^2 inverse + mu + N z. */
float glass_texel(int row, int r)
{
  return texelFetch(s_table, ivec2(r, row), 0).r;
}

/* The tables' coordinates (texels) of roughness, mu and eta's z, and whether eta < 1 (z.w). */
vec4 glass_coordinates(float roughness, float mu, float eta)
{
  float ior = eta < 1.0 ? 1.0 / eta : eta;
  vec3 x = clamp(vec3(roughness, mu, sqrt(abs(ior - 1.0) / (ior + 1.0))), 0.0, 1.0) * float(SL_S_SIZE - 1);
  return vec4(x, eta < 1.0 ? 1.0 : 0.0);
}

/* Trilinear in the 3D table whose rows start at `first`. */
float glass_table(int first, vec3 x)
{
  int n = SL_S_SIZE;
  ivec3 i0 = min(ivec3(floor(x)), ivec3(n - 2));
  vec3 f = x - vec3(i0);
  float r = 0.0;
  for (int k = 0; k < 2; k++) {
    int row = first + i0.y + n * (i0.z + k);
    float e0 = mix(glass_texel(row, i0.x), glass_texel(row, i0.x + 1), f.x);
    float e1 = mix(glass_texel(row + 1, i0.x), glass_texel(row + 1, i0.x + 1), f.x);
    r += (k == 0 ? 1.0 - f.z : f.z) * mix(e0, e1, f.y);
  }
  return r;
}

/* (E, Eavg) */
vec2 glass_albedo(float roughness, float mu, float eta)
{
  int n = SL_S_SIZE;
  vec4 x = glass_coordinates(roughness, mu, eta);
  int inverse = int(x.w);
  ivec2 i0 = min(ivec2(floor(x.xz)), ivec2(n - 2));
  vec2 f = x.xz - vec2(i0);
  int row = 3 * n * n + n * inverse + i0.y;
  float a0 = mix(glass_texel(row, i0.x), glass_texel(row, i0.x + 1), f.x);
  float a1 = mix(glass_texel(row + 1, i0.x), glass_texel(row + 1, i0.x + 1), f.x);
  return vec2(glass_table(n * n * (1 + inverse), x.xyz), mix(a0, a1, f.y));
}

/* What of the light crossing rough glass at n.v = mu passes through: T / E, the share of its
 * transmission in what the compensated glass closure scatters (Cycles' microfacet_ggx_preserve_energy
 * scales both by 1 / E); beyond the critical angle some still passes (the microfacets tilted towards
 * the ray). */
float glass_transmitted(float roughness, float mu, float eta)
{
  int n = SL_S_SIZE;
  vec4 x = glass_coordinates(roughness, mu, eta);
  int inverse = int(x.w);
  float E = glass_table(n * n * (1 + inverse), x.xyz);
  /* E >= 0.3 in the tables but at grazing mu (the mu = 0 node: 0.024 at IOR 1.01, roughness 1): the
   * floor guards a division by 0 */
  return glass_table(3 * n * n + 2 * n + n * n * inverse, x.xyz) / max(E, 1e-3);
}

/* What Cycles' microfacet_ggx_preserve_energy multiplies a Multiscatter GGX glass closure by (its
 * reflection and transmission alike): its energy_scale 1 / E times the darkening of a tinted glass,
 * together 1 + Fms (1 - E) / E, Fms = Fss Eavg / (1 - Fss (1 - Eavg)) (Kulla & Conty 2017, "Revisiting
 * Physically Based Shading at Imageworks", appendix), Fss the transmission's tint as
 * bsdf_microfacet_setup_fresnel_generalized_schlick takes it. Per channel; light arriving at n.v =
 * mu. (The Refraction BSDF has none: 1.) */
vec3 glass_compensation(TransmissionLobe t, float roughness, float mu, float eta)
{
  if (!t.fresnel) {
    return vec3(1.0);
  }
  vec2 e = glass_albedo(roughness, mu, eta);
  /* E -> 0 only at grazing mu on the roughest glass leaving it (0.3 there): floored as Cycles' table
   * never is, against a division by 0 */
  float E = max(e.x, 1e-3);
  /* a tint above 1 (a Glass BSDF's Color) is no average Fresnel: at 1 the darkening is none, and the
   * formula's denominator stays positive */
  vec3 Fss = clamp(t.tint, 0.0, 1.0);
  vec3 Fms = Fss * e.y / (1.0 - Fss * (1.0 - e.y));
  return 1.0 + Fms * ((1.0 - E) / E);
}

/* How far (radians) the first crossing's rough lobe turns the view ray refracted into glass of
 * relative IOR eta: a microfacet tilted by delta turns it by delta (1 - cos_v / (eta cos_t))
 * (d theta_t / d theta_i = cos_i / (eta cos_t)), cos_v the view's cosine and cos_t the refracted
 * ray's to the surface's normal, times `spread` alpha (the programs' REFRACTION_EXIT_SPREAD: GGX's
 * slopes scale with alpha). */
float transmission_inner_spread(float cos_v, float cos_t, float eta, float alpha, float spread)
{
  /* cos_t -> 0 only for a ray refracted along the surface (eta < 1 near its critical angle): no turn */
  return cos_t > 1e-4 ? spread * alpha * max(1.0 - cos_v / (eta * cos_t), 0.0) : 0.0;
}

/* The fraction of the light crossing a closed object's far face from inside (relative IOR 1 / eta)
 * along the view ray refracted in, at cos_i to that face's normal, for glass of perceptual
 * `roughness`: what the far face's compensated rough closure passes (glass_transmitted: its
 * microfacets' Fresnel, total internal reflection included) averaged over the incidence angles the
 * first crossing's lobe turns the ray to, four angles theta +- s / sqrt(3), +- sqrt(3) s (the
 * quartiles of a Student-t of 2 degrees, GGX's slopes; s = `spread` radians:
 * transmission_inner_spread). Against a Monte-Carlo integration of Cycles' two compensated rough
 * crossings of a slab (IOR 1.33 and 1.5, roughness 0.1-0.8, views 0-70 degrees; times the first
 * crossing's 1 - F): 0.013 mean absolute difference, 0.0055 at views up to 50 degrees (0.11 largest,
 * at 70 degrees); the smooth Fresnel averaged over a spread of 0.25 roughness radians (the engine
 * before) 0.034 (0.16). Smooth glass (roughness at most the floor) and the Refraction BSDF (no
 * Fresnel, no compensation in Cycles) pass the smooth fraction, exact at roughness 0. */
float transmission_exit_fraction(float cos_i, float eta, float roughness, float spread, bool fresnel)
{
  float c = clamp(cos_i, 0.0, 1.0);
  float sin_i = sqrt(1.0 - c * c);
  bool rough = fresnel && roughness > MIN_PERCEPTUAL_ROUGHNESS;
  float sum = 0.0;
  for (int k = 0; k < 4; k++) {
    float offset = spread * (k < 2 ? 0.57735027 : 1.7320508) * ((k & 1) == 0 ? 1.0 : -1.0);
    /* cos(theta + offset) (an angle past the normal is that angle on the other side, cos being even;
     * one past grazing is grazing: cos 0) */
    float cos_k = max(c * cos(offset) - sin_i * sin(offset), 0.0);
    sum += rough ? glass_transmitted(roughness, cos_k, 1.0 / eta) : transmission_fraction(cos_k, 1.0 / eta, fresnel);
  }
  return 0.25 * sum;
}

/* The direction light travelling along unit d takes through an interface of unit normal n (facing
 * against d) into a medium of relative IOR eta (Snell's law, Walter et al. 2007 eq. 40); 0 under
 * total internal reflection. */
vec3 transmission_direction(vec3 d, vec3 n, float eta)
{
  return refract(d, n, 1.0 / eta);
}

/* The GGX transmission lobe times |n.l| for light arriving along l from behind the surface (n.l <
 * 0), towards v (n.v > 0), into relative IOR eta, per unit irradiance, without its Fresnel and tint
 * (Walter et al. 2007 eq. 21 with the height-correlated Smith term, as Cycles' bsdf_microfacet_eval
 * evaluates a glass closure's transmission: D G2 eta^2 |h.v| |h.l| / (n.v (h.v + eta h.l)^2)), and
 * the cosine h.v its Fresnel is taken at. 0 where the half vector faces away from either side (no
 * microfacet refracts l into v). */
float transmission_ggx(vec3 n, vec3 v, vec3 l, float eta, float alpha, out float HoV)
{
  HoV = 0.0;
  float NoV = dot(n, v);
  float NoL = dot(n, l);
  if (NoV <= 0.0 || NoL >= 0.0 || abs(eta - 1.0) < 1e-4) {
    /* eta = 1: every microfacet passes l straight on, a lobe of no width (a delta, not evaluated) */
    return 0.0;
  }
  vec3 h = -(v + eta * l);
  float len2 = dot(h, h);
  if (len2 <= 1e-20) {
    return 0.0;
  }
  h *= inversesqrt(len2);
  h = dot(h, n) < 0.0 ? -h : h;
  HoV = dot(h, v);
  float HoL = dot(h, l);
  if (HoV <= 0.0 || HoL >= 0.0) {
    return 0.0; /* a microfacet seen from behind, or l in front of it */
  }
  float NoH = dot(n, h);
  vec3 NxH = cross(n, h);
  float D = D_GGX(NoH, dot(NxH, NxH), alpha);
  float V = V_SmithGGXCorrelated(max(NoV, MIN_COS), max(-NoL, MIN_COS), alpha); /* G2 / (4 n.v |n.l|) */
  float denominator = HoV + eta * HoL;
  /* h.v + eta h.l -> 0 only where h is perpendicular to both (no refraction there): its square
   * floored at 1e-12 keeps the ratio finite where it rounds to 0 */
  return 4.0 * D * V * (-NoL) * eta * eta * HoV * (-HoL) / max(denominator * denominator, 1e-12);
}

/* The GGX transmission lobe towards l at `alpha` times the transmission's Fresnel at h.v
 * (transmission_ggx, transmission_fraction), per unit irradiance. */
float transmission_crossing(Surface s, vec3 l, float alpha)
{
  float HoV;
  float lobe = transmission_ggx(s.n, s.v, l, s.transmission.eta, alpha, HoV);
  return lobe > 0.0 ? transmission_fraction(HoV, s.transmission.eta, s.transmission.fresnel) * lobe : 0.0;
}

#if defined(SL_SPHERE_LIGHTS)
#  if defined(SL_HAS_POINT) || defined(SL_HAS_SPOT)
#  define SL_TRANSMISSION_SPHERE_LIGHTS
/* A sphere light's angular radius (a point or spot light of radius r) in the half-vector space of a
 * transmission lobe of relative IOR eta seen along v, the light along l, from p: its angular radius
 * r / d' (2 sphere_light_theta) times eta / |v + eta l|, how far h = -(v + eta l) normalised turns as
 * l turns (where the reflection's half vector turns by 1/2). */
float transmission_light_theta(LightData light, vec3 p, vec3 v, vec3 l, float eta)
{
  vec3 h = v + eta * l;
  /* |v + eta l| -> 0 only for eta -> 1 straight through, where there is no lobe (transmission_ggx) */
  return 2.0 * sphere_light_theta(light, p) * eta * inversesqrt(max(dot(h, h), 1e-8));
}

/* Whether `light` is a sphere light (a point or spot light with a radius). */
bool transmission_sphere_light(LightData light)
{
  int kind = int(light.position_kind.w);
  return light.shape.x > 0.0 && (kind == LIGHT_POINT || kind == LIGHT_SPOT);
}
#  endif
#endif

/* A light's radiance through the surface from behind it (n.l < 0): the glass share times its tint,
 * the transmission's Fresnel at h.v and the GGX lobe, per unit irradiance E (Cycles evaluates the
 * glass closure's transmission for lights behind the surface, the light's shadow through the rest of
 * the object not looked up: a closed object's far side does not dim it), times the lobe's
 * compensation for what single scattering loses (glass_compensation at the view). A sphere light
 * widens the lobe by its angular radius in the lobe's half-vector space (transmission_light_theta),
 * as the wide part of lights.glsl's sphere_light_specular widens a reflection's. */
vec3 transmission_light(Surface s, LightData light, vec3 l, vec3 E, vec4 factors)
{
  if (s.transmission.weight <= 0.0 || dot(s.n, l) >= 0.0 || s.transmission.exit) {
    return vec3(0.0); /* (through a closed object: at its far face, transmission_exit_light) */
  }
  float lobe;
#ifdef SL_TRANSMISSION_SPHERE_LIGHTS
  if (transmission_sphere_light(light)) {
    /* the lobe widened by the light's angular radius in its half-vector space (lobe widths convolved
     * add in quadrature, as size_lobe_weights' wide lobe; capped as there), at most 1, as Cycles'
     * bsdf_microfacet_ggx_setup saturates a lobe's alpha */
    float theta = min(transmission_light_theta(light, s.p, s.v, l, s.transmission.eta), 0.78539816);
    lobe = transmission_crossing(s, l, min(sqrt(s.alpha * s.alpha + theta * theta), 1.0));
  }
  else
#endif
  {
    lobe = transmission_crossing(s, l, s.alpha);
  }
  if (lobe <= 0.0) {
    return vec3(0.0);
  }
  return s.transmission.tint * glass_near_compensation * (s.transmission.weight * lobe * factors.y) * E;
}

/* --- the first crossing's rays through a curved far face ------------------------------------ */

/* On a curved far face (a sphere) the far face's normal turns across the first crossing's lobe, which
 * the two lobes' mean (transmission_exit_light) cannot see: there the light through the far face is
 * a quadrature of EXIT_RAYS rays of the first crossing (transmission_exit_ray, at visible normals of
 * a fixed 2 x 4 grid), each meeting the far face where the far faces' depth map has it
 * (transmission_exit_rays, in the programs drawn by the refraction pass) and crossing it by the far
 * face's own lobe and compensation towards the light. A flat far face (a slab) keeps the lobes' mean,
 * exact there, where the quadrature's eight narrow lobes would show apart; between them by how much
 * the far face's normal turns against the rays (exit_curved). */
/* Smith's Lambda for isotropic GGX at cos_n to the normal (Heitz 2014 eq. 72, Cycles' bsdf_lambda). */
float transmission_lambda(float cos_n, float alpha)
{
  float c2 = max(cos_n * cos_n, 1e-12);
  return 0.5 * (sqrt(1.0 + alpha * alpha * max(1.0 / c2 - 1.0, 0.0)) - 1.0);
}

/* Visible normal k of EXIT_RAYS of isotropic GGX seen from (sin_v, 0, cos_v), in the frame (x the
 * view's direction along the surface, y, n): Heitz 2018, "Sampling the GGX Distribution of Visible
 * Normals", listing 1, with the view in the xz plane (its stretched view vh = (alpha sin_v, 0, cos_v)
 * normalised, the disc's axes y and vh x y), at (u1, u2) = ((k / 4 + 1/2) / 2, (k % 4 + 1/2) / 4). */
vec3 transmission_exit_normal(float sin_v, float cos_v, float alpha, int k)
{
  vec3 vh = normalize(vec3(alpha * sin_v, 0.0, cos_v));
  float r = sqrt((float(k / 4) + 0.5) * 0.5);
  float phi = 2.0 * PI * (float(k % 4) + 0.5) * 0.25;
  float a = r * cos(phi);
  float b = mix(sqrt(max(1.0 - a * a, 0.0)), r * sin(phi), 0.5 * (1.0 + vh.z));
  float c = sqrt(max(1.0 - a * a - b * b, 0.0));
  vec3 nh = vec3(c * vh.x - b * vh.z, a, b * vh.x + c * vh.z);
  return normalize(vec3(alpha * nh.xy, max(nh.z, 0.0)));
}

/* Ray k of the first crossing (entering glass of relative IOR eta along the view): its direction
 * inside, refracted by visible normal k (transmission_exit_normal), and its weight as Cycles samples
 * it (bsdf_microfacet_ggx_sample: the Fresnel's transmitted share, G2 / G1(v)); 0 where none crosses. */
float transmission_exit_ray(Surface s, float eta, int k, out vec3 d)
{
  vec3 x = s.v - s.n * s.NoV;
  float len2 = dot(x, x);
  /* the view along the normal: any direction along the surface */
  x = len2 > 1e-12 ? x * inversesqrt(len2) : normalize(cross(s.n, abs(s.n.z) < 0.9 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0)));
  vec3 m_local = transmission_exit_normal(sqrt(max(1.0 - s.NoV * s.NoV, 0.0)), s.NoV, s.alpha, k);
  vec3 m = x * m_local.x + cross(s.n, x) * m_local.y + s.n * m_local.z;
  d = transmission_direction(-s.v, m, eta);
  float cos_d = -dot(d, s.n);
  if (dot(d, d) <= 0.0 || cos_d <= 0.0) {
    return 0.0; /* reflected totally, or refracted back out across the surface */
  }
  float lambda_v = transmission_lambda(s.NoV, s.alpha);
  return transmission_fraction(dot(s.v, m), eta, s.transmission.fresnel) * (1.0 + lambda_v) /
         (1.0 + lambda_v + transmission_lambda(cos_d, s.alpha));
}

/* The quadrature's light through the far face from `light` arriving along l with irradiance E at the
 * exit point (transmission_exit_light's E), its lobes at `alpha`: each ray's far lobe towards the
 * light from where it meets the far face (a light with a position: its own direction, the irradiance
 * by the inverse square of its own distance; a sun: l), per unit E, averaged; without the near
 * face's compensation, weight and tints. */
float transmission_exit_quadrature(Surface s, LightData light, vec3 l, float alpha)
{
  float sum = 0.0;
  bool positioned = int(light.position_kind.w) != LIGHT_SUN;
  vec3 to_exit = light.position_kind.xyz - s.transmission.exit_p;
  /* (no turns on a flat far face: see transmission_exit_rays) */
  int rays = exit_curved > 0.0 ? EXIT_RAYS : 0;
  for (int k = 0; k < rays; k++) {
    if (exit_ray_weight[k] <= 0.0) {
      continue;
    }
    vec3 lk = l;
    float scale = 1.0;
    if (positioned) {
      vec3 to_light = light.position_kind.xyz - exit_ray_point[k];
      float d2 = max(dot(to_light, to_light), MIN_DIST2);
      lk = to_light * inversesqrt(d2);
      scale = max(dot(to_exit, to_exit), MIN_DIST2) / d2;
    }
    float HoV;
    float lobe = transmission_ggx(exit_ray_normal[k], -exit_ray_dir[k], lk, 1.0 / s.transmission.eta, alpha, HoV);
    if (lobe > 0.0) {
      sum += exit_ray_weight[k] * scale * transmission_fraction(HoV, 1.0 / s.transmission.eta, s.transmission.fresnel) *
             lobe;
    }
  }
  return sum / float(EXIT_RAYS);
}

/* What the lights through the glass share (the globals above), for the surface's view and the way
 * transmission_trace found: the compensations (glass_compensation) and the far face's spread loss,
 * what the first crossing's spread loses at the far face beyond the central ray's fraction (on a
 * sphere, rays turned towards its rim meet the far face more obliquely; a loss only: the spread can
 * raise the fraction a little, angles turned towards the normal; where the central ray passes
 * nothing, the lobes are all there is). `spread`: the programs' REFRACTION_EXIT_SPREAD. */
void transmission_prepare_lights(Surface s, float spread)
{
  TransmissionLobe t = s.transmission;
  glass_near_compensation = glass_compensation(t, s.roughness, s.NoV, t.eta);
  float cos2 = max(-dot(t.inner, t.exit_n), 0.0);
  glass_far_compensation = vec3(1.0);
  exit_loss = 1.0;
  /* (a loop of one turn or none, not an `if`: see transmission_exit_rays) */
  for (int once = 0; once < (t.exit ? 1 : 0); once++) {
    glass_far_compensation = glass_compensation(t, s.roughness, max(cos2, MIN_COS), 1.0 / t.eta);
    float inner_spread = transmission_inner_spread(s.NoV, -dot(t.inner, s.n), t.eta, s.alpha, spread);
    /* (the central ray's own fraction: transmission_exit_fraction at no spread) */
    bool rough = t.fresnel && s.roughness > MIN_PERCEPTUAL_ROUGHNESS;
    float central = rough ? glass_transmitted(s.roughness, cos2, 1.0 / t.eta)
                          : transmission_fraction(cos2, 1.0 / t.eta, t.fresnel);
    float spread_fraction = transmission_exit_fraction(cos2, t.eta, s.roughness, inner_spread, t.fresnel);
    exit_loss = central > 0.0 ? min(spread_fraction / central, 1.0) : 1.0;
  }
}

/* A light's radiance reaching the viewer through a closed object's far face (s.transmission.exit),
 * l and E taken at the exit point -- Cycles' light sampled at the second crossing of a path through
 * the object, after a first crossing sampled from the view's lobe. A light beyond that face shines
 * through both rough crossings: their lobes' convolution, taken as the mean of two single lobes, each
 * at the two crossings' roughness together (alpha_factor times the surface's alpha, the programs'
 * REFRACTION_EXIT_ALPHA: two GGX slopes summed, Student-t's of 2 degrees, peak as one of sqrt(3)
 * alpha): the far face's lobe seen from inside along the view ray refracted in, and the near face's
 * lobe towards the light's ray refracted in at the far face (smooth, by Snell's law, so that the far
 * face's bending of wide angles is exact: the light's irradiance crosses by cos_out / cos_in, the
 * adjoint lobe's eta^2 undone); times what the first crossing's spread loses at the far face beyond
 * the central ray's fraction (transmission_exit_fraction; `spread` the programs'
 * REFRACTION_EXIT_SPREAD). Against a Monte-Carlo integration of the two crossings'
 * single-scattering lobes (156 slabs and tilted far faces, IOR 1.33-1.8, alpha 0.03-0.5): 2.3 % of
 * their sum, median ratio 0.96. A light on the inside's side is reflected by the far face (GGX at the
 * same sqrt(3) alpha, the Fresnel from inside: all of it beyond the critical angle; a shadow-casting
 * light reaches there only through the object, which its shadow map shades). Times what crossed in
 * (s.transmission). Each rough lobe times its face's compensation for what single scattering loses
 * (glass_compensation: the far face's seen from inside along the view ray, 1 / eta; the near face's
 * at the view), as Cycles' glass closure at each face carries its own; the first crossing's fraction
 * (s.transmission.inside: 1 - the reflection's albedo) loses nothing already. */
vec3 transmission_exit_light(Surface s, LightData light, vec3 l, vec3 E, vec4 factors, float alpha_factor)
{
  TransmissionLobe t = s.transmission;
  vec3 n = t.exit_n;
  float alpha = s.alpha * alpha_factor;
#ifdef SL_TRANSMISSION_SPHERE_LIGHTS
  if (transmission_sphere_light(light)) {
    /* a sphere light widens both lobes by its angular radius in the far face's half-vector space
     * (lobe widths convolved add in quadrature, as size_lobe_weights' wide lobe; capped as there) */
    float theta = min(transmission_light_theta(light, t.exit_p, -t.inner, l, 1.0 / t.eta), 0.78539816);
    alpha = sqrt(alpha * alpha + theta * theta);
  }
#endif
  float NoL = dot(n, l);
  if (NoL < 0.0) {
    /* the far face's lobe, seen from inside along the view ray */
    float HoV;
    float lobe = transmission_ggx(n, -t.inner, l, 1.0 / t.eta, alpha, HoV);
    vec3 far = t.inside * glass_far_compensation *
               (lobe > 0.0 ? transmission_fraction(HoV, 1.0 / t.eta, t.fresnel) * lobe : 0.0);
    /* the near face's lobe towards the light's ray refracted in at the far face (which faces it: -n) */
    vec3 u = transmission_direction(-l, -n, t.eta);
    float cos_in = dot(u, n);
    vec3 near = vec3(0.0);
    if (cos_in > 0.0) {
      float HoV2;
      float lobe2 = transmission_ggx(s.n, s.v, -u, t.eta, alpha, HoV2);
      if (lobe2 > 0.0) {
        float crossings = transmission_fraction(HoV2, t.eta, t.fresnel) *
                          transmission_fraction(-NoL, t.eta, t.fresnel);
        near = t.tint * glass_near_compensation *
               (t.weight * crossings * lobe2 * (-NoL) / (t.eta * t.eta * cos_in));
      }
    }
    /* times what the first crossing's spread loses at the far face (transmission_prepare_lights) */
    vec3 lobes = t.tint * (0.5 * exit_loss) * (far + near);
    if (exit_curved > 0.0) {
      /* the quadrature's far lobes at the surface's own alpha (widened by a sphere light as above) */
      float alpha_q = sqrt(max(alpha * alpha - (alpha_factor * alpha_factor - 1.0) * s.alpha * s.alpha, 0.0));
      vec3 quadrature = t.tint * t.tint * glass_near_compensation *
                        (t.weight * transmission_exit_quadrature(s, light, l, alpha_q));
      lobes = mix(lobes, quadrature, exit_curved);
    }
    return lobes * (factors.y * E);
  }
  if (!t.fresnel) {
    return vec3(0.0); /* the Refraction BSDF reflects nothing */
  }
  vec3 v = -t.inner;
  float NoV = max(dot(n, v), MIN_COS);
  vec3 h = half_vector(l, v, n);
  vec3 NxH = cross(n, h);
  float lobe = D_GGX(dot(n, h), dot(NxH, NxH), alpha) * V_SmithGGXCorrelated(NoV, max(NoL, MIN_COS), alpha) * NoL;
  return t.inside * t.reflection_tint * glass_far_compensation * (F_Dielectric(1.0 / t.eta, dot(h, v)) * lobe * factors.y) * E;
}

/* The direction the view ray inside, along unit d, leaves through the far face (unit normal n facing
 * the inside, against d) into the outside (relative IOR 1 / eta): Snell's; where that reflects
 * totally, rough glass of `alpha` > 0 still passes some (glass_transmitted: the microfacets tilted
 * towards the ray refract it out near their own grazing angle), taken along the face turned
 * outwards by alpha radians (a microfacet's typical tilt); smooth glass passes none (0). */
vec3 transmission_exit_direction(vec3 d, vec3 n, float eta, float alpha)
{
  vec3 out_d = transmission_direction(d, n, 1.0 / eta);
  if (dot(out_d, out_d) > 0.0 || alpha <= 0.0) {
    return out_d;
  }
  vec3 along = d - dot(d, n) * n;
  float len2 = dot(along, along);
  /* (d along the normal never reflects totally: the guard is for rounding alone) */
  along = len2 > 1e-20 ? along * inversesqrt(len2) : vec3(0.0);
  return along * cos(alpha) - n * sin(alpha);
}

/* --- what lies behind, in screen space (passes.RefractionPass) ------------------------------ */

#  ifdef REFRACTION_LEVELS /* the shading programs drawn by the pass (programs.program_source) */

/* A world position's clip coordinates (the frame's camera). */
vec4 refraction_clip(vec3 p)
{
  return frame.view_proj * vec4(p, 1.0);
}

/* Distance along the camera's axis from the camera (perspective and orthographic alike). */
float refraction_view_depth(vec3 p)
{
  return dot(p - frame.camera_position.xyz, frame.camera_forward.xyz);
}

/* The depth (0..1) the pass's maps hold at texel t: the faces turned away from the viewer
 * (`back`), or the opaque scene (level 0 of refraction_behind holds it in alpha). */
float refraction_map_depth(bool back, ivec2 t)
{
  return back ? texelFetch(refraction_back_depth, t, 0).r : texelFetch(refraction_behind, t, 0).a;
}

/* How far along the ray p + t d it leaves the view (the clip volume -w <= x, y, z <= w: each bound
 * linear in t), at most `far`. */
float refraction_ray_end(vec4 c0, vec4 cd, float far)
{
  float t = far;
  for (int axis = 0; axis < 3; axis++) {
    for (int side = 0; side < 2; side++) {
      float sign = side == 0 ? 1.0 : -1.0;
      float f0 = c0.w - sign * c0[axis];
      float slope = cd.w - sign * cd[axis];
      if (slope < 0.0) {
        t = min(t, max(f0, 0.0) / -slope);
      }
    }
  }
  return t;
}

/* The pixel of clip position c (the target's texel) and its depth (0..1). */
vec3 refraction_pixel(vec4 c)
{
  vec3 ndc = c.xyz / c.w;
  return vec3((ndc.xy * 0.5 + 0.5) * frame.viewport.xy, ndc.z * 0.5 + 0.5);
}

/* The length along the ray of clip position c0 + t cd at which its depth (0..1) is `depth`: a
 * clip position's depth is linear over linear in t (perspective and orthographic alike), so this
 * is exact; -1 where the ray keeps one depth. */
float refraction_depth_crossing(vec4 c0, vec4 cd, float depth)
{
  float z = 2.0 * depth - 1.0;
  float slope = cd.z - z * cd.w;
  return abs(slope) > 1e-20 ? (z * c0.w - c0.z) / slope : -1.0;
}

/* Where the ray from p along unit d first passes behind the surface of a depth map (`back`: the
 * faces turned away, else the opaque scene), marched in steps even across the screen up to where it
 * leaves the view -- one per REFRACTION_STRIDE pixels of its way across the screen, at least one,
 * at most REFRACTION_STEPS (a ray along the view stays on a few pixels, where the depth behind it is
 * one: a step at its end finds it, the bisection and settling place it) -- the crossing refined by
 * bisection: xyz the point on the ray, w 1 where it met the surface (for the opaque scene: within
 * `thickness` of it along the view, so that a ray passing behind a nearer object goes on), 0 where
 * it met none (then xyz where it left the view). Positions along the screen map to the ray's length
 * perspective-correctly (1 / w is linear across the screen). */
vec4 refraction_march(bool back, vec3 p, vec3 d, float far)
{
  vec4 c0 = refraction_clip(p);
  vec4 cd = frame.view_proj * vec4(d, 0.0);
  float end = refraction_ray_end(c0, cd, far);
  float w1 = c0.w + end * cd.w;
  float across = distance(refraction_pixel(c0).xy, refraction_pixel(c0 + end * cd).xy);
  int steps = clamp(int(ceil(across / REFRACTION_STRIDE)), 1, REFRACTION_STEPS);
  /* the ray's length at a fraction f of its way across the screen */
  float previous = 0.0;
  for (int k = 1; k <= steps; k++) {
    float f = float(k) / float(steps);
    float t = f * end / w1 / ((1.0 - f) / c0.w + f / w1);
    vec3 q = refraction_pixel(c0 + t * cd);
    ivec2 texel = clamp(ivec2(q.xy), ivec2(0), ivec2(frame.viewport.xy) - 1);
    float depth = refraction_map_depth(back, texel);
    if (q.z >= depth && depth < 1.0) {
      /* behind the map's surface: bisect between the last step in front and this one */
      float lo = previous;
      float hi = t;
      for (int i = 0; i < REFRACTION_BISECTIONS; i++) {
        float mid = 0.5 * (lo + hi);
        vec3 m = refraction_pixel(c0 + mid * cd);
        ivec2 mt = clamp(ivec2(m.xy), ivec2(0), ivec2(frame.viewport.xy) - 1);
        if (m.z >= refraction_map_depth(back, mt)) {
          hi = mid;
        }
        else {
          lo = mid;
        }
      }
      /* then onto the map's surface: the ray's length where its depth is the map's at the texel
       * it reaches, again from there (the bracket's width is the march's step over 2^bisections:
       * with an orthographic camera whose view reaches 1000 m, 0.3 m; on the surface, the lights
       * through it see no shadow acne and the far face's normal is read where the ray is) */
      for (int i = 0; i < REFRACTION_SETTLE; i++) {
        vec3 m = refraction_pixel(c0 + hi * cd);
        ivec2 mt = clamp(ivec2(m.xy), ivec2(0), ivec2(frame.viewport.xy) - 1);
        float onto = refraction_depth_crossing(c0, cd, refraction_map_depth(back, mt));
        if (!(onto >= lo && onto <= hi)) {
          break; /* the texel's surface crosses the ray outside the bracket: keep it */
        }
        hi = onto;
      }
      vec3 hit = p + hi * d;
      if (back) {
        return vec4(hit, 1.0);
      }
      /* the opaque surface's point at that pixel, along the view */
      vec3 at = refraction_pixel(c0 + hi * cd);
      ivec2 ht = clamp(ivec2(at.xy), ivec2(0), ivec2(frame.viewport.xy) - 1);
      vec2 ndc = (vec2(ht) + 0.5) / frame.viewport.xy * 2.0 - 1.0;
      vec4 surface = refraction.inverse_view_projection *
                     vec4(ndc, refraction_map_depth(false, ht) * 2.0 - 1.0, 1.0);
      float gap = refraction_view_depth(hit) - refraction_view_depth(surface.xyz / surface.w);
      if (gap <= max(refraction.info.w, 2.0 * (t - previous))) {
        return vec4(hit, 1.0);
      }
    }
    previous = t;
  }
  return vec4(p + end * d, 0.0);
}

/* The far faces' normal at target position `pixel`: bilinear between the four texels around it that
 * hold a face (a texel's normal alone turns by up to the surface's curvature over a pixel: 3 degrees
 * on a 0.6 m sphere 20 pixels across, whose lights through it then fell into blocks), normalised. */
vec3 refraction_back_normal(vec2 pixel)
{
  vec2 x = pixel - 0.5;
  ivec2 i0 = ivec2(floor(x));
  vec2 f = x - vec2(i0);
  vec4 sum = vec4(0.0);
  for (int k = 0; k < 4; k++) {
    ivec2 o = ivec2(k & 1, k >> 1);
    ivec2 t = clamp(i0 + o, ivec2(0), ivec2(frame.viewport.xy) - 1);
    float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
    /* a texel no face covers (its depth the cleared 1) takes no part */
    w *= texelFetch(refraction_back_depth, t, 0).r < 1.0 ? 1.0 : 0.0;
    sum += w * vec4(texelFetch(refraction_back, t, 0).xyz, 1.0);
  }
  float len2 = dot(sum.xyz, sum.xyz);
  /* (no face around: the ray met one at `pixel`, so this is only where they cancel; the view's axis) */
  return len2 > 1e-20 ? sum.xyz * inversesqrt(len2) : -frame.camera_forward.xyz;
}

/* The copy of what is behind at target pixel `pixel`, its blurred level `lod` (0: the copy itself,
 * each next level half the size), bilinear within a level and linear between levels. */
vec3 refraction_level(int k, vec2 pixel)
{
  vec4 rect = refraction.rect[k];
  /* bilinear by hand within the level (its edge texels repeat): no filtering state to rely on */
  vec2 x = clamp(pixel * (rect.zw / frame.viewport.xy), vec2(0.5), rect.zw - 0.5) - 0.5;
  ivec2 i0 = ivec2(floor(x));
  vec2 f = x - vec2(i0);
  ivec2 i1 = min(i0 + 1, ivec2(rect.zw) - 1);
  ivec2 o = ivec2(rect.xy);
  vec3 a = mix(texelFetch(refraction_behind, o + i0, 0).rgb, texelFetch(refraction_behind, o + ivec2(i1.x, i0.y), 0).rgb,
               f.x);
  vec3 b = mix(texelFetch(refraction_behind, o + ivec2(i0.x, i1.y), 0).rgb, texelFetch(refraction_behind, o + i1, 0).rgb,
               f.x);
  return mix(a, b, f.y);
}

vec3 refraction_sample(vec2 pixel, float lod)
{
  lod = clamp(lod, 0.0, refraction.info.x - 1.0);
  int k = int(floor(lod));
  int k1 = min(k + 1, int(refraction.info.x) - 1);
  return mix(refraction_level(k, pixel), refraction_level(k1, pixel), lod - float(k));
}

/* The pixels a world-space radius r spans at p on screen. */
float refraction_pixels(vec3 p, float r)
{
  vec3 up = vec3(frame.view[0][1], frame.view[1][1], frame.view[2][1]); /* the camera's up in the world */
  vec3 a = refraction_pixel(refraction_clip(p));
  vec3 b = refraction_pixel(refraction_clip(p + r * up));
  return length(b.xy - a.xy);
}

/* The quadrature's rays (transmission_exit_ray) through the far face transmission_trace found, for
 * rough glass entering a closed object: each taken as far as the central ray went and moved onto the
 * far faces' depth at the pixel it reaches (the ray's length where its depth is that texel's:
 * refraction_depth_crossing), the far faces' normal read there (refraction_back_normal; where no far
 * face covers that pixel, the central ray's point and normal); its weight times the far face's
 * compensation for light leaving along it (white: 1 / E). exit_curved: the rays' mean turn of the far
 * normal over their mean turn from the central ray, at most 1 (a sphere's 1.6-2, a slab's 0). */
void transmission_exit_rays(Surface s)
{
  exit_curved = 0.0;
  TransmissionLobe t = s.transmission;
  /* (no rays but for rough glass leaving through a far face: a loop of no turns, where an `if` around
   * it would still be run at every pixel by the CPU rasteriser, which runs both sides of a branch
   * but leaves a loop no pixel is in) */
  int rays = t.exit && s.roughness > MIN_PERCEPTUAL_ROUGHNESS ? EXIT_RAYS : 0;
  float reach = distance(t.exit_p, s.p);
  vec4 c0 = refraction_clip(s.p);
  float turn = 0.0;
  float turn_normal = 0.0;
  for (int k = 0; k < rays; k++) {
    vec3 d;
    float w = transmission_exit_ray(s, t.eta, k, d);
    vec3 q = t.exit_p;
    vec3 n2 = t.exit_n;
    if (w > 0.0) {
      vec4 cd = frame.view_proj * vec4(d, 0.0);
      q = s.p + reach * d;
      ivec2 texel = clamp(ivec2(refraction_pixel(c0 + reach * cd).xy), ivec2(0), ivec2(frame.viewport.xy) - 1);
      float depth = texelFetch(refraction_back_depth, texel, 0).r;
      if (depth < 1.0) {
        float onto = refraction_depth_crossing(c0, cd, depth);
        q = onto > 0.0 ? s.p + onto * d : q;
        n2 = refraction_back_normal(refraction_pixel(refraction_clip(q)).xy);
        n2 = dot(n2, d) < 0.0 ? n2 : -n2;
      }
      else {
        q = t.exit_p;
      }
      /* (E >= 0.3 but at grazing: floored against a division by 0, as glass_compensation's) */
      w *= t.fresnel ? 1.0 / max(glass_albedo(s.roughness, max(-dot(d, n2), 0.0), 1.0 / t.eta).x, 1e-3) : 1.0;
      turn += w * acos(clamp(dot(d, t.inner), -1.0, 1.0));
      turn_normal += w * acos(clamp(dot(n2, t.exit_n), -1.0, 1.0));
    }
    exit_ray_dir[k] = d;
    exit_ray_point[k] = q;
    exit_ray_normal[k] = n2;
    exit_ray_weight[k] = w;
  }
  exit_curved = turn > 0.0 ? min(turn_normal / turn, 1.0) : 0.0;
}

/* The view ray's way into the glass and through it (s.transmission's inside, inner, exit_p, exit_n,
 * exit, behind), before the lights, which shine through it too: refracted into the surface
 * (entering: from the outside; else the viewer is inside, relative IOR 1 / eta), times the first
 * crossing's Fresnel (at the view: 1 - the reflection's albedo estimate for rough glass, all the
 * lobe's microfacets together) and tint; entering a closed object, it crosses to the face turned
 * away from the viewer that it meets (the back faces' depth and normals) and leaves there refracted
 * again; an open surface (a plane) has no such face. Then it is marched to the opaque scene. Nothing
 * crosses where the ray reflects totally (the viewer inside at a grazing angle, or inside at the far
 * face: then only the far face is found). The two marches are one loop (one copy of the march in the
 * program: on the CPU rasteriser every branch of it runs, and its size costs as much). */
void transmission_trace_ray(inout Surface s, bool entering)
{
  TransmissionLobe t = s.transmission;
  if (t.weight <= 0.0) {
    return;
  }
  float eta = entering ? t.eta : 1.0 / t.eta;
#  ifdef SL_LAYERS
  /* the reflection's albedo estimate at the view (the smooth Fresnel at roughness 0) */
  vec3 first = t.fresnel ? max(1.0 - s.layers.albedo, 0.0) : vec3(transmission_fraction(s.NoV, eta, false));
#  else
  vec3 first = vec3(transmission_fraction(s.NoV, eta, t.fresnel));
#  endif
  vec3 d = transmission_direction(-s.v, s.n, eta);
  if (dot(d, d) <= 0.0) {
    return; /* total internal reflection */
  }
  s.transmission.inside = t.weight * t.tint * first;
  s.transmission.inner = d;
  /* a closed object has a face turned away behind the fragment at its own pixel (the view ray
   * leaves through it); where none is (an open surface: a plane), nothing to march through */
  float far_face = texelFetch(refraction_back_depth, ivec2(gl_FragCoord.xy), 0).r;
  bool closed = entering && far_face < 1.0 && far_face > gl_FragCoord.z;
  vec3 start = s.p;
  for (int leg = closed ? 0 : 1; leg < 2; leg++) {
    vec4 hit = refraction_march(leg == 0, start, d, 1e6);
    if (leg == 1) {
      s.transmission.behind = hit.xyz;
    }
    /* (the ray leaves through a face turned away from the viewer at least a hair behind the
     * fragment: a face of its own, an open surface seen from behind, is no far side) */
    else if (hit.w > 0.5 && distance(hit.xyz, s.p) > 1e-5) {
      vec3 n2 = refraction_back_normal(refraction_pixel(refraction_clip(hit.xyz)).xy);
      n2 = dot(n2, d) < 0.0 ? n2 : -n2; /* facing the inside: against d */
      s.transmission.exit_n = n2;
      s.transmission.exit_p = hit.xyz;
      s.transmission.exit = true;
      start = hit.xyz;
      d = transmission_exit_direction(d, n2, eta, s.roughness > MIN_PERCEPTUAL_ROUGHNESS ? s.alpha : 0.0);
      if (dot(d, d) <= 0.0) {
        break; /* smooth glass totally reflecting inside: nothing behind is seen (transmission_behind) */
      }
    }
  }
}

/* transmission_trace_ray, then what the lights through the glass need of the way it found: the
 * curved far face's rays (transmission_exit_rays) and what every light shares
 * (transmission_prepare_lights). */
void transmission_trace(inout Surface s, bool entering)
{
  transmission_trace_ray(s, entering);
  transmission_exit_rays(s);
  transmission_prepare_lights(s, REFRACTION_EXIT_SPREAD);
}

/* Where a light's shadow is looked up for the far face: the exit point (on the depth map's
 * surface, which is flat across each texel, not on the mesh's) moved out along the face's normal by
 * two pixels' width there, so that the face's own shadow does not shade it (shadow acne in blocks of
 * the map's texels on a sphere's far side); a light on the inside's side stays in the object's
 * shadow. */
vec3 transmission_exit_lookup(Surface s)
{
  vec3 p = s.transmission.exit_p;
  float per_metre = refraction_pixels(p, 1.0);
  return p - s.transmission.exit_n * (2.0 / max(per_metre, 1e-6));
}

/* The radiance reaching the viewer through the surface from what lies behind it, along the way
 * transmission_trace found: out through a closed object's far face (times what that crossing passes,
 * transmission_exit_fraction, and tint; for smooth glass 0 where the ray reflects totally inside:
 * Cycles' internal reflections are glossy bounces, which its transmission tests turn off; rough glass
 * passes some there, along transmission_exit_direction) to the opaque scene behind
 * (or where it leaves the view). Rough glass reads a blurred level: the refracted lobe's spread,
 * alpha (1 - 1 / eta) radians entering and alpha (eta - 1) leaving (a microfacet tilted by alpha
 * turns the ray by that much), over the length it then travels, in pixels (with one level, the
 * frame's glass all smooth, the copy alone). */
vec3 transmission_behind(Surface s, bool entering)
{
  TransmissionLobe t = s.transmission;
  if (max(t.inside.r, max(t.inside.g, t.inside.b)) <= 0.0) {
    return vec3(0.0);
  }
  float eta = entering ? t.eta : 1.0 / t.eta;
  vec3 throughput = t.inside;
  vec3 start = s.p;
  float inside = 0.0;
  /* glass at the roughness floor is smooth: unblurred, as Cycles' (programs.REFRACTION_SMOOTH) */
  float alpha = s.roughness > MIN_PERCEPTUAL_ROUGHNESS ? s.alpha : 0.0;
  float spread_in = alpha * abs(1.0 - 1.0 / eta);
  float spread_out = 0.0;
  /* (a loop of one turn or none, not an `if`: see transmission_exit_rays) */
  for (int once = 0; once < (t.exit ? 1 : 0); once++) {
    float cos2 = -dot(t.inner, t.exit_n);
    vec3 out_d = transmission_exit_direction(t.inner, t.exit_n, eta, alpha);
    if (dot(out_d, out_d) <= 0.0) {
      return vec3(0.0); /* smooth glass totally reflecting inside */
    }
    float spread = transmission_inner_spread(s.NoV, -dot(t.inner, s.n), eta, alpha, REFRACTION_EXIT_SPREAD);
    throughput *= t.tint * transmission_exit_fraction(cos2, eta, alpha > 0.0 ? s.roughness : 0.0, spread,
                                                      t.fresnel);
    inside = distance(t.exit_p, s.p);
    start = t.exit_p;
    spread_out = alpha * abs(eta - 1.0);
  }
  float beyond = distance(t.behind, start);
  float radius = spread_in * (inside + beyond) + spread_out * beyond;
  float lod = log2(max(refraction_pixels(t.behind, radius) * REFRACTION_BLUR, 1.0));
  vec3 pixel = refraction_pixel(refraction_clip(t.behind));
  return throughput * refraction_sample(pixel.xy, lod);
}
#  endif
#endif
