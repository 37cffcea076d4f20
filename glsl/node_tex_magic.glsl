/* Magic Texture (Cycles' svm_magic and svm_node_tex_magic, svm/magic.h): three waves of the
 * coordinate, folded into one another `depth` times (0 .. 10), each fold scaled by the
 * distortion; Color (0.5 - x, 0.5 - y, 0.5 - z) after dividing by 2 x distortion (where it is not
 * 0), Fac the colour's average. Returned as vec4(Color, Fac). */

vec4 node_tex_magic(vec3 co, float scale, float distortion, float turbulence_depth)
{
  int depth = int(turbulence_depth);
  /* the coordinate reduced modulo 2 pi first, as Cycles does (C's fmodf, exactly), so that
   * large coordinates keep their precision and 5 (x + y + z) stays finite */
  float px = float_fmod(co.x, 6.2831855);
  float py = float_fmod(co.y, 6.2831855);
  float pz = float_fmod(co.z, 6.2831855);
  /* every sum and product in Cycles' order (PRECISE: a GPU may otherwise fold 5 x scale first,
   * measured: a different last bit, which the waves turn into 1e-5) */
  PRECISE float x = sin((px + py + pz) * 5.0 * scale);
  PRECISE float y = cos((-px + py - pz) * 5.0 * scale);
  PRECISE float z = -cos((-px - py + pz) * 5.0 * scale);
  float d = distortion;
  if (depth > 0) {
    y = -cos(float_fma(-y, d, x * d) + z * d) * d; /* x d - y d: y d fused, as Cycles' kernel does */
    x *= d;
    z *= d;
  }
  if (depth > 1) { x = cos(x - y - z) * d; }
  if (depth > 2) { z = sin(-x - y - z) * d; }
  if (depth > 3) { x = -cos(-x + y - z) * d; }
  if (depth > 4) { y = -sin(-x + y + z) * d; }
  if (depth > 5) { y = -cos(-x + y + z) * d; }
  if (depth > 6) { x = cos(x + y + z) * d; }
  if (depth > 7) { z = sin(x + y - z) * d; }
  if (depth > 8) { x = -cos(-x - y + z) * d; }
  if (depth > 9) { y = -sin(x - y + z) * d; }
  if (d != 0.0) { /* no division by a zero distortion: the waves are then left as they are */
    float inverse = 1.0 / (d * 2.0); /* Cycles' three divisions: one reciprocal (fast math) */
    x *= inverse;
    y *= inverse;
    z *= inverse;
  }
  vec3 color = vec3(0.5 - x, 0.5 - y, 0.5 - z);
  return vec4(color, (color.x + color.y + color.z) * 0.33333334);
}
