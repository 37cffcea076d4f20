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

#ifdef SL_GRAPH_RAY_FOOTPRINT
/* The width of the scene camera's ray footprint at p, as Cycles carries it to a camera ray's hit
 * (sd->dP: camera_sample_perspective's spread dD = (|dD.dx| + |dD.dy|) / 2, the change of the unit
 * direction to the next pixel right and down, times the distance from the camera,
 * differential_transfer_compact; camera_sample_orthographic's: a pixel's size, the same
 * everywhere). A pixel of the target drawn (a supersampled render's sub-pixel). */
float graph_ray_footprint(vec3 p)
{
  mat4 projection = frame.view_proj * inverse(frame.view);
  /* a pixel's step on the plane one unit ahead of a perspective camera, anywhere for an orthographic one */
  vec2 step = 2.0 / (frame.viewport.xy * vec2(projection[0][0], projection[1][1]));
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
  /* Blender's texture space: Generated = (object position - location) / size / 2 + 1/2 */
  g.generated = (object_position - graph_texspace.xyz) / graph_texspace_size.xyz * 0.5 + 0.5;
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
  return g;
}


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
  return m;
}
#endif
