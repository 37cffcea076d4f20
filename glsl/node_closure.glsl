/* The shader nodes of a compiled graph (addon/materials/codegen.py): what each closure gives the
 * shading models, per fragment. A rasteriser shades one set of inputs per fragment, so a closure is
 * the inputs of the BSDFs under it, each times its weight and summed (Mix Shader and Add Shader are
 * linear in their closures, and so are these sums), with the emitted radiance and the transparent
 * share beside them. material_surface divides the inputs by the BSDFs' total weight and scales the
 * shaded radiance by it: exact for one BSDF mixed with Transparent, Emission or nothing, and for
 * BSDFs of equal inputs; BSDFs of different inputs are shaded with their weighted mean inputs
 * (what a rasteriser with one lobe per fragment can do; the Material panel says so). */

/* The Principled BSDF's lobes beyond its base (glsl/principled.glsl), each times its closure's
 * weight as the inputs below; the coat's and the sheen's own inputs also times the lobe's weight, so
 * that apply_closure takes their means over the closures that have the lobe. */
struct ClosureLobes {
  vec3 specular_tint;
  float coat;            /* Coat Weight */
  float coat_roughness;  /* each of the coat's inputs times the Coat Weight */
  float coat_ior;
  vec3 coat_tint;
  vec3 coat_normal;
  vec3 sheen;            /* Sheen Weight x Sheen Tint */
  float sheen_weight;    /* its mean over the channels: what Sheen Roughness is weighted by */
  float sheen_roughness; /* times that */
  float thin_film;       /* Thin Film Thickness (nm) */
  float thin_film_ior;   /* Thin Film IOR times the thickness */
  vec3 tangent;          /* the anisotropic lobe's tangent (unit, node_anisotropy.glsl; 0: none) */
  float stretch;         /* its roughness stretch k (alpha_x = alpha k, alpha_y = alpha / k; 1: none) */
  vec3 translucent;      /* the Translucent BSDFs' colour (glsl/subsurface.glsl) */
  float subsurface;      /* Subsurface Weight (the Subsurface Scattering node's: 1) */
  vec3 subsurface_radius; /* its mean free paths (m, per channel: glsl/subsurface.glsl) times that */
  float transmission;    /* the glass share of the non-metallic part (glsl/transmission.glsl) */
  float transmission_ior;     /* each of the glass's inputs times that share */
  vec3 transmission_tint;
  float transmission_fresnel; /* 1: the Fresnel splits reflection and transmission (0: Refraction BSDF) */
  vec3 reflection_tint;  /* the dielectric reflection's tint, times the closure's weight (the Glass
                          * BSDF's Color, 0 for the Refraction BSDF, else white) */
  vec4 subsurface_walk;  /* the subsurface's random walk row (node_subsurface.glsl) times its weight */
};

ClosureLobes lobes_none()
{
  return ClosureLobes(vec3(0.0), 0.0, 0.0, 0.0, vec3(0.0), vec3(0.0), vec3(0.0), 0.0, 0.0, 0.0, 0.0,
                      vec3(0.0), 0.0, vec3(0.0), 0.0, vec3(0.0), 0.0, 0.0, vec3(0.0), 0.0, vec3(0.0),
                      vec4(0.0));
}

/* A BSDF's own lobes of weight 1: a white Specular Tint, no coat, no sheen, isotropic. */
ClosureLobes lobes_base()
{
  ClosureLobes l = lobes_none();
  l.specular_tint = vec3(1.0);
  l.stretch = 1.0;
  l.reflection_tint = vec3(1.0);
  return l;
}

ClosureLobes lobes_scale(ClosureLobes l, float w)
{
  return ClosureLobes(l.specular_tint * w, l.coat * w, l.coat_roughness * w, l.coat_ior * w, l.coat_tint * w,
                      l.coat_normal * w, l.sheen * w, l.sheen_weight * w, l.sheen_roughness * w,
                      l.thin_film * w, l.thin_film_ior * w, l.tangent * w, l.stretch * w,
                      l.translucent * w, l.subsurface * w, l.subsurface_radius * w,
                      l.transmission * w, l.transmission_ior * w, l.transmission_tint * w,
                      l.transmission_fresnel * w, l.reflection_tint * w, l.subsurface_walk * w);
}

