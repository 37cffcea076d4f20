/* One light loop for every model: the model file bound at compile time supplies shade_direct,
 * shade_ambient and shade_finish. */

/* Texel t of light i (glsl/uniforms.glsl): from the lights' uniform block where they fit (a
 * block's load costs less than a texel fetch on a software rasteriser), else their texture. */
#ifdef SL_LIGHT_BLOCK
#  define LIGHT_TEXEL(i, t) light_block.texels[(i) * LIGHT_TEXELS + (t)]
#else
#  define LIGHT_TEXEL(i, t) texelFetch(light_data, ivec2(t, i), 0)
#endif

/* Light i's data, one texel per vec4 of LightData (LIGHT_TEXEL). The position and
 * reach first (light culling tests them alone), then the texels the light's kind reads: a point
 * light has no direction, only an area light has axes, only lights with a size have a shape (on a
 * software rasteriser each read is a gather per pixel, even where every pixel reads one light:
 * ~20 % of a culled point light's cost from the block, more from the texture). */
LightData load_light_reach(int i)
{
  LightData light;
  light.position_kind = LIGHT_TEXEL(i, 0);
  light.influence = LIGHT_TEXEL(i, 6);
  return light;
}

LightData load_light_rest(LightData light, int i)
{
  light.intensity_blend = LIGHT_TEXEL(i, 2);
  light.factors = LIGHT_TEXEL(i, 3);
  /* and only the texels some light of the scene needs: a runtime test would not save the fetch
   * here (both sides of an `if` run), so the kinds and radii present decide at compile time */
  light.shape = vec4(0.0);
#if defined(SL_LIGHT_RADII) || defined(SL_HAS_AREA)
  light.shape = LIGHT_TEXEL(i, 4);
#endif
  int kind = int(light.position_kind.w);
  light.direction_cone = vec4(0.0, 0.0, -1.0, 1.0);
#if defined(SL_HAS_SPOT) || defined(SL_HAS_SUN) || defined(SL_HAS_AREA)
  if (kind != LIGHT_POINT) {
    light.direction_cone = LIGHT_TEXEL(i, 1);
  }
#endif
  light.area = vec4(1.0, 0.0, 0.0, 0.0);
#ifdef SL_HAS_AREA
  if (kind == LIGHT_AREA) {
    light.area = LIGHT_TEXEL(i, 5);
  }
#endif
  return light;
}

#ifdef SL_LIGHT_TILES
/* Light culling (addon/plan/light_tiles.py): light_tiles holds each screen tile's (first, count), row
 * by row (frame.counts.z tiles a row of frame.counts.y pixels), then from texel frame.counts.w on
 * the tiles' light indices; a tile lists every light whose reach covers it, in light order. */
vec4 tile_texel(int i)
{
  return texelFetch(light_tiles, ivec2(i % SL_LIGHT_LIST_WIDTH, i / SL_LIGHT_LIST_WIDTH), 0);
}

ivec2 tile_lights()
{
  ivec2 t = ivec2(gl_FragCoord.xy) / int(frame.counts.y);
  return ivec2(tile_texel(t.y * int(frame.counts.z) + t.x).xy);
}

int tile_light(int first, int k)
{
  return int(tile_texel(int(frame.counts.w) + first + k).x);
}
#endif

/* The index of the k-th light of `listed` (first, count): the screen tile's list with light
 * culling, else every light in order. */
int listed_light(ivec2 listed, int k)
{
#ifdef SL_LIGHT_TILES
  return tile_light(listed.x, k);
#else
  return k;
#endif
}

/* The index of the k-th light of `listed`, or `end` past the list. */
int listed_index(ivec2 listed, int k, int end)
{
  return k < listed.y ? listed_light(listed, k) : end;
}

#ifdef SL_GRAPH_BENT_NORMAL
/* Where the node graph bent the normal: the specular lobe's shading point, at Cycles' valid
 * specular normal (bent_normal.glsl's valid_specular_normal), which main sets; bent_split where
 * that normal differs from the surface's (the lobes are then shaded apart). */
Surface bent_specular;
bool bent_split;
#endif

/* A light's share of the radiance leaving s. shadowed: look its shadow up (where the light
 * has a shadow map; ng is the flat face's normal for it), a constant at each call, so a loop
 * over lights without shadows holds no lookup. */
