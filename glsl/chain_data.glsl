/* The downsampled environment in one texture for filtered importance sampling: each level's
 * rectangle (x, y, width, height in texels; a border of one texel around it), info: x the number
 * of levels, yz the texture's size. */
struct ChainData {
  vec4 rect[12];
  vec4 info;
};

/* The occlusion pass's camera (glsl/gtao.frag.glsl, glsl/occlusion.glsl). lateral: a view
 * position's x and y at normalised device coordinates (x, y) and view depth z, (o + x ex + y ey)
 * times z (perspective) or alone (orthographic): o = lateral_origin.xy, ex, ey = lateral_axes.xy,
 * .zw. */
struct OcclusionData {
  mat4 inverse_projection;
  mat4 projection;
  mat4 view;
  vec4 params;
  vec4 lateral_axes;
  vec4 lateral_origin;
};
