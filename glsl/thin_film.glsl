/* The Principled BSDF's Thin Film (SL_THIN_FILM): the iridescent Fresnel of a film of thickness d (nm)
 * and IOR n2 over the dielectric or the metallic base, as the Cycles of the Blender that read the
 * material evaluates it (kernel/closure/bsdf_util.h's fresnel_iridescence, bsdf_microfacet.h's
 * microfacet_fresnel), after Belcour & Barla 2017, "A Practical Extension to Microfacet Theory for
 * the Modeling of Varying Iridescence": the Airy series of the film's reflections, its mean in closed
 * form and its terms m = 1..3 through the Fourier transform of the colour matching functions at m
 * times the optical path difference, per polarisation, averaged. Twin: addon/reference/thin_film.py.
 *
 * Cycles' rule by version (snapshot.THIN_FILM_RULES, chosen by the reader), side by side below where
 * they differ: Blender 5.0's (no define) reads the CIE 1931 functions' transform from a table, films
 * the metal too and blends the film's IOR below 1 nm; 4.2 and 4.5's (SL_THIN_FILM_CYCLES_4) evaluate
 * Belcour & Barla's Gaussian fit of it in XYZ, leave the metal bare and blend below 30 nm. */

#ifdef SL_THIN_FILM

#  ifdef SL_THIN_FILM_CYCLES_4
/* Blender 4.2 and 4.5 (Cycles' iridescence_lookup_sensitivity): the sensitivity at path difference D
 * (nm) from Belcour & Barla's fit of the XYZ functions' transform, a Gaussian per channel (X two),
 * each about 1 at D = 0, turned into RGB by SL_THIN_FILM_RGB (reference/thin_film.py's gaussian_rgb:
 * 4.x multiplies the XYZ sum by the white point before its XYZ -> RGB); the real part the fit's
 * cosine, the imaginary part minus its sine (so that re cos(m phi) + im sin(m phi) is Cycles'
 * cos(pos phase + m phi)). Its constants: reference/thin_film.py's GAUSSIAN_*. */
void thin_film_sensitivity(float opd, out vec3 re, out vec3 im)
{
  const vec3 amp = vec3(5.4856e-13, 4.4201e-13, 5.2481e-13);
  const vec3 pos = vec3(1.6810e+06, 1.7953e+06, 2.2084e+06);
  const vec3 var = vec3(4.3278e+09, 9.3046e+09, 6.6121e+09);
  float phase = 2.0 * PI * 1e-9 * opd;
  vec3 a = amp * sqrt(2.0 * PI * var) * exp(-phase * phase * var);
  vec3 arg = pos * phase;
  re = a * cos(arg);
  im = -a * sin(arg);
  float a2 = 1.64408e-8 * exp(-4.5282e+09 * phase * phase);
  re.x += a2 * cos(2.2399e+06 * phase);
  im.x -= a2 * sin(2.2399e+06 * phase);
  re = SL_THIN_FILM_RGB * (re / 1.0685e-7);
  im = SL_THIN_FILM_RGB * (im / 1.0685e-7);
}

/* Below this thickness (nm) the film's IOR blends to the air's (Cycles 4.2 and 4.5) */
const float THIN_FILM_BLEND = 30.0;
#  else
/* Blender 5.0: the sensitivity at path difference D (nm) from thin_film_table (512 x 2 texels, row 0
 * its real part, row 1 its imaginary part, rgb, for x = 2 pi D / 60 um = i / 511; reference/
 * thin_film.py's sensitivity_table), linear between the table's entries and clamped at its ends, as
 * Cycles' lookup_table_read. */
void thin_film_sensitivity(float opd, out vec3 re, out vec3 im)
{
  float x = clamp(2.0 * PI * opd / 60000.0, 0.0, 1.0) * 511.0;
  int i = min(int(x), 511);
  int j = min(i + 1, 511);
  float t = x - float(i);
  re = mix(texelFetch(thin_film_table, ivec2(i, 0), 0).rgb, texelFetch(thin_film_table, ivec2(j, 0), 0).rgb, t);
  im = mix(texelFetch(thin_film_table, ivec2(i, 1), 0).rgb, texelFetch(thin_film_table, ivec2(j, 1), 0).rgb, t);
}

/* Below this thickness (nm) the film's IOR blends to the air's (Cycles 5.0) */
const float THIN_FILM_BLEND = 1.0;
#  endif

/* The film's interfaces are written with optical cosines q = n cos(theta) (Snell: n sin(theta) is the
 * view's sin(theta_i) in every layer, so q^2 = n^2 - sin^2(theta_i) = (n - 1)(n + 1) + cos_i^2), and
 * their transmittances T = 1 - R apart: the same reflectances and phases as Cycles'
 * fresnel_dielectric_polarized (its r_s = (cos_i + eta cos_t) / (cos_i - eta cos_t) is
 * (qa - qb) / (qa + qb)), without float32's cancellations in 1 - cos^2 at grazing views, in a film of
 * a high IOR (whose cos(theta_2) rounds to 1) and in 1 - R where R nears 1 (the twin's float64 keeps
 * them: Cycles' float32 has them too). */

