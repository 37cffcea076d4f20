/* What a compiled node graph (addon/materials/codegen.py) reads of the fragment: its texture
 * coordinates (the active UV map, z = 0, as Blender's UV output), the world position, the unit
 * shading normal n and the unit direction towards the viewer i (Cycles' sd->N and sd->wi), and
 * whether the fragment is a back face. */

struct GraphInputs {
  vec3 uv;
  vec3 position;
  vec3 n;
  vec3 i;
  bool backfacing;
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
