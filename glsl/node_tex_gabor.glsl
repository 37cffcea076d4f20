/* Gabor Texture (Cycles' svm_node_tex_gabor, kernel/svm/gabor.h): sparse Gabor convolution
 * (Lagae et al. 2009, "Procedural noise using sparse Gabor convolution") with a fixed number of
 * impulses per cell and weights of +-1 (Tavernier et al. 2019, "Making Gabor noise fast and
 * normalized"), summed as phasors so that Phase and Intensity follow (Tricard et al. 2019,
 * "Procedural phasor noise", eqs. 8 and 9). The same hashes of the same keys, the same float
 * operations in the same order as Cycles; only the GPU's sin, cos and exp differ from C's by
 * ulps. The numpy twin is addon/reference/gabor.py.
 *
 * The loops test at their end (do-while; one loop over the neighbourhood's cells): Mesa's
 * llvmpipe runs a loop tested at its top once more, every pixel masked off (glsl/README.md);
 * measured on 512 x 512 points against nested for loops, interleaved in one process, fastest of
 * 8: 2D 0.39 -> 0.33 s, 3D 1.45 -> 1.18 s, the same values bit for bit. (It also runs both sides
 * of every `if`: the impulses beyond the unit radius cost as much as the others there, not on a
 * GPU whose pixels agree; a test skipping the cells beyond the unit radius saved nothing.) */

/* impulses per cell (Cycles' IMPULSES_COUNT) */
#define GABOR_IMPULSES 8
/* M_PI_F (rounds to the same float) and 2 M_PI_F, as Cycles' 2.0f * M_PI_F */
#define GABOR_PI 3.14159265
#define GABOR_TWO_PI (2.0 * GABOR_PI)

/* Cycles' compute_2d_gabor_kernel / compute_3d_gabor_kernel once the kernel's angle is known:
 * a unit Gaussian exp(-pi d^2) windowed by a Hann window (zero at the unit radius, where the
 * impulses stop), times the phasor (cos, sin) of the angle */
vec2 gabor_kernel(float distance_squared, float angle)
{
  float hann_window = 0.5 + 0.5 * cos(GABOR_PI * distance_squared);
  float gaussian_envelope = exp(-GABOR_PI * distance_squared);
  float windowed = gaussian_envelope * hann_window;
  return vec2(windowed * cos(angle), windowed * sin(angle));
}

/* The node's outputs from the summed phasor (svm_node_tex_gabor's tail): Value the sine part
 * over 6 standard deviations remapped to [0, 1], Phase its angle remapped to [0, 1], Intensity
 * its length over 6 standard deviations. atan2_accurate (common.glsl): the GPU's own atan is
 * 2e-5 relative off C's atan2f. */
vec3 gabor_outputs(vec2 phasor, float standard_deviation)
{
  float normalization = 6.0 * standard_deviation;
  float value = (phasor.y / normalization) * 0.5 + 0.5;
  float phase = (atan2_accurate(phasor.y, phasor.x) + GABOR_PI) / GABOR_TWO_PI;
  return vec3(value, phase, length(phasor) / normalization);
}

/* One impulse's share (the tail of Cycles' loop over a cell's impulses): the kernel added or
 * subtracted by a fair Bernoulli weight (its hash below 1/2: -1) */
vec2 gabor_impulse(float weight_hash, float distance_squared, float angle)
{
  return (weight_hash < 0.5 ? -1.0 : 1.0) * gabor_kernel(distance_squared, angle);
}

/* Cycles' compute_2d_gabor_noise_cell: the impulses of one cell at position (relative to the
 * cell), keyed by (cell, 3i + k); the kernel centre's hash is taken first (Cycles takes the
 * orientation's first: the same values, fewer hashes for impulses beyond the unit radius, where
 * the windowed kernel is zero and Cycles skips them). The orientation: a random one across pi
 * (the kernel is symmetric under a half turn), blended in by the isotropy. */
vec2 gabor_cell_2d(vec2 cell, vec2 position, float frequency, float isotropy, float base_orientation)
{
  vec2 noise = vec2(0.0);
  int i = 0;
  do {
    vec2 in_kernel = position - hash_vec3_to_vec2(vec3(cell, float(i * 3 + 1)));
    float distance_squared = dot(in_kernel, in_kernel);
    if (distance_squared < 1.0) {  /* beyond the unit radius the windowed kernel is 0: skipped */
      float random_orientation = (hash_vec3_to_float(vec3(cell, float(i * 3))) - 0.5) * GABOR_PI;
      float orientation = base_orientation + random_orientation * isotropy;
      vec2 frequency_vector = frequency * vec2(cos(orientation), sin(orientation));
      noise += gabor_impulse(hash_vec3_to_float(vec3(cell, float(i * 3 + 2))), distance_squared,
                             GABOR_TWO_PI * dot(in_kernel, frequency_vector));
    }
  } while (++i < GABOR_IMPULSES);
  return noise;
}

/* The offset of the n-th cell of the neighbourhood (3 x 3, or 3 x 3 x 3) from the point's, in
 * Cycles' loop order: x fastest, then y, then z */
vec3 gabor_cell_offset(int n) { return vec3(float(n % 3 - 1), float((n / 3) % 3 - 1), float(n / 9 - 1)); }

/* Cycles' compute_2d_gabor_noise: the 3 x 3 cells, each cell's sum added in Cycles' order */
vec2 gabor_noise_2d(vec2 coordinates, float frequency, float isotropy, float base_orientation)
{
  vec2 cell_position = floor(coordinates);
  vec2 local_position = coordinates - cell_position;
  vec2 sum = vec2(0.0);
  int n = 0;
  do {
    vec2 offset = gabor_cell_offset(n).xy;
    sum += gabor_cell_2d(cell_position + offset, local_position - offset, frequency, isotropy,
                         base_orientation);
  } while (++n < 9);
  return sum;
}

