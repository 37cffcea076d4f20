/* What a compiled node graph (addon/materials/codegen.py) reads of the fragment, filled by the
 * program that calls it (glsl/mesh.frag.glsl's graph_inputs; the tests' harness from Cycles' own
 * AOVs of the same fragment). World space unless said. */

/* PRECISE: GLSL's `precise` (4.00), a variable's operations rounded as written, none reordered
 * or fused (the procedural textures' arithmetic, as Cycles rounds it). Blender's Metal shading
 * language has no such qualifier: there the compiler rounds as it will (ulps from Cycles'). */
#ifdef GPU_METAL
#  define PRECISE
#else
#  define PRECISE precise
#endif

#ifndef GRAPH_ATTRIBUTES
#  define GRAPH_ATTRIBUTES 1
#endif

struct GraphInputs {
  vec3 uv;              /* the active UV map's (u, v, 0), as Blender's UV outputs */
  vec3 position;        /* the fragment's position */
  vec3 n;               /* unit shading normal (Cycles' sd->N: facing the viewer) */
  vec3 ng;              /* unit true normal, the flat face's (Cycles' sd->Ng, facing the viewer) */
  vec3 i;               /* unit direction towards the viewer (Cycles' sd->wi) */
  bool backfacing;      /* the fragment is a back face */
  vec4 tangent;         /* xyz: unit tangent of the active UV map (0: none); w: the bitangent's sign
                         * as the mesh has it (object space: a mirrored object's is not flipped) */
  vec3 object;          /* the position in object space */
  vec3 generated;       /* Generated coordinates: the object-space position in the object's
                         * original bounds, 0..1 (Blender's texture space) */
  mat4 object_to_world; /* the object's matrix */
  mat4 world_to_object;
  mat4 world_to_view;   /* the camera's view matrix (world -> camera space, looking down -Z) */
  mat4 view_to_world;
  vec2 window;          /* the fragment's place in the view, 0..1 (Texture Coordinate's Window) */
  vec4 object_color;    /* Object Info's Color (rgb) and Alpha (a) */
  vec4 object_info;     /* Object Info's x: Object Index (pass index), y: Material Index
                         * (the material's pass index), z: Random */
  /* the attributes the graph reads (codegen's Compiled.attributes: named UV maps, colour
   * attributes, generic attributes), in its order; vec4, a UV map's (u, v, 0, 1) */
  vec4 attributes[GRAPH_ATTRIBUTES];
  /* the object's, its instancer's or the view layer's attributes the graph reads (codegen's
   * Compiled.uniform_attributes: an Attribute node of type Object, Instancer or View Layer), the
   * same over the whole object: RGBA, a float as (x, x, x, 1) */
  vec4 uniform_attributes[2];
  float clip_start;     /* the camera's clip start (Light Path > Ray Length: a camera ray starts
                         * on the near clip plane) */
  vec3 triangle[3];     /* the fragment's triangle's corners, in the mesh's (Cycles') order */
  float ray_footprint;  /* how wide the camera ray's footprint is at the fragment (Cycles' sd->dP:
                         * the distance times the ray's spread per pixel; orthographic: a pixel) */
  float subpixels;      /* the target's pixels per image pixel along an axis: n where Anti-Aliasing
                         * draws n x n sub-pixels, else 1 (screen derivatives span 1 / n pixel) */
};

/* Cycles' fresnel_dielectric_cos (kernel/closure/bsdf_util.h): 1 where no light refracts */
float node_fresnel_dielectric(float cosi, float eta)
{
  float c = abs(cosi);
  float g = eta * eta - 1.0 + c * c;
  if (g > 0.0) {
    g = sqrt(g);
    float a = (g - c) / (g + c);
    float b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * a * a * (1.0 + b * b);
  }
  return 1.0;
}

/* The Fresnel node: the dielectric's reflectance at the view, the ratio inverted on back faces */
float node_fresnel(float ior, vec3 n, GraphInputs g)
{
  float eta = max(ior, 1e-5);
  return node_fresnel_dielectric(dot(g.i, n), g.backfacing ? 1.0 / eta : eta);
}

/* The Layer Weight node's Fresnel output: Blend as 1 - 1/eta */
float node_layer_weight_fresnel(float blend, vec3 n, GraphInputs g)
{
  float eta = max(1.0 - blend, 1e-5);
  return node_fresnel_dielectric(dot(g.i, n), g.backfacing ? eta : 1.0 / eta);
}

/* The Layer Weight node's Facing output: 1 - |i.n|^b, Blend 0.5 linear */
float node_layer_weight_facing(float blend, vec3 n, GraphInputs g)
{
  float f = abs(dot(g.i, n));
  if (blend != 0.5) {
    float b = clamp(blend, 0.0, 1.0 - 1e-5);
    f = pow(f, b < 0.5 ? 2.0 * b : 0.5 / (1.0 - b));
  }
  return 1.0 - f;
}

