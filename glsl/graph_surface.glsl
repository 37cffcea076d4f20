/* A material's compiled node graph in the mesh program (SL_GRAPH): its inputs filled from the
 * fragment, its Surface closure (glsl/node_closure.glsl) turned into what the models read. */

#ifdef SL_GRAPH
/* The Blinn-Phong exponent of a perceptual roughness: addon/scene/snapshot.py's
 * shininess_from_roughness (Walter et al. 2007, section 5.2: 2 / alpha^4 - 2 with alpha = r^2,
 * r floored at MIN_PERCEPTUAL_ROUGHNESS), within [1, 1e4]. */
float graph_shininess(float roughness)
{
  float a = max(roughness, MIN_PERCEPTUAL_ROUGHNESS);
  a *= a;
  return clamp(2.0 / (a * a) - 2.0, 1.0, 1e4);
}

/* A mesh's tangent attribute (object space, w the bitangent's sign) in world space, its sign as
 * the mesh has it (GraphInputs.tangent's) */
vec4 graph_tangent_to_world(vec4 t)
{
  vec3 w = mat3(objects.object[object_index].model) * t.xyz;
  float len2 = dot(w, w);
  return vec4(len2 > 1e-20 ? w * inversesqrt(len2) : vec3(0.0), t.w);
}

#if defined(SL_GRAPH_OBJECT) || defined(SL_GRAPH_GENERATED)
/* Generated coordinates of an object-space position p: Blender's texture space, (p - location) /
 * size / 2 + 1/2 (Cycles' mesh_texture_space). p is the fragment's own, or where a deformed mesh
 * holds its undeformed positions (an ORCO attribute, materials/surface.py's with_orco) the
 * undeformed one, as Cycles' attr_create_generated takes Blender's orco. */
vec3 graph_generated(vec3 p)
{
  return (p - graph_texspace.xyz) / graph_texspace_size.xyz * 0.5 + 0.5;
}
#endif

#ifdef SL_GRAPH_RAY_FOOTPRINT
/* The width of the scene camera's ray footprint at p, as Cycles carries it to a camera ray's hit
 * (sd->dP: camera_sample_perspective's spread dD = (|dD.dx| + |dD.dy|) / 2, the change of the unit
 * direction to the next pixel right and down, times the distance from the camera,
 * differential_transfer_compact; camera_sample_orthographic's: a pixel's size, the same
 * everywhere). A pixel of the image: a supersampled target's pixel is 1 / frame.viewport.w of one
 * (Cycles' differentials span a whole pixel, however many samples it takes in it). */
float graph_ray_footprint(vec3 p)
{
  mat4 projection = frame.view_proj * inverse(frame.view);
  /* a pixel's step on the plane one unit ahead of a perspective camera, anywhere for an orthographic one */
  vec2 step = 2.0 * frame.viewport.w / (frame.viewport.xy * vec2(projection[0][0], projection[1][1]));
  if (frame.camera_position.w < 0.5) {
    return 0.5 * (step.x + step.y);
  }
  vec3 c = (frame.view * vec4(p, 1.0)).xyz;
  vec3 d = c / -c.z; /* on the plane one unit ahead (the camera looks down -z) */
  vec3 unit = normalize(d);
  float dx = length(normalize(d + vec3(step.x, 0.0, 0.0)) - unit);
  float dy = length(normalize(d - vec3(0.0, step.y, 0.0)) - unit); /* raster rows run down */
  return length(c) * 0.5 * (dx + dy);
}
#endif

/* The graph's inputs at this fragment: n the interpolated normal facing the viewer, v towards
 * the viewer. The optional fields are filled where the graph reads them (SL_GRAPH_<FIELD>). */
