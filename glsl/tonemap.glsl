/* Display pipeline of the engine's own tone mappers (SPEC section 5): radiance x 2^EV, a tone
 * curve to display-linear [0, 1], and optionally the 2.2 gamma approximation. Blender's Standard
 * view transform then applies the exact sRGB encoding; for "gamma 2.2" the value is pre-decoded
 * so that Blender's encoding leaves y^(1/2.2) on the display. Numpy twin: addon/reference/tonemap.py. */

/* The seed's LDR pipeline: clip every channel to [0, 1]. */
vec3 tonemap_clamp(vec3 x)
{
  return clamp(x, 0.0, 1.0);
}

/* Reinhard et al. 2002, "Photographic Tone Reproduction for Digital Images", eq. 3 (the simple
 * global operator L / (1 + L)), applied per channel. */
vec3 tonemap_reinhard(vec3 x)
{
  return x / (1.0 + x);
}

/* Hable 2010, "Uncharted 2: HDR Lighting": the filmic curve with A..F = 0.15, 0.50, 0.10, 0.20,
 * 0.02, 0.30, linear white W = 11.2 and his exposure bias of 2. */
vec3 hable_curve(vec3 x)
{
  const float A = 0.15, B = 0.50, C = 0.10, D = 0.20, E = 0.02, F = 0.30;
  return ((x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F)) - E / F;
}

vec3 tonemap_hable(vec3 x)
{
  return clamp(hable_curve(2.0 * x) / hable_curve(vec3(11.2)), 0.0, 1.0);
}

/* ACES fitted: Stephen Hill's fit of the ACES RRT + sRGB ODT (BakingLab, 2016): sRGB -> ACES AP1
 * input matrix, the rational RRT/ODT fit, then back to sRGB. Matrices written row by row. */
vec3 tonemap_aces(vec3 x)
{
  mat3 to_ap1 = transpose(mat3(0.59719, 0.35458, 0.04823,
                                     0.07600, 0.90834, 0.01566,
                                     0.02840, 0.13383, 0.83777));
  mat3 from_ap1 = transpose(mat3(1.60475, -0.53108, -0.07367,
                                       -0.10208, 1.10813, -0.00605,
                                       -0.00327, -0.07276, 1.07602));
  vec3 v = to_ap1 * x;
  vec3 a = v * (v + 0.0245786) - 0.000090537;
  vec3 b = v * (0.983729 * v + 0.4329510) + 0.238081;
  return clamp(from_ap1 * (a / b), 0.0, 1.0);
}

/* The exact sRGB decoding (IEC 61966-2-1), used to pre-compensate Blender's encoding. */
vec3 srgb_to_linear(vec3 c)
{
  vec3 lo = c / 12.92;
  vec3 hi = pow((c + 0.055) / 1.055, vec3(2.4));
  return mix(lo, hi, step(vec3(0.04045), c));
}

/* "Gamma correction ~ power 2.2": encoding raises to 1/2.2 (SPEC: the seed's text says 2.2). */
vec3 transfer_gamma22(vec3 y)
{
  return srgb_to_linear(pow(max(y, 0.0), vec3(1.0 / 2.2)));
}

vec3 tonemap(vec3 x)
{
#if defined(SL_TONEMAP_REINHARD)
  return tonemap_reinhard(x);
#elif defined(SL_TONEMAP_HABLE)
  return tonemap_hable(x);
#elif defined(SL_TONEMAP_ACES)
  return tonemap_aces(x);
#elif defined(SL_TONEMAP_BLENDER)
  return x; /* automatic exposure only: Blender's view transform displays it */
#else
  return tonemap_clamp(x);
#endif
}