/* q^2 of a layer of IOR n under the view at cosine cos_i (<= 0: total internal reflection into it):
 * (n - 1)(n + 1) + cos_i^2 keeps an IOR near 1 at grazing views, n^2 - (1 - cos_i)(1 + cos_i) one
 * below 1/2 (whose light enters only near normal views), each where the other cancels. */
float optical_cosine_sq(float n, float cos_i)
{
  return n < 0.5 ? n * n - (1.0 - cos_i) * (1.0 + cos_i) : (n - 1.0) * (n + 1.0) + cos_i * cos_i;
}

/* The interface from a layer of IOR^2 na2 above to one of nb2 below at optical cosines qa >= 0 and
 * qb > 0: the s- and p-reflectances R = r^2, r_s = (qa - qb) / (qa + qb), r_p = (nb2 qa - na2 qb) /
 * (nb2 qa + na2 qb), their transmittances T = 1 - R = 4 a b / (a + b)^2 and the amplitudes' signs (the
 * phase shift 0 or pi). */
void interface_polarized(float qa, float qb, float na2, float nb2, out vec2 R, out vec2 T, out vec2 sign_r)
{
  vec2 a = vec2(qa, nb2 * qa);
  vec2 b = vec2(qb, na2 * qb);
  vec2 inv = 1.0 / (a + b); /* a + b > 0: qb > 0 and the IORs are floored at 1e-5 */
  vec2 r = (a - b) * inv;
  R = r * r;
  T = 4.0 * (a * inv) * (b * inv);
  sign_r = vec2(r.x >= 0.0 ? 1.0 : -1.0, r.y >= 0.0 ? 1.0 : -1.0);
}

/* Cycles' fresnel_f82 and fresnel_f82_B, one channel: Schlick's curve less b cos (1 - cos)^6, and
 * the b whose curve passes through f82 at cos = 1/7. */
float F82_scalar(float f0, float b, float cos_i)
{
  float s = saturate(1.0 - cos_i);
  float s5 = pow5(s);
  return clamp(mix(f0, 1.0, s5) - b * cos_i * s5 * s, 0.0, 1.0);
}

float F82_b_of(float f0, float f82)
{
  const float f = 6.0 / 7.0;
  float f5 = pow5(f);
  return (7.0 / (f5 * f)) * (mix(f0, 1.0, f5) - f82);
}

/* Unit phasor of (re, im); 1 where it vanishes (Cycles'). */
vec2 unit_phasor(float re, float im)
{
  float mag = sqrt(re * re + im * im);
  return mag == 0.0 ? vec2(1.0, 0.0) : vec2(re, im) / mag;
}

/* One channel of a metal of IOR n + ik under a film of IOR eta1 at cosine cos_i (> 0), the view's
 * sin^2 sin2_view (eta1^2 (1 - cos_i^2), Snell's invariant: no cancellation as cos_i nears 1), Cycles'
 * fresnel_conductor_polarized with its F82 model (Born & Wolf 14.4.1 for the phases): the
 * reflectance of F82 with F0 recomputed against eta1 and the value f82 at cos = 1/7, alike for both
 * polarisations; the s- and p-phasors (re, im) in phase_s, phase_p. */
float conductor_polarized(float cos_i, float eta1, float sin2_view, float n, float k, float f82, out vec2 phase_s,
                          out vec2 phase_p)
{
  float t1 = n * n - k * k - sin2_view;
  float t2 = sqrt(t1 * t1 + 4.0 * n * n * k * k);
  float u2 = max(0.5 * (t2 + t1), 0.0);
  float v2 = max(0.5 * (t2 - t1), 0.0);
  float u = sqrt(u2);
  float v = sqrt(v2);
  float nr = n / eta1;
  float kr2 = (k / eta1) * (k / eta1);
  float F0 = ((nr - 1.0) * (nr - 1.0) + kr2) / ((nr + 1.0) * (nr + 1.0) + kr2);
  float ec = eta1 * cos_i;
  phase_s = unit_phasor(-u2 - v2 + ec * ec, -2.0 * ec * v);
  float nk2 = (n * n + k * k) * cos_i;
  phase_p = unit_phasor(nk2 * nk2 - eta1 * eta1 * (u2 + v2), 2.0 * ec * (2.0 * n * k * u - (n * n - k * k) * v));
  return F82_scalar(F0, F82_b_of(F0, f82), cos_i);
}