vec3 light_share(Surface s, vec3 ng, LightData light, bool shadowed)
{
  vec4 factors = light.factors * vec4(lobes.xy, 1.0, 1.0);
  if (light.factors.z > 0.5) {
    /* a sun split off the world */
#ifdef SL_MODEL_PBR
    factors.y *= world_sun_specular(s.roughness);
#else
#  ifndef SL_AMBIENT_WORLD
    return vec3(0.0); /* the empirical models are lit by their ambient constant, not the world */
#  endif
#endif
  }
  vec3 l;
  vec3 E = light_irradiance(light, s.p, l);
  bool lit = dot(s.n, l) > 0.0;
#if defined(SL_TRANSLUCENT) || defined(SL_SUBSURFACE)
  /* the translucent lobe is lit from behind, the subsurface past the terminator */
  lit = true;
#endif
#ifdef SL_GRAPH_BENT_NORMAL
  /* a normal the node graph bent: Cycles' rules for light from behind the surface, the specular
   * lobe's at its own normal (bent_normal.glsl) */
  factors.x *= bump_terminator(s.smooth_n, s.n, l).x;
  factors.y *= bump_terminator(s.smooth_n, bent_specular.n, l).y;
  lit = lit || dot(bent_specular.n, l) > 0.0;
#endif
  float visibility = 1.0;
#ifdef SL_SHADOWS
  if (shadowed && lit && max(E.r, max(E.g, E.b)) > 0.0) {
    visibility = light_visibility(light, s.p, ng);
    E *= visibility;
  }
#endif
  vec3 c = vec3(0.0);
#ifdef REFRACTION_LEVELS
  if (s.transmission.exit) {
    /* through a closed glass object's far face, at the exit point (transmission.glsl) */
    vec3 l_exit;
    vec3 E_exit = light_irradiance(light, s.transmission.exit_p, l_exit);
#  ifdef SL_SHADOWS
    if (shadowed && max(E_exit.r, max(E_exit.g, E_exit.b)) > 0.0) {
      E_exit *= light_visibility(light, transmission_exit_lookup(s), -s.transmission.exit_n);
    }
#  endif
    c = transmission_exit_light(s, light, l_exit, E_exit, factors, REFRACTION_EXIT_ALPHA);
#  if defined(SL_COAT) || defined(SL_SHEEN)
    c *= s.below; /* under the upper layers, as the rest of the glass */
#  endif
  }
#endif
#ifdef SL_GRAPH_BENT_NORMAL
  if (bent_split) {
    return c + shade_light(s, light, l, E, visibility, factors * vec4(1.0, 0.0, 1.0, 1.0)) +
           shade_light(bent_specular, light, l, E, visibility, factors * vec4(0.0, 1.0, 1.0, 1.0));
  }
#endif
  return c + shade_light(s, light, l, E, visibility, factors);
}

/* Shade the fragment's lights from its k-th listed one up to light index `end` into c (k moves
 * on). programs.light_order lists the lights by group, a kind with or without a shadow map, and a
 * program loops over each group its scene has: with `kind` and `shadowed` constants at each call
 * the loop holds that kind's code alone, and the shadow lookup only where shadowed (both sides of
 * an `if` would run: glsl/README.md). kind -1: each light's own (one loop over every light).
 * The loop tests at its end: one testing at its top ran its body once more, masked, on the CPU
 * rasteriser (glsl/README.md) -- a light's whole shading per group (material_grid's deferred
 * shading 26 -> 20 ms). */
void shade_group(inout vec3 c, Surface s, vec3 ng, ivec2 listed, inout int k, int end, int kind,
                 bool shadowed)
{
  int index = listed_index(listed, k, end);
  if (index >= end) {
    return;
  }
  do {
    /* k and the next index move on first, so that a `continue` reaches the test with them */
    int current = index;
    k++;
    index = listed_index(listed, k, end);
    LightData light = load_light_reach(current);
    if (kind >= 0) {
      light.position_kind.w = float(kind);
    }
#ifdef SL_LIGHT_TILES
    /* a tile lists every light whose reach meets some of its pixels: at the others the light's
     * window is exactly 0 (light_window), known before the rest of its texels are read */
    if (light_window(light, s.p) <= 0.0) {
      continue;
    }
#endif
    c += light_share(s, ng, load_light_rest(light, current), shadowed);
  } while (index < end && k < SL_MAX_LIGHTS);
}

