/* What a compiled node graph (addon/materials/codegen.py) reads of the fragment: its texture
 * coordinates (the active UV map, z = 0, as Blender's UV output). */

struct GraphInputs {
  vec3 uv;
};
