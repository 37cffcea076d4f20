/* White Noise Texture (Cycles' svm_node_tex_white_noise, svm/white_noise.h): the hash of the
 * coordinate's bits, 1D (W), 2D (x, y), 3D, 4D (x, y, z, W); Value a float, Color three. */

float node_white_noise_value_1d(vec3 co, float w) { return hash_float_to_float(w); }
float node_white_noise_value_2d(vec3 co, float w) { return hash_vec2_to_float(co.xy); }
float node_white_noise_value_3d(vec3 co, float w) { return hash_vec3_to_float(co); }
float node_white_noise_value_4d(vec3 co, float w) { return hash_vec4_to_float(vec4(co, w)); }

vec4 node_white_noise_color_1d(vec3 co, float w) { return vec4(hash_float_to_vec3(w), 1.0); }
vec4 node_white_noise_color_2d(vec3 co, float w) { return vec4(hash_vec2_to_vec3(co.xy), 1.0); }
vec4 node_white_noise_color_3d(vec3 co, float w) { return vec4(hash_vec3_to_vec3(co), 1.0); }
vec4 node_white_noise_color_4d(vec3 co, float w) { return vec4(hash_vec4_to_vec3(vec4(co, w)), 1.0); }
