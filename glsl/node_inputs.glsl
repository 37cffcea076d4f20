/* What a compiled node graph (addon/materials/codegen.py) reads of the fragment, filled by the
 * program that calls it (glsl/mesh.frag.glsl's graph_inputs; the tests' harness from Cycles' own
 * AOVs of the same fragment). World space unless said. */

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
  vec4 tangent;         /* xyz: unit tangent of the active UV map (0: none); w: the bitangent's sign */
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
