/* Brick Texture (Cycles' svm_brick and svm_node_tex_brick, svm/brick.h): rows of bricks, every
 * `offset_frequency`-th row shifted by offset x width and every `squash_frequency`-th row's
 * bricks `squash` times as wide; each brick tinted by an integer noise of its row and column,
 * the mortar a band of `mortar_size` along the borders, smoothed. */

/* Cycles' brick_noise: an integer hash of n to [0, 1) (not util/hash.h's) */
float brick_noise(uint n)
{
  n = (n + 1013u) & 0x7fffffffu;
  n = (n >> 13) ^ n;
  uint nn = (n * (n * n * 60493u + 19990303u) + 1376312589u) & 0x7fffffffu;
  return 0.5 * (float(nn) / 1073741824.0);
}

/* Cycles' smoothstepf: 3f^2 - 2f^3 on [0, 1] (3f^2 fused into the difference), 0 below, 1 above */
float brick_smoothstep(float f)
{
  if (f <= 0.0) {
    return 0.0;
  }
  if (f >= 1.0) {
    return 1.0;
  }
  float ff = f * f;
  return float_fma(3.0, ff, -(2.0 * ff * f));
}

/* vec2(tint, mortar) at p (the coordinate times the node's Scale) */
vec2 brick_pattern(vec3 p, float mortar_size, float mortar_smooth, float bias, float brick_width,
                   float row_height, float offset_amount, int offset_frequency, float squash_amount,
                   int squash_frequency)
{
  int row = int(floor(p.y / row_height));
  float offset = 0.0;
  /* (Blender's frequencies are 1 .. 99; Cycles shifts and squashes nothing where one is 0) */
  if (offset_frequency != 0 && squash_frequency != 0) {
    /* C's remainder of a negative row is negative, and GLSL's % of one undefined: the remainder
     * of |row| is zero exactly where C's is */
    if (abs(row) % squash_frequency == 0) {
      brick_width *= squash_amount;
    }
    if (abs(row) % offset_frequency == 0) {
      offset = brick_width * offset_amount;
    }
  }
  int brick = int(floor((p.x + offset) / brick_width));
  /* the products rounded before the differences (PRECISE: Cycles does not fuse them, measured) */
  PRECISE float x = (p.x + offset) - brick_width * float(brick);
  PRECISE float y = p.y - row_height * float(row);
  /* the noise of (row, brick's low 16 bits), biased, kept in [0, 1] (Cycles' saturatef) */
  float tint = clamp(brick_noise(uint((row << 16) + (brick & 0xFFFF))) + bias, 0.0, 1.0);
  float min_dist = min(min(x, y), min(brick_width - x, row_height - y));
  float mortar;
  if (min_dist >= mortar_size) {
    mortar = 0.0;
  }
  else if (mortar_smooth == 0.0) {
    mortar = 1.0;
  }
  else {
    mortar = brick_smoothstep((1.0 - min_dist / mortar_size) / mortar_smooth);
  }
  return vec2(tint, mortar);
}

/* vec4(Color, Fac): the brick's colour between Color1 and Color2 by its tint, blended with the
 * mortar's by the mortar factor (Fac) */
vec4 node_tex_brick(vec3 co, vec4 color1, vec4 color2, vec4 mortar, float scale, float mortar_size,
                    float mortar_smooth, float bias, float brick_width, float row_height,
                    float offset_amount, float offset_frequency, float squash_amount,
                    float squash_frequency)
{
  vec2 f = brick_pattern(co * scale, mortar_size, mortar_smooth, bias, brick_width, row_height,
                         offset_amount, int(offset_frequency), squash_amount, int(squash_frequency));
  vec3 color = color1.rgb;
  if (f.y != 1.0) {
    color = float_fma(vec3(f.x), color2.rgb, (1.0 - f.x) * color); /* tint x Color2 fused */
  }
  return vec4(float_fma(mortar.rgb, vec3(f.y), color * (1.0 - f.y)), f.y); /* mortar x Fac fused */
}