#ifdef SL_LIGHT_SEQUENCE
/* Shade light `index` (of kind `kind`; shadowed: as light_share's) into c: the calls of
 * SL_LIGHT_SEQUENCE (addon/plan/programs.py's sequence_source), one per light of a scene of a few, each
 * with constants. A loop's index differs per pixel for all the CPU rasteriser's compiler knows,
 * so each of the light's texels is a gather, a load per pixel; a constant's is one load for every
 * pixel (the shading passes 0.96-0.98x: addon/plan/programs.py's UNROLLED_LIGHTS). */
void shade_light(inout vec3 c, Surface s, vec3 ng, int index, int kind, bool shadowed)
{
  LightData light = load_light_reach(index);
  light.position_kind.w = float(kind);
  c += light_share(s, ng, load_light_rest(light, index), shadowed);
}
#endif

#ifdef SL_DEFERRED
/* The material of G-buffer row `row` (addon/frame/gpu_scene.py's material table: MaterialData's vec4s in
 * order, one row per material). */
MaterialData load_material(int row)
{
  MaterialData m;
  m.base_color = texelFetch(material_table, ivec2(0, row), 0);
  m.diffuse_color = texelFetch(material_table, ivec2(1, row), 0);
  m.specular_color = texelFetch(material_table, ivec2(2, row), 0);
  m.ambient_color = texelFetch(material_table, ivec2(3, row), 0);
  m.params = texelFetch(material_table, ivec2(4, row), 0);
  m.fresnel = texelFetch(material_table, ivec2(5, row), 0);
  m.ior_n = texelFetch(material_table, ivec2(6, row), 0);
  m.ior_k = texelFetch(material_table, ivec2(7, row), 0);
  m.emission = texelFetch(material_table, ivec2(8, row), 0);
  /* the lobes' rows only where the program draws them (a fetch per row and pixel) */
#ifdef SL_SPECULAR_TINT
  m.specular_tint = texelFetch(material_table, ivec2(9, row), 0);
#endif
#ifdef SL_COAT
  m.coat = texelFetch(material_table, ivec2(10, row), 0);
  m.coat_tint = texelFetch(material_table, ivec2(11, row), 0);
  m.coat_normal = vec4(0.0); /* the surface's (no node graph is shaded deferred) */
#endif
#ifdef SL_SHEEN
  m.sheen = texelFetch(material_table, ivec2(12, row), 0);
#endif
#ifdef SL_THIN_FILM
  m.thin_film = texelFetch(material_table, ivec2(14, row), 0);
#endif
#ifdef SL_ANISOTROPY
  m.anisotropy = vec4(0.0, 0.0, 0.0, 1.0); /* isotropic: an anisotropic lobe compiles a graph */
#endif
  /* (no program with the translucent or the subsurface lobe is shaded deferred: Features) */
  /* the closure nodes' rows: a node graph's alone, and none is shaded deferred (its sheen layered);
   * but the Principled BSDF's Diffuse Roughness and its multiple scattering (programs.pack_material) */
#ifdef SL_DIFFUSE_ROUGHNESS
  m.closure_bsdfs = texelFetch(material_table, ivec2(21, row), 0);
  m.diffuse_ms = texelFetch(material_table, ivec2(26, row), 0);
#else
  m.closure_bsdfs = vec4(1.0, 0.0, 0.0, 0.0);
#endif
  return m;
}
#endif

