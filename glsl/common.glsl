/* Constants and small helpers shared by every term. */

#define PI 3.14159265358979323846
#define INV_PI 0.31830988618379067154

float saturate(float x)
{
  return clamp(x, 0.0, 1.0);
}

/* x^5 by multiplication: cheaper than pow() and exact at x = 0 (pow(0, 5) is defined, but the
 * multiplication keeps the GLSL and numpy twins bit-for-bit comparable). */
float pow5(float x)
{
  float x2 = x * x;
  return x2 * x2 * x;
}

/* Smallest perceptual roughness: alpha = r^2 must stay above zero or D_GGX is 0/0 at n = h.
 * 0.045 (alpha ~ 2e-3) is Filament's float32 floor; GGX peaks at 1/(pi alpha^2) ~ 8e4 there. */
#define MIN_PERCEPTUAL_ROUGHNESS 0.045

/* Smallest cosine used in a division (n.v, n.l at grazing angles). */
#define MIN_COS 1e-4

/* acos() through atan(y, x): Mesa llvmpipe's acos() was measured off by up to 1.6e-4 rad,
 * atan(sqrt(1 - x^2), x) by 3e-6 (tests/test_terms_gpu.py compares against float64). */
float acos_accurate(float x)
{
  x = clamp(x, -1.0, 1.0);
  return atan(sqrt(max(1.0 - x * x, 0.0)), x);
}

/* Point i of `count` spread evenly over the unit disc (Vogel's spiral: radius sqrt((i + 1/2) / count),
 * each turned from the last by the golden angle). */
vec2 vogel_disc(int i, int count)
{
  float r = sqrt((float(i) + 0.5) / float(count));
  float phi = 2.3999632 * float(i); /* the golden angle */
  return r * vec2(cos(phi), sin(phi));
}

/* The Diffuse BSDF's Oren-Nayar of roughness sigma in [0, 1] as Cycles sets it up
 * (bsdf_oren_nayar_setup: Fujii's improved model; 4.2 writes A's pi / 2 - 2 / 3 as (3 pi - 4) / 6): A,
 * B and the average albedo E_avg of its single scattering (5.0's multiple scattering reads it). Here because both the closure (node_closure.glsl,
 * in every program a node graph makes) and the lobe (closures.glsl) need it. */
vec3 oren_nayar_coefficients(float sigma)
{
  float a = 1.0 / (PI + sigma * (0.5 * PI - 2.0 / 3.0));
  float b = sigma * a;
  return vec3(a, b, a * PI + ((2.0 * PI - 5.6) / 3.0) * b);
}

/* atan2 to float precision, in every quadrant: Mesa llvmpipe's atan(y, x) was measured off by
 * 2.1e-5 relative at every scale (through tests/glsl_harness.py, against float64), and an area
 * light's form factor, a sum of edge angles that cancel, multiplied that into 2e-3 of the light a
 * 10 cm panel 1 m away sends. Cephes' atanf (Moshier 1992): the ratio reduced to |t| <= tan(pi / 8)
 * and an odd degree-9 polynomial; measured 2.2e-7 relative (tests/test_terms_gpu.py). */
float atan2_accurate(float y, float x)
{
  float ax = abs(x);
  float ay = abs(y);
  float t = min(ax, ay) / max(max(ax, ay), 1e-37);
  float r = 0.0;
  if (t > 0.41421356) {
    r = 0.78539816;
    t = (t - 1.0) / (t + 1.0);
  }
  float z = t * t;
  r += (((0.0805374449538 * z - 0.138776856032) * z + 0.199777106478) * z - 0.333329491539) * z * t + t;
  if (ay > ax) {
    r = 1.5707963 - r;
  }
  if (x < 0.0) {
    r = 3.1415927 - r;
  }
  return y < 0.0 ? -r : r;
}