/* --- the input nodes (Texture Coordinate, Geometry, Tangent, Object Info, Camera Data, Light Path,
 * Vector Transform, attributes), each as Cycles' SVM evaluates it for a camera ray's hit
 * (kernel/svm/tex_coord.h, geometry.h, camera.h, light_path.h, vector_transform.h, attribute.h) */

/* Cycles' camera space looks down +Z (kernel_data.cam.worldtocamera), Blender's view down -Z */
mat4 graph_world_to_camera(GraphInputs g)
{
  return mat4(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0) *
         g.world_to_view;
}

/* Cycles' object_inverse_normal_transform: a world normal in object space (M^T n), unit */
vec3 graph_normal_to_object(vec3 n, GraphInputs g)
{
  return normalize(transpose(mat3(g.object_to_world)) * n);
}

/* Cycles' object_normal_transform: an object-space normal in world space (M^-T n), unit */
vec3 graph_normal_to_world(vec3 n, GraphInputs g)
{
  return normalize(transpose(mat3(g.world_to_object)) * n);
}

/* Texture Coordinate > Normal: the shading normal in object space (NODE_TEXCO_NORMAL) */
vec3 node_texcoord_normal(GraphInputs g) { return graph_normal_to_object(g.n, g); }

/* Texture Coordinate > Object with its Object set: the position in that object's space (its
 * world-to-object matrix m, read when the graph is compiled) */
vec3 node_texcoord_object_from(mat4 m, GraphInputs g) { return (m * vec4(g.position, 1.0)).xyz; }

/* Texture Coordinate > Camera: the position in camera space, +Z ahead (svm_texco_camera) */
vec3 node_texcoord_camera(GraphInputs g) { return (graph_world_to_camera(g) * vec4(g.position, 1.0)).xyz; }

/* Texture Coordinate > Window: the position in the view, 0..1, z 0 (camera_world_to_ndc) */
vec3 node_texcoord_window(GraphInputs g) { return vec3(g.window, 0.0); }

/* Texture Coordinate > Reflection: the view direction mirrored about the normal, world space */
vec3 node_texcoord_reflection(GraphInputs g) { return 2.0 * dot(g.n, g.i) * g.n - g.i; }

/* The Tangent node's and Geometry > Tangent's last step (svm_node_tangent, primitive_tangent): an
 * object-space direction through the normal transform, made perpendicular to the shading normal */
vec3 graph_tangent_finish(vec3 t, GraphInputs g)
{
  vec3 w = transpose(mat3(g.world_to_object)) * t;
  return cross(g.n, normalize(cross(w, g.n)));
}

/* Tangent node, Radial about X, Y or Z of the Generated coordinates (Geometry > Tangent: Z) */
vec3 node_tangent_radial_x(GraphInputs g)
{
  return graph_tangent_finish(vec3(0.0, -(g.generated.z - 0.5), g.generated.y - 0.5), g);
}
vec3 node_tangent_radial_y(GraphInputs g)
{
  return graph_tangent_finish(vec3(-(g.generated.z - 0.5), 0.0, g.generated.x - 0.5), g);
}
vec3 node_tangent_radial_z(GraphInputs g)
{
  return graph_tangent_finish(vec3(-(g.generated.y - 0.5), g.generated.x - 0.5, 0.0), g);
}

/* Tangent node, UV Map: the map's tangent t (world space, unit; xyz 0 where the mesh has none,
 * which Cycles outputs as 0) taken back to object space, as Cycles holds it, then finished */
vec3 node_tangent_uv(vec4 t, GraphInputs g)
{
  if (all(equal(t.xyz, vec3(0.0)))) {
    return vec3(0.0); /* guards: no tangent (Cycles' attribute not found) */
  }
  return graph_tangent_finish(mat3(g.world_to_object) * t.xyz, g);
}

/* Camera Data (svm_node_camera): the position in camera space (+Z ahead), normalised; its depth
 * along the view axis; its distance from the camera */
vec3 node_camera_view_vector(GraphInputs g) { return normalize(node_texcoord_camera(g)); }
float node_camera_view_z_depth(GraphInputs g) { return node_texcoord_camera(g).z; }
float node_camera_view_distance(GraphInputs g) { return length(node_texcoord_camera(g)); }

/* Light Path > Ray Length for a camera ray (sd->ray_length): how far the camera ray travelled to
 * the fragment, along -i; Cycles starts it on the near clip plane (camera_sample_perspective,
 * _orthographic), so it is the depth past the clip start over the cosine of the ray to the axis */
float node_light_path_ray_length(GraphInputs g)
{
  vec3 ahead = -g.view_to_world[2].xyz; /* the camera's view axis in world space */
  float depth = dot(g.position - g.view_to_world[3].xyz, ahead);
  return (depth - g.clip_start) / max(dot(-g.i, ahead), 1e-8); /* guards: a ray across the axis */
}