void main()
{
#ifdef SL_DEFERRED
  /* Deferred: the surface this pixel sees, as the G-buffer pass left it (glsl/gbuffer.frag.glsl),
   * shaded here where this program's group drew it: each pixel once, in whole quads (small
   * triangles shaded forward cost the rasteriser's partly covered blocks whole) */
  ivec2 texel = ivec2(gl_FragCoord.xy);
  vec4 g_normal = texelFetch(gbuffer_normal, texel, 0);
  if (int(g_normal.w) != deferred_group) {
    discard; /* another group's surface, or none */
  }
  vec4 g_position = texelFetch(gbuffer_position, texel, 0);
  vec3 p = g_position.xyz;
  vec3 n = g_normal.xyz; /* facing the viewer */
#  ifdef SL_SHADOWS
  vec3 ng = texelFetch(gbuffer_face, texel, 0).xyz;
#  else
  vec3 ng = n; /* no shadow lookups */
#  endif
  MaterialData m = load_material(int(g_position.w));
  Surface s = make_surface(p, n, view_direction(p), m);
#else
  /* screen derivatives and textures (the node graph's) first: they need every fragment of the
   * quad alive */
  vec3 n = shading_normal(world_position);
#ifdef SL_SUBSURFACE
  float curvature = subsurface_curvature(n, world_position);
#endif
#ifdef SL_SHADOWS
  /* the flat face's normal, for shadow lookups (the receiver's plane) */
  vec3 ng = face_normal(world_position, n);
#else
  vec3 ng = n; /* no shadow lookups */
#endif
  MaterialData m = material;
  bool outward = facing_outward();
#ifdef REFRACTION_LEVELS
  bool entering = outward; /* the viewer outside the surface (transmission.glsl) */
#endif
  vec3 v = view_direction(world_position);
#ifdef SL_GRAPH
  /* the material's node graph: its closures' inputs at this fragment */
  n = outward ? n : -n;
  vec3 smooth_n = n;
  Closure closure;
  material_graph(graph_inputs(n, v, !outward), closure);
  float closure_scale;
  m = apply_closure(m, closure, n, closure_scale);
  outward = true; /* n faces the viewer already */
#  ifdef SL_GRAPH_BENT_NORMAL
  vec3 true_n = face_normal(world_position, smooth_n);
  vec3 specular_n = valid_specular_normal(dot(true_n, v) < 0.0 ? -true_n : true_n, v, n);
#  endif
#else
  const float closure_scale = 1.0;
#endif
#ifdef SL_PEEL
  /* Depth peeling (Everitt 2001): each pass keeps, per pixel, the nearest partly transparent
   * fragment behind the layer peeled before (peel_depth) and not behind the opaque surface
   * (opaque_depth); fully transparent fragments (cut-outs) take no layer. The renderer
   * composites the layers front to back. */
  ivec2 texel = ivec2(gl_FragCoord.xy);
  if (m.emission.w <= 0.0 || gl_FragCoord.z <= texelFetch(peel_depth, texel, 0).r ||
      gl_FragCoord.z > texelFetch(opaque_depth, texel, 0).r)
  {
    discard;
  }
#endif
  Surface s = make_surface(world_position, outward ? n : -n, v, m);
#  ifdef SL_SUBSURFACE
  s.curvature = curvature;
#  endif
#  ifdef SL_GRAPH_BENT_NORMAL
  s.smooth_n = smooth_n;
  bent_specular = make_surface(world_position, specular_n, v, m);
  bent_specular.smooth_n = smooth_n;
  bent_split = specular_n != n;
#    ifdef SL_LAYERS
  /* the diffuse base lies under the specular layer at that layer's normal (Cycles takes the
   * dielectric layer's albedo, that the diffuse is weighted by, at its valid normal) */
  s.layers = bent_specular.layers;
#    endif
#  endif
#endif
#ifdef REFRACTION_LEVELS
  /* the view ray's way through the glass, which the lights shine along too (transmission.glsl) */
  transmission_trace(s, entering);
#  ifdef SL_GRAPH_BENT_NORMAL
  bent_specular.transmission = s.transmission;
#  endif
#endif
  /* ambient: neither a diffuse nor a specular lobe (weight z, off in lobe passes) */
  vec3 c = shade_ambient(s, frame.ambient.rgb) * lobes.z;
  /* the world is a light: its diffuse and specular parts go to the lobes' passes */
#ifdef SL_GRAPH_BENT_NORMAL
  /* Cycles rejects the world's light from below the smooth surface as any light's (its bump map
   * correction): of the bent normal's cosine-weighted hemisphere, a uniform world's light comes
   * from the share above the smooth surface, (1 + cos) / 2 of the angle between the two normals
   * (a tilted plane's sky view factor) */
  vec2 world_lobes = lobes.xy * vec2(0.5 + 0.5 * dot(s.n, smooth_n), 1.0);
  if (bent_split) {
    c += shade_environment(s, world_lobes * vec2(1.0, 0.0)) +
         shade_environment(bent_specular, world_lobes * vec2(0.0, 1.0));
  }
  else {
    c += shade_environment(s, world_lobes);
  }
#else
  c += shade_environment(s, lobes.xy);
#endif
#ifdef SL_LIGHT_SEQUENCE
  SL_LIGHT_SEQUENCE
#else
#  ifdef SL_LIGHT_TILES
  ivec2 listed = tile_lights();
#  else
  ivec2 listed = ivec2(0, int(frame.counts.x));
#  endif
  int k = 0;
#endif
#ifdef SL_ONE_LIGHT_LOOP
#  ifdef SL_SHADOWS
  shade_group(c, s, ng, listed, k, SL_MAX_LIGHTS, -1, true);
#  else
  shade_group(c, s, ng, listed, k, SL_MAX_LIGHTS, -1, false);
#  endif
#endif
#ifdef SL_LIGHTS_POINT_SHADOWED
  shade_group(c, s, ng, listed, k, int(frame.group_ends[0].x), LIGHT_POINT, true);
#endif
#ifdef SL_LIGHTS_SPOT_SHADOWED
  shade_group(c, s, ng, listed, k, int(frame.group_ends[0].y), LIGHT_SPOT, true);
#endif
#ifdef SL_LIGHTS_SUN_SHADOWED
  shade_group(c, s, ng, listed, k, int(frame.group_ends[0].z), LIGHT_SUN, true);
#endif
#ifdef SL_LIGHTS_AREA_SHADOWED
  shade_group(c, s, ng, listed, k, int(frame.group_ends[0].w), LIGHT_AREA, true);
#endif
#ifdef SL_LIGHTS_POINT
  shade_group(c, s, ng, listed, k, int(frame.group_ends[1].x), LIGHT_POINT, false);
#endif
#ifdef SL_LIGHTS_SPOT
  shade_group(c, s, ng, listed, k, int(frame.group_ends[1].y), LIGHT_SPOT, false);
#endif
#ifdef SL_LIGHTS_SUN
  shade_group(c, s, ng, listed, k, int(frame.group_ends[1].z), LIGHT_SUN, false);
#endif
#ifdef SL_LIGHTS_AREA
  shade_group(c, s, ng, listed, k, int(frame.group_ends[1].w), LIGHT_AREA, false);
#endif
#ifdef REFRACTION_LEVELS
  /* what lies behind, through the glass (passes.RefractionPass), under the upper layers */
#  if defined(SL_COAT) || defined(SL_SHEEN)
  c += transmission_behind(s, entering) * s.below * lobes.y;
#  else
  c += transmission_behind(s, entering) * lobes.y;
#  endif
#endif
  /* a node graph's BSDFs' weight over the coverage (1 without a graph), then the emission (neither
   * lobe: weight z) */
#ifndef SL_DEFERRED
  c *= closure_scale;
#endif
#if defined(SL_COAT) || defined(SL_SHEEN)
  c += m.emission.rgb * s.below * lobes.z; /* under the sheen and the coat, as Cycles' */
#else
  c += m.emission.rgb * lobes.z;
#endif
  /* alpha: coverage, blended over what is behind (L = a L_surface + (1 - a) L_behind, as Cycles'
   * transparency); the renderer peels partly transparent surfaces and composites them in depth order */
  float alpha = m.emission.w;
#ifdef SL_GRAPH
#  ifndef SL_PEEL
  /* a Holdout's share of an opaque surface is left transparent (Cycles' holdout: colour and alpha
   * reduced by its weight, what is behind hidden); a partly transparent (peeled) one below */
  alpha = clamp(alpha - closure.holdout, 0.0, 1.0);
#  endif
#endif
#ifdef REFRACTION_LEVELS
  if (alpha < 1.0) {
    /* a partly transparent glass (Alpha under 1, or a node graph's coverage): Cycles mixes in a
     * Transparent BSDF by 1 - Alpha, through which what lies behind shows unrefracted -- the
     * refraction pass's copy of it at this pixel (its alpha the depth: a surface covers, the world
     * leaves the film's alpha) */
    vec4 behind = texelFetch(refraction_behind, ivec2(gl_FragCoord.xy), 0);
    c = alpha * c + (1.0 - alpha) * behind.rgb;
    alpha += (1.0 - alpha) * (behind.a < 1.0 ? 1.0 : refraction.world.x);
  }
#endif
  frag_color = vec4(write_target(lobes.w > 0.5 ? shade_finish(c) : c), alpha);
#ifdef SL_PEEL
  /* a peeled layer keeps its coverage (what is behind stays hidden) and gives its Holdout share
   * apart, for the composite to take out of the render's alpha (glsl/under.frag.glsl); the share
   * within the coverage (a Holdout's weight is part of it: guards weights summing over 1) */
#  ifdef SL_GRAPH
  frag_holdout = vec4(0.0, 0.0, 0.0, clamp(closure.holdout, 0.0, alpha));
#  else
  frag_holdout = vec4(0.0);
#  endif
#endif
}