ClosureLobes lobes_add(ClosureLobes a, ClosureLobes b)
{
  return ClosureLobes(a.specular_tint + b.specular_tint, a.coat + b.coat, a.coat_roughness + b.coat_roughness,
                      a.coat_ior + b.coat_ior, a.coat_tint + b.coat_tint, a.coat_normal + b.coat_normal,
                      a.sheen + b.sheen, a.sheen_weight + b.sheen_weight, a.sheen_roughness + b.sheen_roughness,
                      a.thin_film + b.thin_film, a.thin_film_ior + b.thin_film_ior, a.tangent + b.tangent,
                      a.stretch + b.stretch, a.translucent + b.translucent, a.subsurface + b.subsurface,
                      a.subsurface_radius + b.subsurface_radius,
                      a.transmission + b.transmission, a.transmission_ior + b.transmission_ior,
                      a.transmission_tint + b.transmission_tint, a.transmission_fresnel + b.transmission_fresnel,
                      a.reflection_tint + b.reflection_tint, a.subsurface_walk + b.subsurface_walk);
}

/* The closure nodes beyond the Principled BSDF's lobes (glsl/closures.glsl draws them), each input
 * times its closure's weight as the Closure's: the Diffuse BSDF's roughness over the BSDFs with a
 * diffuse base, the Sheen BSDF's (a sheen not layered over anything: the share of the sheen that
 * is the Principled BSDFs' layers the rest), Ashikhmin's velvet and the Toon BSDF's components. */
struct ClosureBsdfs {
  float diffuse_weight;     /* the weight of the BSDFs with a diffuse base (all but Glossy) */
  float diffuse_roughness;  /* the Diffuse BSDFs' Roughness times their weight */
  vec3 diffuse_ms;          /* their Oren-Nayar's multiple scattering: Color x E_ms(Color) x weight */
  float sheen_layered;      /* the Principled BSDFs' sheen_weight (ClosureLobes'): layered over them */
  float unlayered;          /* the weight of diffuse bases beside their specular layer, not under it */
  vec3 velvet;              /* Sheen BSDF (Ashikhmin): Color x weight */
  float velvet_weight;
  float velvet_sigma;       /* its Roughness times velvet_weight */
  vec3 toon_diffuse;        /* Toon BSDF (Diffuse): Color x weight */
  vec3 toon_diffuse_shape;  /* its weight, Size and Smooth times it */
  vec3 toon_glossy;         /* Toon BSDF (Glossy) likewise */
  vec3 toon_glossy_shape;
  vec4 glossy;              /* the weights of the metal lobes of a constant Fresnel (Glossy BSDF: its
                             * colour), of those uncompensated (GGX, Beckmann, Ashikhmin-Shirley), of
                             * the Beckmann and the Ashikhmin-Shirley distributions */
  vec4 conductor;           /* Metallic BSDF (Physical Conductor): rgb its IOR x weight, w its weight */
  vec3 conductor_k;         /* its Extinction x weight */
};

ClosureBsdfs bsdfs_none()
{
  return ClosureBsdfs(0.0, 0.0, vec3(0.0), 0.0, 0.0, vec3(0.0), 0.0, 0.0, vec3(0.0), vec3(0.0), vec3(0.0),
                      vec3(0.0), vec4(0.0), vec4(0.0), vec3(0.0));
}

ClosureBsdfs bsdfs_scale(ClosureBsdfs b, float w)
{
  return ClosureBsdfs(b.diffuse_weight * w, b.diffuse_roughness * w, b.diffuse_ms * w, b.sheen_layered * w,
                      b.unlayered * w, b.velvet * w,
                      b.velvet_weight * w, b.velvet_sigma * w, b.toon_diffuse * w, b.toon_diffuse_shape * w,
                      b.toon_glossy * w, b.toon_glossy_shape * w, b.glossy * w, b.conductor * w,
                      b.conductor_k * w);
}

