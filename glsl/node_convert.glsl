/* Blender's implicit conversions between socket types (addon/materials/convert.py, the same
 * table): a colour read as a float is its luminance under the running Blender's weights
 * (convert.LUMA, LUMA_4: Cycles' rgb_to_y), a vector read as a float the mean of its components, a float read as a colour grey with
 * alpha 1, a colour read as a vector its RGB, a vector read as a colour its XYZ with alpha 1. */

float convert_rgba_to_value(vec4 c, vec3 luma) { return dot(c.rgb, luma); }
float convert_vector_to_value(vec3 v) { return (v.x + v.y + v.z) * (1.0 / 3.0); }
vec4 convert_value_to_rgba(float f) { return vec4(vec3(f), 1.0); }
vec3 convert_value_to_vector(float f) { return vec3(f); }
vec3 convert_rgba_to_vector(vec4 c) { return c.rgb; }
vec4 convert_vector_to_rgba(vec3 v) { return vec4(v, 1.0); }
