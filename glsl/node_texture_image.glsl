/* The Image Texture node (ShaderNodeTexImage) as Cycles evaluates it: svm_node_tex_image and
 * svm_node_tex_image_box (intern/cycles/kernel/svm/image.h) over the CPU kernel's texture
 * interpolator (kernel/device/cpu/image.h: TextureInterpolator's interp_closest, interp_linear,
 * interp_cubic and its wrap_* rules), with texels as Cycles' image loader stores them.
 *
 * The sampler (graph_image_<k>) holds the engine's texels (addon/scene/snapshot.py ImageData,
 * addon/frame/gpu_scene.py image_texture): a float image's scene-linear, premultiplied values
 * (HALF or FLOAT; Cycles keeps a float file's values as they are); an 8-bit image's own bytes,
 * alpha straight (UNORM8, or SRGB8 decoded by the sampler). Cycles filters an 8-bit image's bytes
 * as they are, alpha premultiplied in bytes (OIIOImageLoader: util_image_multiply_native, a * b
 * / 255 rounded down) unless the image is data, channel packed or without alpha, and decodes sRGB
 * after filtering (NODE_IMAGE_COMPRESS_AS_SRGB); the texel reads below give those bytes back.
 * Texels are fetched one by one (texelFetch): no hardware filtering, wrapping or mipmaps.
 *
 * The node's enum settings are named constants below (the generated source names them, a
 * setting's value is never a number in it): interpolation, extension, how the texels are read. */

#define TEX_IMAGE_CLOSEST 0
#define TEX_IMAGE_LINEAR 1
#define TEX_IMAGE_CUBIC 2 /* Cubic and Smart: Cycles' interp() filters both by the cubic B-spline */

#define TEX_IMAGE_REPEAT 0
#define TEX_IMAGE_EXTEND 1
#define TEX_IMAGE_CLIP 2
#define TEX_IMAGE_MIRROR 3

/* how a fetched texel becomes the value Cycles stores for it */
#define TEX_IMAGE_TEXELS_FLOAT 0          /* HALF, FLOAT: as they are */
#define TEX_IMAGE_TEXELS_BYTES 1          /* UNORM8, straight bytes left straight (data, channel
                                           * packed, no alpha) */
#define TEX_IMAGE_TEXELS_BYTES_ASSOCIATE 2 /* UNORM8, alpha premultiplied in bytes */
#define TEX_IMAGE_TEXELS_SRGB 3           /* SRGB8: the sRGB bytes again, straight */
#define TEX_IMAGE_TEXELS_SRGB_ASSOCIATE 4 /* SRGB8: the sRGB bytes, alpha premultiplied in bytes */

/* Cycles' TEX_IMAGE_MISSING_R/G/B/A (kernel/types.h): what a node without an image gives */
vec4 node_tex_image_missing() { return vec4(1.0, 0.0, 1.0, 1.0); }

/* Cycles' color_linear_to_srgb (util/color.h): the inverse of the sampler's decoding, to give
 * an SRGB8 texel's byte back */