/* Vector Transform (svm_node_vector_transform): m maps the source space to the target space
 * (graph_space_*); a point moves, a vector turns, a normal goes through the inverse transpose
 * (Cycles' transform_direction_transposed of the inverse) and is normalised */
vec3 vector_transform_point(vec3 v, mat4 m) { return (m * vec4(v, 1.0)).xyz; }
vec3 vector_transform_vector(vec3 v, mat4 m) { return mat3(m) * v; }
vec3 vector_transform_normal(vec3 v, mat4 m) { return normalize(transpose(inverse(mat3(m))) * v); }

mat4 graph_space_world_to_object(GraphInputs g) { return g.world_to_object; }
mat4 graph_space_world_to_camera(GraphInputs g) { return graph_world_to_camera(g); }
mat4 graph_space_object_to_world(GraphInputs g) { return g.object_to_world; }
mat4 graph_space_object_to_camera(GraphInputs g) { return graph_world_to_camera(g) * g.object_to_world; }
mat4 graph_space_camera_to_world(GraphInputs g) { return inverse(graph_world_to_camera(g)); }
mat4 graph_space_camera_to_object(GraphInputs g) { return g.world_to_object * inverse(graph_world_to_camera(g)); }
mat4 graph_space_identity(GraphInputs g) { return mat4(1.0); }

/* Attribute > Fac (svm_node_attr's NODE_ATTR_OUTPUT_FLOAT): a float's value, a vector's or a
 * colour's average */
float node_attribute_fac(vec4 a) { return (a.x + a.y + a.z) / 3.0; }

/* Geometry > Parametric (svm_node_geometry's NODE_GEOM_uv): Cycles' hit (u, v) on the triangle,
 * P = (1 - u - v) p0 + u p1 + v p2, given as (1 - u - v, u, 0); the rasteriser's fragment taken
 * back to (u, v) on its triangle by least squares (exact on the triangle's plane) */
vec3 node_geometry_parametric(GraphInputs g)
{
  vec3 e1 = g.triangle[1] - g.triangle[0];
  vec3 e2 = g.triangle[2] - g.triangle[0];
  vec3 d = g.position - g.triangle[0];
  float a = dot(e1, e1), b = dot(e1, e2), c = dot(e2, e2);
  float det = a * c - b * b;
  if (det <= 0.0) {
    return vec3(0.0); /* guards: a triangle of no area (no fragment should come from it) */
  }
  float u = (c * dot(d, e1) - b * dot(d, e2)) / det;
  float v = (a * dot(d, e2) - b * dot(d, e1)) / det;
  return vec3(1.0 - u - v, u, 0.0);
}

/* Wireframe (Cycles' wireframe, kernel/svm/wireframe.h, from Open Shading Language): 1 where the
 * fragment is within width / 2 of one of its triangle's edges (the neighbour face draws the other
 * half), the squared distance to the edge's line |edge x (p - corner)|^2 / |edge|^2 compared */
float wireframe_within(float half_width, GraphInputs g)
{
  float w2 = half_width * half_width;
  for (int i = 0; i < 3; i++) {
    vec3 edge = g.triangle[i] - g.triangle[i == 0 ? 2 : i - 1];
    vec3 crs = cross(edge, g.position - g.triangle[i]);
    if (dot(crs, crs) < dot(edge, edge) * w2) {
      return 1.0;
    }
  }
  return 0.0;
}

/* Wireframe, Size in world units */
float node_wireframe(float size, GraphInputs g) { return wireframe_within(0.5 * size, g); }

/* Wireframe with Use Pixel Size: Size in the pixel's width at the fragment, as Cycles measures it
 * (svm_node_wireframe): its ray footprint sd->dP laid along two orthonormal directions of the face
 * (differential_from_compact: make_orthonormals of the true normal), each projected onto the plane
 * facing the incoming direction, their lengths averaged */
float node_wireframe_pixel(float size, GraphInputs g)
{
  vec3 ng = normalize(cross(g.triangle[1] - g.triangle[0], g.triangle[2] - g.triangle[0]));
  /* make_orthonormals (util/math_float3.h): (1, 1, 1) x N, or (-1, 1, 1) x N along (1, 1, 1) */
  vec3 a = (ng.x != ng.y || ng.x != ng.z) ? vec3(ng.z - ng.y, ng.x - ng.z, ng.y - ng.x) :
                                            vec3(ng.z - ng.y, ng.x + ng.z, -ng.y - ng.x);
  a = normalize(a);
  vec3 b = cross(ng, a);
  float wx = g.ray_footprint * length(a - dot(a, g.i) * g.i);
  float wy = g.ray_footprint * length(b - dot(b, g.i) * g.i);
  return wireframe_within(0.5 * size * 0.5 * (wx + wy), g);
}