ClosureBsdfs bsdfs_add(ClosureBsdfs a, ClosureBsdfs b)
{
  return ClosureBsdfs(a.diffuse_weight + b.diffuse_weight, a.diffuse_roughness + b.diffuse_roughness,
                      a.diffuse_ms + b.diffuse_ms, a.sheen_layered + b.sheen_layered, a.unlayered + b.unlayered,
                      a.velvet + b.velvet, a.velvet_weight + b.velvet_weight, a.velvet_sigma + b.velvet_sigma, a.toon_diffuse + b.toon_diffuse,
                      a.toon_diffuse_shape + b.toon_diffuse_shape, a.toon_glossy + b.toon_glossy,
                      a.toon_glossy_shape + b.toon_glossy_shape, a.glossy + b.glossy,
                      a.conductor + b.conductor, a.conductor_k + b.conductor_k);
}

struct Closure {
  float weight;        /* the BSDFs' total weight */
  vec3 base_color;     /* the BSDFs' inputs, each times its weight */
  float metallic;
  float roughness;
  float specular;      /* dielectric F0 (0: no specular lobe, a Diffuse BSDF's) */
  vec3 normal;
  vec3 emission;       /* emitted radiance, W/(m^2 sr) */
  float transparency;  /* the Transparent BSDFs' weight (their colour's mean: the coverage is grey) */
  float holdout;       /* the Holdout closures' weight: the share of the pixel left transparent in the
                        * render's alpha, hiding what is behind (Cycles' holdout) */
  ClosureLobes lobes;
  ClosureBsdfs bsdfs;
};

Closure closure_none()
{
  return Closure(0.0, vec3(0.0), 0.0, 0.0, 0.0, vec3(0.0), vec3(0.0), 0.0, 0.0, lobes_none(), bsdfs_none());
}

/* A BSDF of weight 1 with these inputs. */
Closure closure_bsdf(vec3 base_color, float metallic, float roughness, float specular, vec3 n)
{
  return Closure(1.0, base_color, clamp(metallic, 0.0, 1.0), clamp(roughness, 0.0, 1.0),
                 clamp(specular, 0.0, 1.0), n, vec3(0.0), 0.0, 0.0, lobes_base(), bsdfs_none());
}

Closure closure_scale(Closure c, float w)
{
  return Closure(c.weight * w, c.base_color * w, c.metallic * w, c.roughness * w, c.specular * w,
                 c.normal * w, c.emission * w, c.transparency * w, c.holdout * w,
                 lobes_scale(c.lobes, w), bsdfs_scale(c.bsdfs, w));
}

Closure closure_add(Closure a, Closure b)
{
  return Closure(a.weight + b.weight, a.base_color + b.base_color, a.metallic + b.metallic,
                 a.roughness + b.roughness, a.specular + b.specular, a.normal + b.normal,
                 a.emission + b.emission, a.transparency + b.transparency, a.holdout + b.holdout,
                 lobes_add(a.lobes, b.lobes), bsdfs_add(a.bsdfs, b.bsdfs));
}

/* Mix Shader: (1 - fac) a + fac b, the factor clamped to [0, 1] as Cycles' svm_node_mix_closure */
Closure closure_mix(float fac, Closure a, Closure b)
{
  float t = clamp(fac, 0.0, 1.0);
  return closure_add(closure_scale(a, 1.0 - t), closure_scale(b, t));
}

/* A diffuse base's Oren-Nayar roughness (glsl/closures.glsl, where the program draws it:
 * SL_DIFFUSE_ROUGHNESS) on closure c: sigma = roughness clamped to [0, 1] as bsdf_oren_nayar_setup
 * clamps it (Lambert below 1e-5: Cycles' bsdf_diffuse_setup, CLOSURE_WEIGHT_CUTOFF), and its multiple
 * scattering's colour here, per closure, as it is not linear in the colour: weight x E_ms, E_ms =
 * rho^2 E_avg / (1 - E_avg) / (pi (1 - rho (1 - E_avg))) of rho = `color` within [0, 1]
 * (bsdf_oren_nayar_setup; `color` the closure's weight: the Diffuse BSDF's Color, the Principled BSDF's
 * Base Color). Twin: addon/reference/closures.py's oren_nayar_ms. */
