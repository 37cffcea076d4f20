/* The depth standing for deferred group g (0 <= g < 255: passes.GATED_GROUPS): (g + 1) / 256, exact
 * in float and in a 32-bit float depth texture, and never the far plane's 1. */
float deferred_depth(int group)
{
  return float(group + 1) * (1.0 / 256.0);
}