/* The film's reflectance for one polarisation (Belcour & Barla 2017, eq. 10; Cycles'
 * iridescence_airy_summation): the series' mean R12 + T121^2 R23 / (1 - R12 R23), then m = 1..3,
 * each C_m times the sensitivity at m D turned by phasor^m (re, im per channel). The transmittances
 * T12 = T121 and T23 come apart (interface_polarized): 1 - R12 R23 = T12 + R12 T23 and C_0 = Rs - T121
 * = -T12 T23 / (1 - R12 R23), Cycles' terms without their cancellation as both reflectances near 1. */
vec3 thin_film_airy(float R12, float T12, vec3 R23, vec3 T23, float opd, vec3 phasor_re, vec3 phasor_im)
{
  vec3 r123 = sqrt(R12 * R23);
  /* 1 - R12 R23 is 0 only where both interfaces reflect all (a view at 90 degrees onto a base that
   * reflects all): 1e-30 keeps Rs and C_0 at 0 there (their numerators are 0) */
  vec3 inv = 1.0 / max(T12 + R12 * T23, vec3(1e-30));
  vec3 Rs = T12 * T12 * R23 * inv;
  vec3 R = Rs + R12;
  vec3 Cm = -T12 * T23 * inv;
  vec3 acc_re = phasor_re;
  vec3 acc_im = phasor_im;
  for (int m = 1; m < 4; m++) {
    Cm *= r123;
    vec3 s_re, s_im;
    thin_film_sensitivity(float(m) * opd, s_re, s_im);
    R += Cm * 2.0 * (acc_re * s_re + acc_im * s_im);
    vec3 next_re = acc_re * phasor_re - acc_im * phasor_im;
    acc_im = acc_re * phasor_im + acc_im * phasor_re;
    acc_re = next_re;
  }
  return R;
}

/* The film's IOR: below THIN_FILM_BLEND nm it blends towards the air's by smoothstep, where the wave
 * optics of the Airy summation no longer apply. */
float thin_film_ior(vec4 film)
{
  return film.x < THIN_FILM_BLEND ? mix(1.0, film.y, smoothstep(0.0, THIN_FILM_BLEND, film.x)) : film.y;
}

/* The iridescent Fresnel over a dielectric of IOR eta (air above; `film` as MaterialData's thin_film:
 * thickness, IOR), Cycles' fresnel_iridescence<float>. */
vec3 F_ThinFilmDielectric(vec4 film, float eta, float cos_i)
{
  float n2 = thin_film_ior(film);
  cos_i = abs(cos_i);
  float q2sq = optical_cosine_sq(n2, cos_i);
  float q3sq = optical_cosine_sq(eta, cos_i);
  if (q2sq <= 0.0 || q3sq <= 0.0) {
    return vec3(1.0); /* total internal reflection at either interface */
  }
  float q2 = sqrt(q2sq);
  vec2 R12, T12, sign12, R23, T23, sign23;
  interface_polarized(cos_i, q2, 1.0, n2 * n2, R12, T12, sign12);
  interface_polarized(q2, sqrt(q3sq), n2 * n2, eta * eta, R23, T23, sign23);
  float opd = 2.0 * film.x * q2; /* 2 n2 d cos(theta_2) */
  vec3 Rs = thin_film_airy(R12.x, T12.x, vec3(R23.x), vec3(T23.x), opd, vec3(-sign12.x * sign23.x), vec3(0.0));
  vec3 Rp = thin_film_airy(R12.y, T12.y, vec3(R23.y), vec3(T23.y), opd, vec3(-sign12.y * sign23.y), vec3(0.0));
  return clamp(0.5 * (Rs + Rp), 0.0, 1.0);
}

/* The Principled BSDF's dielectric under the film (Cycles' microfacet_fresnel, generalized Schlick
 * with a film): the iridescent Fresnel, each channel scaled towards the tinted F0 over the
 * substrate's own F0 as it nears that F0 from 1; not where the substrate's F0 is below 1e-5 (an IOR of
 * 1: no tint to carry) or the film reflects everything. */
vec3 F_ThinFilmTinted(vec4 film, float eta, vec3 f0_tinted, float cos_i)
{
  vec3 F = F_ThinFilmDielectric(film, eta, cos_i);
  float ratio = (eta - 1.0) / (eta + 1.0);
  float f0 = ratio * ratio;
  if (f0 <= 1e-5 || all(equal(F, vec3(1.0)))) {
    return F;
  }
  vec3 s = clamp((F - 1.0) / (f0 - 1.0), 0.0, 1.0); /* f0 <= 0.99 (surface.glsl's eta): no division by 0 */
  return F * mix(vec3(1.0), f0_tinted / f0, s);
}

/* A metal's complex IOR from its F0 and F82-tint b (Gulbrandsen 2014, "Artist Friendly Metallic
 * Fresnel": F0 the reflectivity r, at most 0.999, the F82 value g the edge tint), as Cycles'
 * microfacet_fresnel reads the Principled BSDF's metal under a film; g in `g`. */