Closure closure_oren_nayar(Closure c, vec3 color, float roughness)
{
  float sigma = clamp(roughness, 0.0, 1.0);
  c.bsdfs.diffuse_roughness = sigma;
  c.bsdfs.diffuse_ms = vec3(0.0);
  if (sigma >= 1e-5) {
    float e_avg = oren_nayar_coefficients(sigma).z; /* < 1 for sigma >= 1e-5 */
    vec3 rho = clamp(color, 0.0, 1.0);
    c.bsdfs.diffuse_ms = color * rho * rho * (e_avg / (1.0 - e_avg)) * INV_PI / (1.0 - rho * (1.0 - e_avg));
  }
  return c;
}

/* The Principled BSDF's inputs the shading models read: the dielectric F0 from IOR and Specular
 * IOR Level as the constant path reads them (addon/blender/extract.py: F0(IOR) x 2 x level, at
 * most 1), Alpha as a mix with Transparent (Cycles' principled alpha), emission under it too; its
 * lobes' inputs clamped as Cycles' svm_node_closure_bsdf clamps them (weights and tints at least 0,
 * roughnesses within [0, 1], the coat's IOR at least 1, the film's thickness at least 0 and IOR at
 * least 1e-5), the coat's normal the BSDF's where
 * nothing is linked to it (codegen passes n then). */
Closure closure_principled(vec4 base_color, float metallic, float roughness, float ior, float level,
                           float alpha, vec4 emission_color, float emission_strength, vec4 specular_tint,
                           float coat, float coat_roughness, float coat_ior, vec4 coat_tint, float sheen,
                           float sheen_roughness, vec4 sheen_tint, float thin_film, float thin_film_ior,
                           float transmission, vec3 n, vec3 coat_n, float subsurface, vec3 subsurface_path,
                           float diffuse_roughness, vec4 subsurface_walk)
{
  float r = (max(ior, 1.0) - 1.0) / (max(ior, 1.0) + 1.0);
  Closure c = closure_bsdf(base_color.rgb, metallic, roughness, min(r * r * 2.0 * max(level, 0.0), 1.0), n);
  c.lobes.specular_tint = max(specular_tint.rgb, 0.0);
  c.lobes.coat = max(coat, 0.0);
  c.lobes.coat_roughness = c.lobes.coat * clamp(coat_roughness, 0.0, 1.0);
  c.lobes.coat_ior = c.lobes.coat * max(coat_ior, 1.0);
  c.lobes.coat_tint = c.lobes.coat * max(coat_tint.rgb, 0.0);
  c.lobes.coat_normal = c.lobes.coat * coat_n;
  c.lobes.sheen = max(sheen, 0.0) * max(sheen_tint.rgb, 0.0);
  c.lobes.sheen_weight = dot(c.lobes.sheen, vec3(1.0 / 3.0));
  c.lobes.sheen_roughness = c.lobes.sheen_weight * clamp(sheen_roughness, 0.0, 1.0);
  c.lobes.thin_film = max(thin_film, 0.0);
  c.lobes.thin_film_ior = c.lobes.thin_film * max(thin_film_ior, 1e-5);
  c.lobes.subsurface = clamp(subsurface, 0.0, 1.0);
  c.lobes.subsurface_radius = c.lobes.subsurface * subsurface_path; /* (node_subsurface.glsl) */
  c.lobes.subsurface_walk = c.lobes.subsurface * subsurface_walk;
  /* the glass part (Cycles' Transmission component): each crossing tinted by sqrt(Base Color), the
   * base colour within [0, 1]; the IOR the Principled BSDF's, at least 1e-5 */
  c.lobes.transmission = clamp(transmission, 0.0, 1.0);
  c.lobes.transmission_ior = c.lobes.transmission * max(ior, 1e-5);
  c.lobes.transmission_tint = c.lobes.transmission * sqrt(clamp(base_color.rgb, 0.0, 1.0));
  c.lobes.transmission_fresnel = c.lobes.transmission;
  c.bsdfs.diffuse_weight = 1.0;
  c.bsdfs.sheen_layered = c.lobes.sheen_weight;
  /* the diffuse base's Diffuse Roughness (Blender 4.3 and later): Cycles 5.0's Principled BSDF sets up
   * the Diffuse BSDF's Oren-Nayar of its Base Color (svm_node_closure_bsdf) */
  c = closure_oren_nayar(c, max(base_color.rgb, 0.0), diffuse_roughness);
  c.emission = emission_color.rgb * emission_strength;
  float a = clamp(alpha, 0.0, 1.0);
  c = closure_scale(c, a);
  c.transparency = 1.0 - a;
  return c;
}