float tex_image_linear_to_srgb(float c)
{
  return c < 0.0031308 ? max(c * 12.92, 0.0) : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

/* Cycles' color_srgb_to_linear (util/color.h; its SSE twin clamps the same way): negative
 * values, as a cubic filter's overshoot gives, decode to 0 */
float tex_image_srgb_to_linear(float c)
{
  return c < 0.04045 ? max(c * (1.0 / 12.92), 0.0) : pow((c + 0.055) * (1.0 / 1.055), 2.4);
}

/* C's integer division toward zero and remainder, as wrap_periodic and wrap_mirror compute */
int tex_image_rem(int x, int n) { return x - n * (x / n); }

/* TextureInterpolator::frac: the texel index below x (one less at a negative whole x, as
 * Cycles' float_to_int(x) - (x < 0) gives) and the fraction above it */
float tex_image_frac(float x, out int i)
{
  i = int(x) - (x < 0.0 ? 1 : 0);
  return x - float(i);
}

/* A texel index under the Extension: wrap_periodic, wrap_clamp, wrap_mirror; Clip leaves the
 * index as it is (tex_image_texel reads outside as transparent black) */
int tex_image_wrap(int x, int n, int extension)
{
  if (extension == TEX_IMAGE_REPEAT) {
    int r = tex_image_rem(x, n);
    return r < 0 ? r + n : r;
  }
  if (extension == TEX_IMAGE_EXTEND) {
    return clamp(x, 0, n - 1);
  }
  if (extension == TEX_IMAGE_MIRROR) {
    int m = tex_image_rem(abs(x + (x < 0 ? 1 : 0)), 2 * n);
    return m >= n ? 2 * n - m - 1 : m;
  }
  return x;
}

/* A fetched texel as Cycles stores it (the texel reads, TEX_IMAGE_TEXELS_*) */
vec4 tex_image_decode(vec4 t, int texels)
{
  if (texels == TEX_IMAGE_TEXELS_FLOAT) {
    return t;
  }
  if (texels >= TEX_IMAGE_TEXELS_SRGB) { /* the byte the sampler decoded (its error is far below
                                          * half a byte: rounding gives it exactly) */
    t.rgb = vec3(tex_image_linear_to_srgb(t.r), tex_image_linear_to_srgb(t.g), tex_image_linear_to_srgb(t.b));
  }
  vec4 bytes = floor(t * 255.0 + 0.5);
  if (texels == TEX_IMAGE_TEXELS_BYTES_ASSOCIATE || texels == TEX_IMAGE_TEXELS_SRGB_ASSOCIATE) {
    bytes.rgb = floor(bytes.rgb * bytes.a / 255.0 + 1e-3); /* (a * b) / 255 in integers; the
                                                            * 1e-3 keeps a whole quotient whole */
  }
  return bytes * (1.0 / 255.0);
}

/* Texel p (already wrapped) as Cycles stores it; outside the image (only Clip reaches there):
 * transparent black, as read_clip gives. One per sampler kind: an image, or one layer (a UDIM
 * tile) of an array. */
vec4 tex_image_texel(sampler2D image, ivec2 p, ivec2 size, int texels)
{
  if (p.x < 0 || p.y < 0 || p.x >= size.x || p.y >= size.y) {
    return vec4(0.0);
  }
  return tex_image_decode(texelFetch(image, p, 0), texels);
}

vec4 tex_image_texel(sampler2DArray image, int layer, ivec2 p, ivec2 size, int texels)
{
  if (p.x < 0 || p.y < 0 || p.x >= size.x || p.y >= size.y) {
    return vec4(0.0);
  }
  return tex_image_decode(texelFetch(image, ivec3(p, layer), 0), texels);
}

/* Cycles' SET_CUBIC_SPLINE_WEIGHTS: the uniform cubic B-spline's four weights at t */
vec4 tex_image_cubic_weights(float t)
{
  return vec4((((-1.0 / 6.0) * t + 0.5) * t - 0.5) * t + (1.0 / 6.0), ((0.5 * t - 1.0) * t) * t + (2.0 / 3.0),
              ((-0.5 * t + 0.5) * t + 0.5) * t + (1.0 / 6.0), (1.0 / 6.0) * t * t * t);
}

/* The filters' texel addresses and weights, whatever holds the texels (one image, or a UDIM
 * tile's layer of an array): the sampler-specific functions below only fetch and sum. */

/* interp_closest: the texel uv lies in; false where Clip leaves it outside (transparent black) */
bool tex_image_closest_at(vec2 uv, ivec2 size, int extension, out ivec2 p)
{
  ivec2 i;
  tex_image_frac(uv.x * float(size.x), i.x);
  tex_image_frac(uv.y * float(size.y), i.y);
  p = ivec2(tex_image_wrap(i.x, size.x, extension), tex_image_wrap(i.y, size.y, extension));
  return !(extension == TEX_IMAGE_CLIP && (i.x < 0 || i.x >= size.x || i.y < 0 || i.y >= size.y));
}

/* interp_linear: the four texels around uv (texel centres at half-integers: x0, x1, y0, y1 in
 * xy) and the fractions t; false where Clip has no texel of the four inside */
bool tex_image_linear_at(vec2 uv, ivec2 size, int extension, out ivec4 xy, out vec2 t)
{
  ivec2 i;
  t.x = tex_image_frac(uv.x * float(size.x) - 0.5, i.x);
  t.y = tex_image_frac(uv.y * float(size.y) - 0.5, i.y);
  xy = ivec4(tex_image_wrap(i.x, size.x, extension), tex_image_wrap(i.x + 1, size.x, extension),
             tex_image_wrap(i.y, size.y, extension), tex_image_wrap(i.y + 1, size.y, extension));
  return !(extension == TEX_IMAGE_CLIP && (i.x < -1 || i.x >= size.x || i.y < -1 || i.y >= size.y));
}

/* interp_linear's sum of the four texels, weighted as Cycles writes it */
vec4 tex_image_bilinear(vec4 a, vec4 b, vec4 c, vec4 d, vec2 t)
{
  return (1.0 - t.y) * (1.0 - t.x) * a + (1.0 - t.y) * t.x * b + t.y * (1.0 - t.x) * c + t.y * t.x * d;
}

/* interp_cubic: the 4 x 4 texels around uv (columns xs, rows ys, wrapped) and their cubic
 * B-spline weights u, v (Cubic and Smart); false where Clip has no texel of the sixteen inside */
bool tex_image_cubic_at(vec2 uv, ivec2 size, int extension, out ivec4 xs, out ivec4 ys, out vec4 u, out vec4 v)
{
  ivec2 i;
  float tx = tex_image_frac(uv.x * float(size.x) - 0.5, i.x);
  float ty = tex_image_frac(uv.y * float(size.y) - 0.5, i.y);
  u = tex_image_cubic_weights(tx);
  v = tex_image_cubic_weights(ty);
  for (int k = 0; k < 4; k++) {
    xs[k] = tex_image_wrap(i.x - 1 + k, size.x, extension);
    ys[k] = tex_image_wrap(i.y - 1 + k, size.y, extension);
  }
  return !(extension == TEX_IMAGE_CLIP && (i.x < -2 || i.x > size.x || i.y < -2 || i.y > size.y));
}

/* kernel_tex_image_interp: the image filtered at uv by the node's Interpolation */
vec4 tex_image_filter(sampler2D image, vec2 uv, int interpolation, int extension, int texels)
{
  ivec2 size = textureSize(image, 0);
  if (interpolation == TEX_IMAGE_CLOSEST) {
    ivec2 p;
    return tex_image_closest_at(uv, size, extension, p) ? tex_image_texel(image, p, size, texels) : vec4(0.0);
  }
  if (interpolation == TEX_IMAGE_LINEAR) {
    ivec4 xy;
    vec2 t;
    if (!tex_image_linear_at(uv, size, extension, xy, t)) {
      return vec4(0.0);
    }
    return tex_image_bilinear(tex_image_texel(image, xy.xz, size, texels), tex_image_texel(image, xy.yz, size, texels),
                              tex_image_texel(image, xy.xw, size, texels), tex_image_texel(image, xy.yw, size, texels),
                              t);
  }
  ivec4 xs, ys;
  vec4 u, v;
  if (!tex_image_cubic_at(uv, size, extension, xs, ys, u, v)) {
    return vec4(0.0);
  }
  vec4 sum = vec4(0.0);
  for (int row = 0; row < 4; row++) {
    vec4 line = vec4(0.0);
    for (int col = 0; col < 4; col++) {
      line += u[col] * tex_image_texel(image, ivec2(xs[col], ys[row]), size, texels);
    }
    sum += v[row] * line;
  }
  return sum;
}

/* The same filters over one layer of an array (a UDIM tile: every layer is one size) */
vec4 tex_image_filter(sampler2DArray image, int layer, vec2 uv, int interpolation, int extension, int texels)
{
  ivec2 size = textureSize(image, 0).xy;
  if (interpolation == TEX_IMAGE_CLOSEST) {
    ivec2 p;
    return tex_image_closest_at(uv, size, extension, p) ? tex_image_texel(image, layer, p, size, texels) :
                                                          vec4(0.0);
  }
  if (interpolation == TEX_IMAGE_LINEAR) {
    ivec4 xy;
    vec2 t;
    if (!tex_image_linear_at(uv, size, extension, xy, t)) {
      return vec4(0.0);
    }
    return tex_image_bilinear(tex_image_texel(image, layer, xy.xz, size, texels),
                              tex_image_texel(image, layer, xy.yz, size, texels),
                              tex_image_texel(image, layer, xy.xw, size, texels),
                              tex_image_texel(image, layer, xy.yw, size, texels), t);
  }
  ivec4 xs, ys;
  vec4 u, v;
  if (!tex_image_cubic_at(uv, size, extension, xs, ys, u, v)) {
    return vec4(0.0);
  }
  vec4 sum = vec4(0.0);
  for (int row = 0; row < 4; row++) {
    vec4 line = vec4(0.0);
    for (int col = 0; col < 4; col++) {
      line += u[col] * tex_image_texel(image, layer, ivec2(xs[col], ys[row]), size, texels);
    }
    sum += v[row] * line;
  }
  return sum;
}

/* svm_image_texture after the filtering: the colour divided by alpha where the node's Alpha is
 * read (NODE_IMAGE_ALPHA_UNASSOCIATE; not at alpha 0 or 1), then an 8-bit sRGB image's bytes
 * decoded (NODE_IMAGE_COMPRESS_AS_SRGB; alpha as it is) */
vec4 tex_image_output(vec4 r, bool unassociate, bool decode)
{
  if (unassociate && r.a != 1.0 && r.a != 0.0) {
    r.rgb /= r.a;
  }
  if (decode) {
    r.rgb = vec3(tex_image_srgb_to_linear(r.r), tex_image_srgb_to_linear(r.g), tex_image_srgb_to_linear(r.b));
  }
  return r;
}

/* Cycles' texco_remap_square: the 0..1 box to -1..1 */
vec3 tex_image_remap_square(vec3 co) { return (co - 0.5) * 2.0; }

/* Cycles' map_to_sphere (util/math_float3.h): longitude and latitude of co about the origin, 0
 * at the origin and along the z axis's longitude */
vec2 tex_image_map_to_sphere(vec3 co)
{
  float l = dot(co, co);
  if (!(l > 0.0)) {
    return vec2(0.0);
  }
  float u = (co.x == 0.0 && co.y == 0.0) ? 0.0 : 0.5 - atan(co.x, co.y) * (0.5 / 3.14159265358979);
  /* safe_acosf(z / |co|) as the angle of (|co.xy|, z): GLSL's acos is far less precise (measured
   * 2.3e-4 off Cycles' alpha at texel edges, 4.1e-6 this way) */
  return vec2(u, 1.0 - atan(length(co.xy), co.z) * (1.0 / 3.14159265358979));
}

/* Cycles' map_to_tube: the angle about the z axis and the height, 0 on the axis */
vec2 tex_image_map_to_tube(vec3 co)
{
  float len = sqrt(co.x * co.x + co.y * co.y);
  if (!(len > 0.0)) {
    return vec2(0.0);
  }
  return vec2((1.0 - atan(co.x / len, co.y / len) * (1.0 / 3.14159265358979)) * 0.5, (co.z + 1.0) * 0.5);
}

/* The node's projections before filtering (svm_node_tex_image): Flat reads co's x and y, Sphere
 * and Tube wrap the -1..1 box around the image */
vec4 node_tex_image_flat(sampler2D image, vec3 co, int interpolation, int extension, int texels)
{
  return tex_image_filter(image, co.xy, interpolation, extension, texels);
}

vec4 node_tex_image_sphere(sampler2D image, vec3 co, int interpolation, int extension, int texels)
{
  return tex_image_filter(image, tex_image_map_to_sphere(tex_image_remap_square(co)), interpolation, extension,
                          texels);
}

vec4 node_tex_image_tube(sampler2D image, vec3 co, int interpolation, int extension, int texels)
{
  return tex_image_filter(image, tex_image_map_to_tube(tex_image_remap_square(co)), interpolation, extension,
                          texels);
}

/* svm_node_tex_image_box: the image projected along the object-space normal's three axes (n:
 * that normal, any length), blended by their weights in the barycentric triangle of |n|;
 * each projection's sample is output (unassociated, decoded) before the weighted sum */
vec4 node_tex_image_box(sampler2D image, vec3 co, vec3 n, float blend, int interpolation, int extension,
                        int texels, bool unassociate, bool decode)
{
  vec3 signed_n = n;
  n = abs(n);
  n /= (n.x + n.y + n.z);
  vec3 weight = vec3(0.0);
  float limit = 0.5 * (1.0 + blend);
  if (n.x > limit * (n.x + n.y) && n.x > limit * (n.x + n.z)) {
    weight.x = 1.0;
  }
  else if (n.y > limit * (n.x + n.y) && n.y > limit * (n.y + n.z)) {
    weight.y = 1.0;
  }
  else if (n.z > limit * (n.x + n.z) && n.z > limit * (n.y + n.z)) {
    weight.z = 1.0;
  }
  else if (blend > 0.0) {
    if (n.z < (1.0 - limit) * (n.y + n.x)) {
      weight.x = clamp((n.x / (n.x + n.y) - 0.5 * (1.0 - blend)) / blend, 0.0, 1.0);
      weight.y = 1.0 - weight.x;
    }
    else if (n.x < (1.0 - limit) * (n.y + n.z)) {
      weight.y = clamp((n.y / (n.y + n.z) - 0.5 * (1.0 - blend)) / blend, 0.0, 1.0);
      weight.z = 1.0 - weight.y;
    }
    else if (n.y < (1.0 - limit) * (n.x + n.z)) {
      weight.x = clamp((n.x / (n.x + n.z) - 0.5 * (1.0 - blend)) / blend, 0.0, 1.0);
      weight.z = 1.0 - weight.x;
    }
    else { /* all three */
      weight = ((2.0 - limit) * n + (limit - 1.0)) / (2.0 * limit - 1.0);
    }
  }
  else { /* no blend and no axis dominant: Cycles falls back to the x projection */
    weight.x = 1.0;
  }
  vec4 f = vec4(0.0);
  if (weight.x > 0.0) {
    vec2 uv = vec2(signed_n.x < 0.0 ? 1.0 - co.y : co.y, co.z);
    f += weight.x * tex_image_output(tex_image_filter(image, uv, interpolation, extension, texels), unassociate,
                                     decode);
  }
  if (weight.y > 0.0) {
    vec2 uv = vec2(signed_n.y > 0.0 ? 1.0 - co.x : co.x, co.z);
    f += weight.y * tex_image_output(tex_image_filter(image, uv, interpolation, extension, texels), unassociate,
                                     decode);
  }
  if (weight.z > 0.0) {
    vec2 uv = vec2(signed_n.z > 0.0 ? 1.0 - co.y : co.y, co.x);
    f += weight.z * tex_image_output(tex_image_filter(image, uv, interpolation, extension, texels), unassociate,
                                     decode);
  }
  return f;
}

/* the tables' reader (the compiled source defines it: glsl/node_ramp.glsl) */
vec4 graph_table(int i);

/* UDIM (tiled) images: svm_node_tex_image's tile lookup (intern/cycles/kernel/svm/image.h). The
 * tile's column and row are uv truncated toward zero (C's (int) cast: u in (-1, 0) is still
 * column 0, and the tile's own Extension then reads it); a tile is found only where
 * 0 <= column < 10 and row >= 0, as number 1001 + 10 row + column among the image's tiles: a
 * table of tile numbers, four to a row, at graph_table(table) .. graph_table(table + rows - 1)
 * (0 after the last: no tile has that number). Gives (uv relative to the tile, the tile's index
 * in the table); index -1 where no tile holds uv (Cycles then gives TEX_IMAGE_MISSING). */
vec3 tex_image_tile(vec2 uv, int table, int rows)
{
  int tx = int(uv.x), ty = int(uv.y);
  if (tx >= 0 && ty >= 0 && tx < 10) {
    float tile = float(1001 + 10 * ty + tx);
    for (int r = 0; r < rows; r++) {
      vec4 numbers = graph_table(table + r);
      for (int c = 0; c < 4; c++) {
        if (numbers[c] == tile) {
          return vec3(uv.x - float(tx), uv.y - float(ty), float(4 * r + c));
        }
      }
    }
  }
  return vec3(uv, -1.0);
}

/* A UDIM image's sample at uv (Flat, Sphere or Tube projected): the tile's layer of the array
 * (layers in the table's order, one size) filtered at uv relative to the tile; outside every
 * tile Cycles' missing colour */
vec4 node_tex_image_tiled(sampler2DArray image, vec2 uv, int table, int rows, int interpolation, int extension,
                          int texels)
{
  vec3 t = tex_image_tile(uv, table, rows);
  if (t.z < 0.0) {
    return node_tex_image_missing();
  }
  return tex_image_filter(image, int(t.z), t.xy, interpolation, extension, texels);
}