/* acosf(x) as atan2_accurate(sqrt((1 - x)(1 + x)), x): the GPU's acos is 1.6e-4 rad off C's
 * (common.glsl), and (1 - x)(1 + x) keeps its precision near |x| = 1 */
float gabor_acos(float x) { return atan2_accurate(sqrt((1.0 - x) * (1.0 + x)), x); }

/* Cycles' compute_3d_orientation: the base direction (a unit vector) turned by random
 * inclination and azimuth within pi each, blended in by the isotropy; the base unchanged for
 * anisotropic noise. inclination and azimuth: the base's spherical angles (Cycles takes them per
 * impulse: the same values; gabor_noise_3d takes them once, with gabor_acos). */
vec3 gabor_orientation_3d(vec3 orientation, float isotropy, vec2 angles, vec4 seed)
{
  if (isotropy == 0.0) {
    return orientation;
  }
  vec2 random_angles = hash_vec4_to_vec2(seed) * GABOR_PI;
  float inclination = angles.x + random_angles.x * isotropy;
  float azimuth = angles.y + random_angles.y * isotropy;
  float sin_inclination = sin(inclination);
  return vec3(sin_inclination * cos(azimuth), sin_inclination * sin(azimuth), cos(inclination));
}

/* Cycles' compute_3d_gabor_noise_cell: as gabor_cell_2d, keyed by (cell, 3i + k) */
vec2 gabor_cell_3d(vec3 cell, vec3 position, float frequency, float isotropy, vec3 base_orientation,
                   vec2 angles)
{
  vec2 noise = vec2(0.0);
  int i = 0;
  do {
    vec3 in_kernel = position - hash_vec4_to_vec3(vec4(cell, float(i * 3 + 1)));
    float distance_squared = dot(in_kernel, in_kernel);
    if (distance_squared < 1.0) {  /* beyond the unit radius the windowed kernel is 0: skipped */
      vec3 orientation = gabor_orientation_3d(base_orientation, isotropy, angles, vec4(cell, float(i * 3)));
      noise += gabor_impulse(hash_vec4_to_float(vec4(cell, float(i * 3 + 2))), distance_squared,
                             GABOR_TWO_PI * dot(in_kernel, frequency * orientation));
    }
  } while (++i < GABOR_IMPULSES);
  return noise;
}

/* Cycles' compute_3d_gabor_noise: the 3 x 3 x 3 cells, as gabor_noise_2d */
vec2 gabor_noise_3d(vec3 coordinates, float frequency, float isotropy, vec3 base_orientation)
{
  /* the base's inclination and, signed by its y, azimuth (Cycles' compute_3d_orientation); a
   * base along z has azimuth 0 (guards: Cycles' 0 / 0 there, NaN, the whole texture NaN; 0 is
   * Cycles' own azimuth for a base leaning the least towards +x) */
  float xy = length(base_orientation.xy);
  float azimuth = xy > 0.0 ? (base_orientation.y < 0.0 ? -1.0 : 1.0) * gabor_acos(base_orientation.x / xy)
                           : 0.0;
  vec2 angles = vec2(gabor_acos(base_orientation.z), azimuth);
  vec3 cell_position = floor(coordinates);
  vec3 local_position = coordinates - cell_position;
  vec2 sum = vec2(0.0);
  int n = 0;
  do {
    vec3 offset = gabor_cell_offset(n);
    sum += gabor_cell_3d(cell_position + offset, local_position - offset, frequency, isotropy,
                         base_orientation, angles);
  } while (++n < 27);
  return sum;
}

/* The node (svm_node_tex_gabor): the coordinate scaled, anisotropy clamped to [0, 1], frequency
 * floored at 0.001 (as Cycles: a zero frequency is a constant kernel); (Value, Phase, Intensity).
 * The scaled coordinate is `precise`: rounded as Cycles rounds it, whatever computed co (a
 * compiler may otherwise fold a constant scale into a constant product upstream: measured 2.7e-2
 * off Cycles at |x| = 5e4, where that one rounding moves the point by 4e-3).
 * Standard deviations (Cycles' compute_*_gabor_standard_deviation): sqrt(impulses x the weights'
 * second moment 1/2 x the squared kernel's integral, 1/4 in 2D, 1/(4 sqrt 2) in 3D). */
vec3 node_tex_gabor_2d(vec3 co, float scale, float frequency, float anisotropy, float orientation)
{
  PRECISE vec3 scaled = co * scale;
  float isotropy = 1.0 - clamp(anisotropy, 0.0, 1.0);
  vec2 phasor = gabor_noise_2d(scaled.xy, max(0.001, frequency), isotropy, orientation);
  return gabor_outputs(phasor, sqrt(float(GABOR_IMPULSES) * 0.5 * 0.25));
}

/* the 3D type: the orientation normalised (Cycles' normalize, a / |a|); a zero orientation is
 * the x axis (guards: Cycles' 0 / 0, NaN, the whole texture NaN) */
vec3 node_tex_gabor_3d(vec3 co, float scale, float frequency, float anisotropy, vec3 orientation)
{
  PRECISE vec3 scaled = co * scale;
  float isotropy = 1.0 - clamp(anisotropy, 0.0, 1.0);
  float len = length(orientation);
  vec3 direction = len > 0.0 ? orientation / len : vec3(1.0, 0.0, 0.0);
  vec2 phasor = gabor_noise_3d(scaled, max(0.001, frequency), isotropy, direction);
  return gabor_outputs(phasor, sqrt(float(GABOR_IMPULSES) * 0.5 * (1.0 / (4.0 * 1.41421356))));
}
