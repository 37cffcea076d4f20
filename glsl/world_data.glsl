/* The world as one radiance field (glsl/environment.glsl): the constant terms' sum and up to
 * four image terms (weight, Mapping as a 4x4, x: projection 0 equirectangular / 1 mirror ball,
 * y: 1 for Closest interpolation). */
struct WorldData {
  vec4 constant_radiance; /* rgb: the constant terms' sum */
  vec4 weight[4];
  mat4 lookup[4];
  vec4 kind[4];
};
