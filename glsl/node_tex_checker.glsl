/* Checker Texture (Cycles' svm_checker and svm_node_tex_checker, svm/checker.h): 1 where the
 * parities of the three cell indices of p = co * scale agree as Cycles compares them
 * ((x odd == y odd) == z odd), else 0. */

float node_tex_checker(vec3 co, float scale)
{
  /* Cycles' nudge off the cell borders ((p + 1e-6) x 0.999999, "precision issues on unit
   * coordinates"), co x scale rounded before the sum (Cycles does not fuse them, measured): a
   * coordinate on a border falls in Cycles' cell */
  PRECISE vec3 p = float_mul_add(co, scale, 0.000001) * 0.999999;
  ivec3 i = abs(ivec3(floor(p)));
  bool xy = (i.x % 2) == (i.y % 2);
  return (int(xy) == i.z % 2) ? 1.0 : 0.0;
}

vec4 node_tex_checker_color(float fac, vec4 color1, vec4 color2)
{
  return vec4(fac == 1.0 ? color1.rgb : color2.rgb, 1.0);
}