GraphInputs graph_inputs(vec3 n, vec3 v, bool backfacing)
{
  GraphInputs g;
  g.uv = vec3(world_uv, 0.0);
  g.position = world_position;
  g.n = n;
  g.i = v;
  g.backfacing = backfacing;
  g.ng = n;
#ifdef SL_GRAPH_NG
  vec3 face = face_normal(world_position, n);
  g.ng = dot(face, v) < 0.0 ? -face : face;
#endif
  ObjectData object = objects.object[object_index];
  g.tangent = vec4(0.0);
#ifdef SL_GRAPH_TANGENT
  /* the bitangent's sign as the mesh has it (Cycles'): the vertex stage's carries the mirror's too */
  float t2 = dot(world_tangent.xyz, world_tangent.xyz);
  g.tangent = vec4(t2 > 1e-20 ? world_tangent.xyz * inversesqrt(t2) : vec3(0.0),
                   world_tangent.w * object.normal_matrix[3][3]);
#endif
#if defined(SL_GRAPH_OBJECT) || defined(SL_GRAPH_GENERATED)
  g.object = object_position;
  g.generated = graph_generated(object_position); /* a deformed mesh's: SL_GRAPH_ATTRIBUTE_READS' */
#endif
#if defined(SL_GRAPH_OBJECT_TO_WORLD) || defined(SL_GRAPH_WORLD_TO_OBJECT)
  g.object_to_world = object.model;
  g.world_to_object = inverse(object.model);
#endif
#if defined(SL_GRAPH_WORLD_TO_VIEW) || defined(SL_GRAPH_VIEW_TO_WORLD)
  g.world_to_view = frame.view;
  g.view_to_world = inverse(frame.view);
#endif
#ifdef SL_GRAPH_WINDOW
  /* the view's 0..1; the viewport's render region and supersampling keep it: the frame's size is
   * the target's */
  g.window = gl_FragCoord.xy / frame.viewport.xy;
#endif
#if defined(SL_GRAPH_OBJECT_COLOR) || defined(SL_GRAPH_OBJECT_INFO)
  g.object_color = graph_object_color;
  g.object_info = graph_object_info;
#endif
#ifdef SL_GRAPH_UNIFORM_ATTRIBUTES
  g.uniform_attributes[0] = graph_uniform_attribute0;
#  if SL_GRAPH_UNIFORM_ATTRIBUTE_COUNT > 1
  g.uniform_attributes[1] = graph_uniform_attribute1;
#  endif
#endif
#ifdef SL_GRAPH_CLIP_START
  g.clip_start = frame.viewport.z;
#endif
#ifdef SL_PASS_ATTRIBUTES
  SL_GRAPH_ATTRIBUTE_READS
#endif
#ifdef SL_GRAPH_TRIANGLE
  /* the fragment's triangle: gl_PrimitiveID, its index in the draw's range of the mesh, finds its
   * corners (object space) in graph_triangles, SL_GRAPH_TRIANGLE_ROW triangles a row */
  int t = gl_PrimitiveID;
  ivec2 at = ivec2(3 * (t % SL_GRAPH_TRIANGLE_ROW), t / SL_GRAPH_TRIANGLE_ROW);
  for (int k = 0; k < 3; k++) {
    g.triangle[k] = (object.model * vec4(texelFetch(graph_triangles, at + ivec2(k, 0), 0).xyz, 1.0)).xyz;
  }
#endif
#ifdef SL_GRAPH_RAY_FOOTPRINT
  g.ray_footprint = graph_ray_footprint(world_position);
#endif
#ifdef SL_GRAPH_SUBPIXELS
  g.subpixels = frame.viewport.w;
#endif
  return g;
}


/* The closures' lobes as the models read them (MaterialData's rows): their means over the BSDFs
 * (`inv`: 1 / their weight), the coat's and sheen's inputs over the closures that have the lobe. */
void apply_closure_lobes(inout MaterialData m, ClosureLobes l, float inv)
{
  m.specular_tint = vec4(l.specular_tint * inv, 0.0);
  /* no coat or sheen: their inputs do not matter (the lobe is off at weight 0) */
  float coat_inv = l.coat > 1e-8 ? 1.0 / l.coat : 0.0;
  m.coat = vec4(l.coat * inv, l.coat_roughness * coat_inv, l.coat_ior * coat_inv, 0.0);
  m.coat_tint = vec4(l.coat_tint * coat_inv, 0.0);
  m.coat_normal = vec4(l.coat_normal * coat_inv, 0.0);
  float sheen_inv = l.sheen_weight > 1e-8 ? 1.0 / l.sheen_weight : 0.0;
  m.sheen = vec4(l.sheen * inv, l.sheen_roughness * sheen_inv);
  /* the film's IOR its mean over the closures that have a film; its z, w as the material's */
  float film_inv = l.thin_film > 1e-8 ? 1.0 / l.thin_film : 0.0;
  m.thin_film = vec4(l.thin_film * inv, l.thin_film_ior * film_inv, m.thin_film.zw);
  m.anisotropy = vec4(l.tangent * inv, l.stretch * inv);
  m.translucent = vec4(l.translucent * inv, 0.0);
  float subsurface_inv = l.subsurface > 1e-8 ? 1.0 / l.subsurface : 0.0; /* none: its radius does not matter */
  m.subsurface = vec4(l.subsurface_radius * subsurface_inv, l.subsurface * inv);
  m.subsurface_walk = l.subsurface_walk * subsurface_inv;
  /* no glass: its inputs do not matter (the lobe is off at share 0) */
  float glass_inv = l.transmission > 1e-8 ? 1.0 / l.transmission : 0.0;
  m.transmission = vec4(l.transmission * inv, l.transmission_fresnel * glass_inv, l.transmission_ior * glass_inv,
                        0.0);
  m.transmission_tint = vec4(l.transmission_tint * glass_inv, 0.0);
  m.reflection_tint = vec4(l.reflection_tint * inv, 0.0);
}

/* The closure nodes beside the Principled BSDF as the models read them (MaterialData's rows): their
 * colours' means over the BSDFs (`inv`: 1 / their weight), their shapes' over the closures of each
 * kind; the sheen's layered share of its weight (ClosureLobes'), the Diffuse Roughness' mean over the
 * BSDFs with a diffuse base, the Glossy BSDFs' shares of the metal lobe and of the BSDFs, the Physical
 * Conductors' mean IOR and Extinction in the complex IOR's rows, their share of the metal lobe in w. */