/* Glass BSDF (Cycles' svm_node_closure_bsdf, CLOSURE_BSDF_MICROFACET_GGX_GLASS_ID): a dielectric that
 * reflects and transmits by the Fresnel of its IOR (at least 1e-5), its Color tinting both, each
 * crossing of the surface; no diffuse part. */
Closure closure_glass(vec4 color, float roughness, float ior, vec3 n)
{
  float eta = max(ior, 1e-5);
  float r = (eta - 1.0) / (eta + 1.0);
  vec3 tint = max(color.rgb, 0.0);
  Closure c = closure_bsdf(tint, 0.0, roughness, min(r * r, 1.0), n);
  c.lobes.transmission = 1.0;
  c.lobes.transmission_ior = eta;
  c.lobes.transmission_tint = tint;
  c.lobes.transmission_fresnel = 1.0;
  c.lobes.reflection_tint = tint;
  return c;
}

/* Refraction BSDF (Cycles' CLOSURE_BSDF_MICROFACET_GGX_REFRACTION_ID: no Fresnel): all the light
 * transmitted (but where it reflects totally inside), tinted by its Color at each crossing; no
 * reflection, no diffuse part. */
Closure closure_refraction(vec4 color, float roughness, float ior, vec3 n)
{
  Closure c = closure_glass(color, roughness, ior, n);
  c.specular = 0.0;
  c.lobes.transmission_fresnel = 0.0;
  c.lobes.reflection_tint = vec3(0.0);
  return c;
}

/* Diffuse BSDF: no specular lobe (F0 0); its Roughness Cycles' Oren-Nayar (closure_oren_nayar). */
Closure closure_diffuse(vec4 color, float roughness, vec3 n)
{
  Closure c = closure_bsdf(color.rgb, 0.0, 1.0, 0.0, n);
  c.bsdfs.diffuse_weight = 1.0;
  return closure_oren_nayar(c, color.rgb, roughness);
}

/* Glossy BSDF, Multiscatter GGX (Cycles 5.0: bsdf_microfacet_setup_fresnel_constant): GGX of its
 * colour, compensated for multiple scattering with that colour as its Fresnel; a metal of that colour
 * where the program has no such lobe (SL_GLOSSY: principled.glsl). (The Metallic BSDF's Physical
 * Conductor: a metal of its Base Color.) */
Closure closure_glossy(vec4 color, float roughness, vec3 n)
{
  Closure c = closure_bsdf(max(color.rgb, 0.0), 1.0, roughness, 0.0, n);
  c.bsdfs.glossy.x = 1.0;
  return c;
}

/* Translucent BSDF (Cycles' bsdf_translucent: a Lambertian lobe on the far side of the normal):
 * a BSDF of no reflection, its colour the translucent lobe's (SL_TRANSLUCENT) */
Closure closure_translucent(vec4 color, vec3 n)
{
  Closure c = closure_bsdf(vec3(0.0), 0.0, 1.0, 0.0, n);
  c.lobes.translucent = max(color.rgb, 0.0);
  return c;
}

Closure closure_emission(vec4 color, float strength)
{
  Closure c = closure_none();
  c.emission = color.rgb * strength;
  return c;
}

Closure closure_transparent(vec4 color)
{
  Closure c = closure_none();
  c.transparency = dot(clamp(color.rgb, 0.0, 1.0), vec3(1.0 / 3.0));
  return c;
}

/* Holdout (Cycles' svm_node_closure_holdout, integrate_surface_holdout): no light, its weight left
 * transparent in the render's alpha whatever the film says (Render > Film > Transparent only makes
 * the world transparent too) */
Closure closure_holdout()
{
  Closure c = closure_none();
  c.holdout = 1.0;
  return c;
}
