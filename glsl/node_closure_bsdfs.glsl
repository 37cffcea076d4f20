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

/* Specular BSDF (EEVEE's node_eevee_specular, gpu_shader_material_eevee_specular.glsl; Cycles renders
 * nothing for it): a Lambert base of Base Color and a GGX lobe of F0 = Specular (its largest channel,
 * the rest as the dielectric's F0 tint: the Principled set's Specular Tint, SL_SPECULAR_TINT), the
 * base beside the lobe (not under it: bsdfs.unlayered), its inputs clamped as EEVEE clamps them; Transparency a mix with Transparent; Emissive Color emitted
 * whatever the transparency, as EEVEE's. Clear Coat is not read. */
Closure closure_specular(vec4 base_color, vec4 specular, float roughness, vec4 emissive, float transparency,
                         vec3 n)
{
  vec3 f0 = max(specular.rgb, 0.0);
  float level = min(max(f0.r, max(f0.g, f0.b)), 1.0);
  Closure c = closure_bsdf(max(base_color.rgb, 0.0), 0.0, roughness, level, n);
  c.lobes.specular_tint = level > 0.0 ? f0 / level : vec3(1.0);
  c.bsdfs.diffuse_weight = 1.0;
  c.bsdfs.unlayered = 1.0; /* EEVEE adds its base and its lobe */
  float t = clamp(transparency, 0.0, 1.0);
  c = closure_scale(c, 1.0 - t);
  c.transparency = t;
  c.emission = max(emissive.rgb, 0.0);
  return c;
}

/* Metallic BSDF, F82 Tint (Cycles' CLOSURE_BSDF_F82_CONDUCTOR, bsdf_microfacet_setup_fresnel_f82_tint):
 * the Principled BSDF's metal lobe, whose Fresnel is this F82-tint of F0 = Base Color and its edge
 * tint = Edge Tint (the Principled set's Specular Tint, SL_SPECULAR_TINT), both within [0, 1] as
 * Cycles takes them, with its multiple-scattering compensation (Multiscatter GGX, the node's default
 * distribution). */
Closure closure_metallic_f82(vec4 base_color, vec4 edge_tint, float roughness, vec3 n)
{
  Closure c = closure_bsdf(clamp(base_color.rgb, 0.0, 1.0), 1.0, roughness, 0.0, n);
  c.lobes.specular_tint = clamp(edge_tint.rgb, 0.0, 1.0);
  return c;
}

/* Glossy BSDF, GGX, Beckmann and Ashikhmin-Shirley (Cycles' CLOSURE_BSDF_MICROFACET_GGX_ID,
 * _BECKMANN_ID, _ASHIKHMIN_SHIRLEY_ID: bsdf_microfacet.h, bsdf_ashikhmin_shirley.h): its colour times
 * the distribution's lobe, no Fresnel and no compensation (closure_glossy's, marked). */
Closure closure_glossy_ggx(vec4 color, float roughness, vec3 n)
{
  Closure c = closure_glossy(color, roughness, n);
  c.bsdfs.glossy.y = 1.0;
  return c;
}

Closure closure_glossy_beckmann(vec4 color, float roughness, vec3 n)
{
  Closure c = closure_glossy_ggx(color, roughness, n);
  c.bsdfs.glossy.z = 1.0;
  return c;
}

Closure closure_glossy_ashikhmin_shirley(vec4 color, float roughness, vec3 n)
{
  Closure c = closure_glossy_ggx(color, roughness, n);
  c.bsdfs.glossy.w = 1.0;
  return c;
}

/* Metallic BSDF, Physical Conductor (Cycles' CLOSURE_BSDF_PHYSICAL_CONDUCTOR, whose Fresnel is the exact
 * conductor Fresnel of IOR n + i Extinction k per channel, both at least 0 as Cycles takes them): its IOR
 * and Extinction for the lights' exact Fresnel (bsdfs.conductor: principled.glsl's
 * principled_specular_tint), in the F82-tint metal that fits it at normal incidence and at cos 1/7
 * (about 82 degrees) -- F0 = F(1) and the edge tint F(1/7) over Schlick's curve there, as Cycles fits it
 * for the lobe's average Fresnel (bsdf_util.h's fresnel_conductor_Fss) -- for its multiple-scattering
 * compensation (Cycles' own) and the world's split sum (within 0.033 of the exact Fresnel for gold,
 * silver, copper, aluminium, iron and chromium, where Schlick's rise from F0 errs by up to 0.20 before
 * grazing; docs/limits.md). The fitted tint is within [0, 1] but for conductors whose edge rises above
 * Schlick's (n < 1 with little extinction), which the F82-tint model cannot draw (clamped to 1, as the
 * Principled BSDF's tint). */
Closure closure_metallic_conductor(vec3 ior, vec3 extinction, float roughness, vec3 n)
{
  /* at least 0 (Cycles'); at most 1e4, where F_Conductor's n^2 k^2 is still a float32 (no metal's is
   * above about 30: beyond, the Fresnel is 1 within float32 anyway) */
  vec3 eta = clamp(ior, 0.0, 1e4);
  vec3 k = clamp(extinction, 0.0, 1e4);
  vec3 f0 = F_Conductor(eta, k, 1.0);
  /* Schlick's curve at cos 1/7, mix(f0, 1, (6/7)^5), is at least (6/7)^5 */
  vec3 tint = F_Conductor(eta, k, 1.0 / 7.0) / mix(f0, vec3(1.0), pow5(6.0 / 7.0));
  Closure c = closure_metallic_f82(vec4(f0, 1.0), vec4(tint, 1.0), roughness, n);
  c.bsdfs.conductor = vec4(eta, 1.0);
  c.bsdfs.conductor_k = k;
  return c;
}

/* The Metallic BSDF's GGX and Beckmann distributions: the metal lobe uncompensated (Cycles
 * compensates Multiscatter GGX alone), Beckmann's share of the specular lobe. */
Closure closure_metallic_ggx(Closure c)
{
  c.bsdfs.glossy.y = c.weight;
  return c;
}

Closure closure_metallic_beckmann(Closure c)
{
  c.bsdfs.glossy.yz = vec2(c.weight);
  return c;
}
