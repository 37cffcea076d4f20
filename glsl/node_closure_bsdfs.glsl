/* The closure nodes drawn beside the Principled BSDF's lobes (codegen.OPTIONAL_LIBRARY: only in the
 * programs whose graphs use them): the Sheen BSDF (Microfiber, Ashikhmin) and the Toon BSDF
 * (Diffuse, Glossy), each a Closure (glsl/node_closure.glsl) of its inputs as Cycles 5.0's
 * svm_node_closure_bsdf clamps them (kernel/svm/closure.h). The physically based model's Principled
 * set draws them where the program holds the lobe (SL_SHEEN, SL_VELVET, SL_TOON: glsl/closures.glsl);
 * the other models and term sets, which have no such lobe, draw each as a diffuse (the Toon BSDF's
 * Glossy component: a metal) of its colour. */

/* Sheen BSDF, Microfiber (Cycles' CLOSURE_BSDF_SHEEN_ID: Zeltner et al. 2022's sheen, bsdf_sheen.h):
 * the Principled BSDF's sheen lobe (principled.glsl's sheen_at) of this colour and roughness, over
 * nothing (not layered: bsdfs.sheen_layered 0) and with no base of its own. */
Closure closure_sheen_microfiber(vec4 color, float roughness, vec3 n)
{
#ifdef SL_SHEEN
  Closure c = closure_bsdf(vec3(0.0), 0.0, 1.0, 0.0, n);
  c.lobes.sheen = max(color.rgb, 0.0); /* a closure weight below 0 adds nothing (Cycles' cutoff) */
  c.lobes.sheen_weight = dot(c.lobes.sheen, vec3(1.0 / 3.0));
  c.lobes.sheen_roughness = c.lobes.sheen_weight * clamp(roughness, 0.0, 1.0);
  return c;
#else
  return closure_bsdf(color.rgb, 0.0, 1.0, 0.0, n);
#endif
}

/* Sheen BSDF, Ashikhmin (Cycles' CLOSURE_BSDF_ASHIKHMIN_VELVET_ID, bsdf_ashikhmin_velvet.h): its
 * colour and sigma = Roughness within [0, 1]. */
Closure closure_sheen_ashikhmin(vec4 color, float roughness, vec3 n)
{
#ifdef SL_VELVET
  Closure c = closure_bsdf(vec3(0.0), 0.0, 1.0, 0.0, n);
  c.bsdfs.velvet = max(color.rgb, 0.0);
  c.bsdfs.velvet_weight = 1.0;
  c.bsdfs.velvet_sigma = clamp(roughness, 0.0, 1.0);
  return c;
#else
  return closure_bsdf(color.rgb, 0.0, 1.0, 0.0, n);
#endif
}

/* Toon BSDF (Cycles' CLOSURE_BSDF_DIFFUSE_TOON_ID / _GLOSSY_TOON_ID, bsdf_toon.h): its colour, Size
 * within [1e-5, 1] and Smooth within [0, 1] (bsdf_toon_setup_common's clamps, before its pi / 2). */
Closure closure_toon(vec4 color, float size, float smooth_, vec3 n, bool glossy)
{
#ifdef SL_TOON
  Closure c = closure_bsdf(vec3(0.0), 0.0, 1.0, 0.0, n);
  vec3 shape = vec3(1.0, clamp(size, 1e-5, 1.0), clamp(smooth_, 0.0, 1.0));
  if (glossy) {
    c.bsdfs.toon_glossy = max(color.rgb, 0.0);
    c.bsdfs.toon_glossy_shape = shape;
  }
  else {
    c.bsdfs.toon_diffuse = max(color.rgb, 0.0);
    c.bsdfs.toon_diffuse_shape = shape;
  }
  return c;
#else
  return closure_bsdf(color.rgb, glossy ? 1.0 : 0.0, clamp(size, 0.0, 1.0), 0.0, n);
#endif
}
