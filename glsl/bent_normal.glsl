/* Cycles' rules for the light a normal bent by a node graph (a Normal Map, a Bump) takes: the
 * terminator's shadowing of each lobe (bump_terminator) and the specular lobes' normal lifted
 * until its mirror direction leaves the surface (valid_specular_normal). In the mesh program after
 * graph_surface.glsl, where a closure's Normal is linked (SL_GRAPH_BENT_NORMAL); numpy twins in
 * addon/reference/normals.py. */

#ifdef SL_GRAPH_BENT_NORMAL
/* A light's (diffuse, specular) weights where the graph bent the normal (a Normal Map, a Bump) to n
 * from the smooth normal ns: Cycles' bump_shadowing_term (kernel/closure/bsdf.h) of the Blender
 * that read the graph (materials/surface.py's bump_shadowing: one SL_BUMP_SHADOWING_<RULE>), with
 * its bump map correction (on by default). */
#  ifdef SL_BUMP_SHADOWING_CHIANG_2019
/* Blender 4.2's: for the diffuse lobe, Chiang, Li and Burley 2019, "Taming the Shadow
 * Terminator": g = (ns.l) / ((n.l)(ns.n)), ns turned to n's side of l; light below the smooth
 * surface (g < 0) is rejected, g in [0, 1) smoothed to -g^3 + g^2 + g. The specular lobe rejects
 * light on the other side of ns than of n (its microfacet eval's hemisphere test, handed sd->N). */
vec2 bump_terminator(vec3 ns, vec3 n, vec3 l)
{
  float cos_nl = dot(n, l);
  float specular = dot(ns, l) * cos_nl < 0.0 ? 0.0 : 1.0;
  vec3 s = cos_nl < 0.0 ? -ns : ns;
  float den = cos_nl * dot(s, n);
  float g = den != 0.0 ? dot(s, l) / den : 0.0; /* guards: Cycles' safe_divide (0 where n.l = 0) */
  if (g >= 1.0) {
    return vec2(1.0, specular);
  }
  if (g < 0.0) {
    return vec2(0.0, specular);
  }
  return vec2(g * (1.0 + g - g * g), specular);
}
#  else
/* Blender 4.5's and 5's: Conty Estevez, Lecocq and Stein 2019, "A Microfacet-Based Shadowing
 * Function to Solve the Bump Terminator Problem". Light from the other side of ns than n sees is
 * rejected (both lobes: Blender 5 tests it here, 4.5 in the diffuse lobe's and in the microfacet
 * eval's hemisphere test, handed sd->N); the diffuse lobe is shadowed by Smith's GGX G1 at the
 * light's angle to ns, with alpha^2 = tan^2(d) / 8 from the bend d. */
vec2 bump_terminator(vec3 ns, vec3 n, vec3 l)
{
  float cos_nsl = dot(ns, l);
  float cos_nsn = dot(ns, n);
  if (cos_nsl * cos_nsn * dot(n, l) < 0.0) {
    return vec2(0.0);
  }
  float cos_i = abs(cos_nsl);
  float cos_d = abs(cos_nsn);
  if (cos_d >= 1.0 || cos_i >= 1.0) {
    return vec2(1.0);
  }
  if (cos_i < 1e-6) {
    return vec2(0.0, 1.0); /* grazing the smooth surface: Cycles' diffuse gets nothing */
  }
  float alpha2 = clamp(0.125 * (1.0 / (cos_d * cos_d) - 1.0), 0.0, 1.0);
  float tan2_i = 1.0 / (cos_i * cos_i) - 1.0;
  return vec2(2.0 / (1.0 + sqrt(1.0 + alpha2 * tan2_i)), 1.0);
}
#  endif

/* Cycles' ensure_valid_specular_reflection (kernel/closure/bsdf_util.h; the same in Blender 4.2 to
 * 5), which its glossy closures and the Principled BSDF's specular lobes apply to their normal
 * (maybe_ensure_valid_specular_reflection, with bump map correction), not its diffuse lobe: n
 * turned towards the true normal ng (facing the viewer), in their common plane, just enough that
 * the view's mirror direction about it leaves the surface min(0.9 ng.i, 0.01) above it. The unit
 * normal's height z over the surface solves 4 a z^4 - 2 b z^2 + c = 0 (a = (i.x)^2 + (i.ng)^2,
 * b = 2 (a + (i.ng) t), c = ((i.ng) + t)^2 for the threshold t), the root of the side i.x has. */
vec3 valid_specular_normal(vec3 ng, vec3 i, vec3 n)
{
  float iz = dot(i, ng);
  float threshold = min(0.9 * iz, 0.01);
  if (dot(ng, 2.0 * dot(n, i) * n - i) >= threshold) {
    return n;
  }
  vec3 x = n - dot(n, ng) * ng;
  float len = length(x);
  x = len > 0.0 ? x / len : n; /* guards: n along ng (Cycles' safe_normalize_fallback) */
  float ix = dot(i, x);
  float a = ix * ix + iz * iz;
  if (a <= 0.0) {
    return n; /* guards: a view along no direction of the plane (i = 0): nothing to mirror */
  }
  float b = 2.0 * (a + iz * threshold);
  float c = (threshold + iz) * (threshold + iz);
  float root = sqrt(max(b * b - 4.0 * a * c, 0.0)); /* guards: Cycles' safe_sqrtf (rounding below 0) */
  float z2 = 0.25 * (ix < 0.0 ? b + root : b - root) / a;
  return sqrt(max(1.0 - z2, 0.0)) * x + sqrt(max(z2, 0.0)) * ng; /* guards: safe_sqrtf as Cycles */
}
#endif