void thin_film_metal_ior(vec3 f0, vec3 b, out vec3 n, out vec3 k, out vec3 g)
{
  vec3 r = min(f0, vec3(0.999));
  g = vec3(F82_scalar(f0.r, b.r, 1.0 / 7.0), F82_scalar(f0.g, b.g, 1.0 / 7.0), F82_scalar(f0.b, b.b, 1.0 / 7.0));
  vec3 sqrt_r = sqrt(r);
  n = mix((1.0 + sqrt_r) / (1.0 - sqrt_r), (1.0 - r) / (1.0 + r), g);
  k = sqrt(max((r * (n + 1.0) * (n + 1.0) - (n - 1.0) * (n - 1.0)) / (1.0 - r), 0.0));
}

/* The iridescent Fresnel over the Principled BSDF's metal (its IOR n + ik and F82 value g from
 * thin_film_metal_ior), Cycles' fresnel_iridescence<Spectrum> with F82. */
vec3 F_ThinFilmMetal(vec4 film, vec3 n, vec3 k, vec3 g, float cos_i)
{
  float n2 = thin_film_ior(film);
  cos_i = abs(cos_i);
  float q2sq = optical_cosine_sq(n2, cos_i);
  if (q2sq <= 0.0) {
    return vec3(1.0); /* total internal reflection into the film */
  }
  float q2 = sqrt(q2sq);
  vec2 R12, T12, sign12;
  interface_polarized(cos_i, q2, 1.0, n2 * n2, R12, T12, sign12);
  float sin2_view = (1.0 - cos_i) * (1.0 + cos_i);
  vec3 R23;
  vec2 ps[3], pp[3];
  for (int c = 0; c < 3; c++) {
    R23[c] = conductor_polarized(q2 / n2, n2, sin2_view, n[c], k[c], g[c], ps[c], pp[c]);
  }
  float opd = 2.0 * film.x * q2; /* 2 n2 d cos(theta_2) */
  vec3 Rs = thin_film_airy(R12.x, T12.x, R23, 1.0 - R23, opd, -sign12.x * vec3(ps[0].x, ps[1].x, ps[2].x),
                           -sign12.x * vec3(ps[0].y, ps[1].y, ps[2].y));
  vec3 Rp = thin_film_airy(R12.y, T12.y, R23, 1.0 - R23, opd, -sign12.y * vec3(pp[0].x, pp[1].x, pp[2].x),
                           -sign12.y * vec3(pp[0].y, pp[1].y, pp[2].y));
  return clamp(0.5 * (Rs + Rp), 0.0, 1.0);
}

#endif

#ifdef SL_THIN_FILM
#  ifdef SL_LAYERS /* the Principled set's programs */
/* The film at the view (make_surface, after principled_layers_at): MaterialData's thin_film, the
 * metal's IOR under it, and what the film makes of the dielectric layer's albedo estimate, which
 * the base below loses: Cycles' bsdf_microfacet_estimate_albedo has no table for a film and takes
 * the specular reflection's Fresnel at the view instead, E M F(n.v) (the compensation M as without
 * the film: Cycles' average Fresnel Fss ignores it). A film of 0.1 nm or less is none (Cycles'
 * THINFILM_THICKNESS_CUTOFF); a film over an IOR of 1 still reflects (Cycles keeps the lobe). */
void thin_film_at(inout Surface s, vec4 film)
{
  s.thin_film = vec4(max(film.x, 0.0), max(film.y, 1e-5), 0.0, 0.0); /* IOR floored as Cycles' */
  if (s.thin_film.x <= 0.1) {
    return;
  }
#    ifndef SL_THIN_FILM_CYCLES_4 /* (4.x's metal has no film) */
#      ifdef SL_SPECULAR_TINT
  vec3 b = s.layers.metal_b;
#      else
  const vec3 b = vec3(0.0);
#      endif
  thin_film_metal_ior(min(s.base_color, vec3(1.0)), b, s.film_metal_n, s.film_metal_k, s.film_metal_g);
#    endif
  float E_mu = max(ms_albedo(s.NoV, s.roughness), 1e-3);
  s.layers.albedo = E_mu * s.layers.dielectric_M * F_ThinFilmTinted(s.thin_film, s.eta, s.layers.dielectric_f0, s.NoV);
  s.layers.layer = max(s.layers.albedo.r, max(s.layers.albedo.g, s.layers.albedo.b));
}

/* The metal's Fresnel under the film where the rule puts it there (Cycles 5.0 does, 4.2 and 4.5
 * leave the metal bare). */
bool thin_film_on_metal(Surface s)
{
#    ifdef SL_THIN_FILM_CYCLES_4
  return false;
#    else
  return s.thin_film.x > 0.1;
#    endif
}
#  endif
#endif
