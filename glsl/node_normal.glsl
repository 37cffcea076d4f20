/* The nodes that bend the shading normal: Normal Map and Bump, as Cycles evaluates them
 * (kernel/svm/tex_coord.h svm_node_normal_map, kernel/svm/displace.h svm_node_set_bump). A Bump's
 * Height subgraph is evaluated again at the fragment moved along Cycles' own position
 * differentials (graph_inputs_dx / _dy, which codegen calls), scaled by the Filter Width: what
 * varies over the surface is moved by the combination of its screen-space derivatives that moves
 * the position there (EEVEE's dF_branch moves it along the screen's axes instead; a curved Height
 * then differs from Cycles' by its curvature over the step). */

/* The camera ray's footprint at the fragment along one screen axis, as Cycles carries it to the
 * surface (differential_transfer_compact, kernel/util/differential.h: the ray's dP + t dD, its
 * spread dD the change of its unit direction to the next pixel's, kernel/camera/camera.h): dp, di
 * the position's and the view direction's screen derivatives along that axis, i towards the
 * viewer. Rays from one point (perspective): the distance t to it (from dp = t' d' - t d) times
 * their spread; parallel rays (orthographic, di = 0): the pixel's width across them. */
float graph_ray_footprint(vec3 dp, vec3 di, vec3 i)
{
  vec3 d = -i;
  vec3 d_next = -(i + di);
  vec3 c = cross(d, d_next);
  float c2 = dot(c, c);
  if (c2 > 0.0) {
    float t = -dot(cross(dp, d_next), c) / c2;
    return t * length(d_next - d);
  }
  return length(dp - dot(dp, i) * i);
}

/* Cycles' position differentials at a shading point (differential_from_compact, kernel/util/
 * differential.h): two directions across the true normal (make_orthonormals, util/math.h: the
 * first (1, 1, 1) x ng) scaled by the camera ray's compact footprint there (the mean of its two
 * axes', differential_make_compact), a whole pixel's: the screen derivatives span a sub-pixel of
 * a supersampled target (g.subpixels of them a pixel). */
void graph_position_differentials(GraphInputs g, out vec3 dx, out vec3 dy)
{
  vec3 ng = g.ng;
  vec3 a = (ng.x != ng.y || ng.x != ng.z) ? vec3(ng.z - ng.y, ng.x - ng.z, ng.y - ng.x)
                                          : vec3(ng.z - ng.y, ng.x + ng.z, -ng.y - ng.x);
  a = normalize(a);
  vec3 b = cross(ng, a);
  float width = 0.5 * g.subpixels * (graph_ray_footprint(dFdx(g.position), dFdx(g.i), g.i) +
                                     graph_ray_footprint(dFdy(g.position), dFdy(g.i), g.i));
  dx = width * a;
  dy = width * b;
}

/* The fragment moved by d (a step in the face's plane): the position by d, what varies across the
 * surface (texture coordinates, attributes) by its screen derivatives' combination s.x dFdx +
 * s.y dFdy whose position's is d; the normals, the view and the tangent stay (Cycles offsets only
 * position- and attribute-derived inputs). */
GraphInputs graph_inputs_moved(GraphInputs g, vec3 d)
{
  vec3 px = dFdx(g.position);
  vec3 py = dFdy(g.position);
  float det = dot(cross(px, py), g.ng);
  GraphInputs o = g;
  if (det == 0.0) {
    return o; /* guards: no surface here (zero derivatives): nothing moves, the Bump bends nothing */
  }
  vec2 s = vec2(dot(cross(d, py), g.ng), dot(cross(px, d), g.ng)) / det;
  o.uv += dFdx(g.uv) * s.x + dFdy(g.uv) * s.y;
  o.position += d;
  o.object += dFdx(g.object) * s.x + dFdy(g.object) * s.y;
  o.generated += dFdx(g.generated) * s.x + dFdy(g.generated) * s.y;
  o.window += dFdx(g.window) * s.x + dFdy(g.window) * s.y;
  for (int k = 0; k < GRAPH_ATTRIBUTES; k++) {
    o.attributes[k] += dFdx(g.attributes[k]) * s.x + dFdy(g.attributes[k]) * s.y;
  }
  return o;
}

/* The fragment moved along Cycles' first (second) position differential times filter_width
 * (svm_node_bump_P_dx / _dy, kernel/svm/attribute.h) */
GraphInputs graph_inputs_dx(GraphInputs g, float filter_width)
{
  vec3 dx, dy;
  graph_position_differentials(g, dx, dy);
  return graph_inputs_moved(g, dx * filter_width);
}

GraphInputs graph_inputs_dy(GraphInputs g, float filter_width)
{
  vec3 dx, dy;
  graph_position_differentials(g, dx, dy);
  return graph_inputs_moved(g, dy * filter_width);
}

/* Bump (svm_node_set_bump): the surface gradient of the height, from its values h here and hx,
 * hy at the fragment moved by filter_width x the position differentials (Mikkelsen's "Bump
 * Mapping Unparametrized Surfaces on the GPU"), bends n; Distance scales the height; Strength
 * blends with n. */
vec3 node_bump(float strength, float dist, float filter_width, float h, float hx, float hy, vec3 n,
               GraphInputs g)
{
  vec3 dpdx, dpdy;
  graph_position_differentials(g, dpdx, dpdy);
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