void apply_closure_bsdfs(inout MaterialData m, ClosureBsdfs b, float sheen_weight, float metallic, float inv)
{
  /* none of a kind: its inputs do not matter (its colour is 0) */
  float diffuse_inv = b.diffuse_weight > 1e-8 ? 1.0 / b.diffuse_weight : 0.0;
  float velvet_inv = b.velvet_weight > 1e-8 ? 1.0 / b.velvet_weight : 0.0;
  float layered = sheen_weight > 1e-8 ? saturate(b.sheen_layered / sheen_weight) : 1.0;
  m.closure_bsdfs = vec4(layered, b.diffuse_roughness * diffuse_inv, b.velvet_sigma * velvet_inv,
                         b.unlayered * diffuse_inv);
  m.velvet = vec4(b.velvet * inv, 0.0);
  float toon_d_inv = b.toon_diffuse_shape.x > 1e-8 ? 1.0 / b.toon_diffuse_shape.x : 0.0;
  float toon_g_inv = b.toon_glossy_shape.x > 1e-8 ? 1.0 / b.toon_glossy_shape.x : 0.0;
  m.toon_diffuse = vec4(b.toon_diffuse * inv, b.toon_diffuse_shape.y * toon_d_inv);
  m.toon_glossy = vec4(b.toon_glossy * inv, b.toon_glossy_shape.y * toon_g_inv);
  m.toon_smooth = vec4(b.toon_diffuse_shape.z * toon_d_inv, b.toon_glossy_shape.z * toon_g_inv, 0.0, 0.0);
  m.diffuse_ms = vec4(b.diffuse_ms * inv, 0.0);
  float metal_inv = metallic > 1e-8 ? 1.0 / metallic : 0.0; /* no metal lobe: its shares do not matter */
  m.glossy = clamp(vec4(b.glossy.xy * metal_inv, b.glossy.zw * inv), 0.0, 1.0);
  if (b.conductor.w > 1e-8) { /* none: the material's own complex IOR rows, its share 0 (w) */
    m.ior_n = vec4(b.conductor.rgb / b.conductor.w, saturate(b.conductor.w * metal_inv));
    m.ior_k = vec4(b.conductor_k / b.conductor.w, 0.0);
  }
}

/* The Surface closure as the models read it: its BSDFs' mean inputs replace the material's values
 * (but those the Material panel sets, SL_KEEP_*), the empirical models' colours and exponent follow
 * them as addon/blender/extract.py's material_params derives them, n becomes the BSDFs' normal,
 * and `scale` is what the shaded radiance is multiplied by: the BSDFs' weight over the coverage
 * (the fragment is composited over what lies behind with the coverage as alpha, L = a L_s +
 * (1 - a) L_behind, so a L_s must be the BSDFs' radiance plus the emission). */
MaterialData apply_closure(MaterialData m, Closure c, inout vec3 n, out float scale)
{
  float coverage = clamp(1.0 - c.transparency, 0.0, 1.0);
  /* a fragment of no coverage is not drawn (the peeling discards it); 1e-6 keeps the division finite */
  float inv_coverage = 1.0 / max(coverage, 1e-6);
  scale = c.weight * inv_coverage;
  float inv = c.weight > 1e-8 ? 1.0 / c.weight : 0.0; /* no BSDF: its inputs do not matter (scale 0) */
#ifndef SL_KEEP_BASE_COLOR
  m.base_color.rgb = c.base_color * inv;
#  ifndef SL_TRANSLUCENT
  /* a program without the translucent lobe (another model or term set) draws a Translucent BSDF as a
   * diffuse of its colour (as unknown closures are) */
  m.base_color.rgb += c.lobes.translucent * inv;
#  endif
#endif
#ifndef SL_KEEP_METALNESS
  m.params.y = clamp(c.metallic * inv, 0.0, 1.0);
#endif
#ifndef SL_KEEP_ROUGHNESS
  m.params.x = clamp(c.roughness * inv, 0.0, 1.0);
#endif
#ifndef SL_KEEP_SHININESS
  m.params.z = graph_shininess(m.params.x);
#endif
#ifndef SL_KEEP_F0
  m.params.w = clamp(c.specular * inv, 0.0, 1.0);
#endif
  float metal = m.params.y;
  m.diffuse_color.rgb = m.base_color.rgb * (1.0 - metal);
#ifndef SL_KEEP_SPECULAR_COLOR
  m.specular_color.rgb = vec3((1.0 - metal) * (m.params.w > 0.0 ? 1.0 : 0.0)) + metal * m.base_color.rgb;
#endif
#ifndef SL_KEEP_AMBIENT_COLOR
  m.ambient_color.rgb = m.diffuse_color.rgb;
#endif
  m.emission = vec4(c.emission * inv_coverage, coverage);
  float len2 = dot(c.normal, c.normal);
  if (len2 > 1e-20) {
    n = c.normal * inversesqrt(len2);
  }
  apply_closure_lobes(m, c.lobes, inv);
  apply_closure_bsdfs(m, c.bsdfs, c.lobes.sheen_weight, c.metallic, inv);
  return m;
}
#endif
