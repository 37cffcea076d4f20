/* The nodes that bend the shading normal: Normal Map and Bump, as Cycles evaluates them
 * (kernel/svm/tex_coord.h svm_node_normal_map, kernel/svm/displace.h svm_node_set_bump) with
 * EEVEE's way of reaching a neighbouring fragment (gpu_shader_material_bump.glsl, the codegen's
 * dF_branch): the Height subgraph is evaluated again at the fragment moved by its screen-space
 * derivatives (graph_inputs_dx / _dy, which codegen calls), scaled by the Filter Width. */

/* The fragment moved along the screen's x (y) by filter_width pixels: what varies across the
 * surface (position, texture coordinates, attributes) moves by its derivative; the normals,
 * the view and the tangent stay (Cycles offsets only position- and attribute-derived inputs). */
GraphInputs graph_inputs_dx(GraphInputs g, float filter_width)
{
  GraphInputs o = g;
  o.uv += dFdx(g.uv) * filter_width;
  o.position += dFdx(g.position) * filter_width;
  o.object += dFdx(g.object) * filter_width;
  o.generated += dFdx(g.generated) * filter_width;
  o.window += dFdx(g.window) * filter_width;
  for (int k = 0; k < GRAPH_ATTRIBUTES; k++) {
    o.attributes[k] += dFdx(g.attributes[k]) * filter_width;
  }
  return o;
}

GraphInputs graph_inputs_dy(GraphInputs g, float filter_width)
{
  GraphInputs o = g;
  o.uv += dFdy(g.uv) * filter_width;
  o.position += dFdy(g.position) * filter_width;
  o.object += dFdy(g.object) * filter_width;
  o.generated += dFdy(g.generated) * filter_width;
  o.window += dFdy(g.window) * filter_width;
  for (int k = 0; k < GRAPH_ATTRIBUTES; k++) {
    o.attributes[k] += dFdy(g.attributes[k]) * filter_width;
  }
  return o;
}

/* Bump (svm_node_set_bump): the surface gradient of the height, from its values h here and hx,
 * hy at the fragment moved by filter_width x its position's derivatives (Mikkelsen's "Bump
 * Mapping Unparametrized Surfaces on the GPU"), bends n; Distance scales the height; Strength
 * blends with n. */
vec3 node_bump(float strength, float dist, float filter_width, float h, float hx, float hy, vec3 n,
               GraphInputs g)
{
  vec3 dpdx = dFdx(g.position);
  vec3 dpdy = dFdy(g.position);
  vec3 rx = cross(dpdy, n);
  vec3 ry = cross(n, dpdx);
  float det = dot(dpdx, rx);
  vec3 surfgrad = (hx - h) * rx + (hy - h) * ry;
  vec3 bent = filter_width * abs(det) * n - dist * sign(det) * surfgrad;
  float len = length(bent);
  if (len == 0.0) {
    return n; /* guards: no surface here (zero derivatives): Cycles keeps the input normal */
  }
  float s = max(strength, 0.0);
  return normalize(s * (bent / len) + (1.0 - s) * n);
}

/* Bump with Invert: the height read as a depth */
vec3 node_bump_inverted(float strength, float dist, float filter_width, float h, float hx, float hy, vec3 n,
                        GraphInputs g)
{
  return node_bump(strength, -dist, filter_width, h, hx, hy, n, g);
}

/* Normal Map's last step: Strength as a linear blend from the shading normal (object and world
 * spaces), and Cycles' fallback to the shading normal where the result is no direction */
vec3 graph_normal_map_finish(vec3 bent, float strength, GraphInputs g)
{
  vec3 n = bent;
  if (strength != 1.0) {
    vec3 d = g.n + (n - g.n) * max(strength, 0.0);
    float len = length(d);
    n = len > 0.0 ? d / len : d; /* guards: Cycles' safe_normalize keeps a zero vector */
  }
  if (all(equal(n, vec3(0.0))) || any(isnan(n)) || any(isinf(n))) {
    return g.n; /* guards: a colour of (0.5, 0.5, 0.5) bends to nothing */
  }
  return n;
}

vec3 graph_safe_normalize(vec3 v)
{
  float len = length(v);
  return len > 0.0 ? v / len : v; /* guards: Cycles' safe_normalize keeps a zero vector */
}

/* Normal Map, Tangent Space, with tangent t (world space, unit, w the bitangent's sign; the
 * active UV map's g.tangent or a named map's): the colour's tangent-space direction in the
 * object's space (Cycles works there, with the interpolated normal and tangent), Strength
 * scaling the bend in tangent space, then to world space; flipped on back faces. */
vec3 node_normal_map_tangent(float strength, vec4 color, vec4 t, GraphInputs g)
{
  if (all(equal(t.xyz, vec3(0.0)))) {
    return g.n; /* guards: no tangent (no UV map): Cycles keeps the shading normal */
  }
  vec3 c = 2.0 * (color.rgb - 0.5);
  float s = strength;
  c.xy *= s;
  c.z = mix(1.0, c.z, clamp(s, 0.0, 1.0));
  vec3 normal = graph_normal_to_object(g.backfacing ? -g.n : g.n, g); /* the unflipped normal */
  vec3 tangent = normalize(mat3(g.world_to_object) * t.xyz);
  vec3 bitangent = t.w * cross(normal, tangent);
  vec3 n = graph_safe_normalize(c.x * tangent + c.y * bitangent + c.z * normal);
  n = graph_safe_normalize(transpose(mat3(g.world_to_object)) * n);
  n = g.backfacing ? -n : n;
  if (all(equal(n, vec3(0.0))) || any(isnan(n))) {
    return g.n; /* guards: a colour that bends to nothing */
  }
  return n;
}

/* Normal Map, Object Space: the colour's direction (x, y, z from r, g, b) in the object's
 * space; Blender Object Space: y and z flipped (Cycles' "strange blender convention") */
vec3 node_normal_map_object(float strength, vec4 color, GraphInputs g)
{
  vec3 c = 2.0 * (color.rgb - 0.5);
  vec3 n = graph_safe_normalize(transpose(mat3(g.world_to_object)) * c);
  return graph_normal_map_finish(g.backfacing ? -n : n, strength, g);
}

vec3 node_normal_map_blender_object(float strength, vec4 color, GraphInputs g)
{
  return node_normal_map_object(strength, vec4(color.r, 1.0 - color.g, 1.0 - color.b, color.a), g);
}

/* Normal Map, World Space; Blender World Space: y and z flipped */
vec3 node_normal_map_world(float strength, vec4 color, GraphInputs g)
{
  vec3 n = graph_safe_normalize(2.0 * (color.rgb - 0.5));
  return graph_normal_map_finish(g.backfacing ? -n : n, strength, g);
}

vec3 node_normal_map_blender_world(float strength, vec4 color, GraphInputs g)
{
  return node_normal_map_world(strength, vec4(color.r, 1.0 - color.g, 1.0 - color.b, color.a), g);
}
