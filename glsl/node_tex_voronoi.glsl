/* Voronoi Texture (Cycles 5.0's svm_node_tex_voronoi, kernel/svm/voronoi.h): F1, F2, Smooth F1,
 * Distance to Edge and N-Sphere Radius in 1D to 4D, by the Euclidean, Manhattan, Chebychev or
 * Minkowski distance, fractal (Detail, Roughness, Lacunarity) but for N-Sphere Radius. Cycles
 * writes each dimension's functions apart (float .. float4); here one body serves all four: a
 * point is a vec4 whose unused components stay 0 (1D in x), which every operation leaves 0, and
 * whose sums and dot products add in Cycles' order for float2 (x + y), float3 ((x + y) + z: SSE's
 * dpps) and float4 ((x + y) + (z + w)): (x + y) + (z + w) with zeros is each of them, bit for
 * bit. The cells are visited in Cycles' order (w outermost, x innermost), only along the point's
 * axes.
 * The numpy twin is addon/reference/voronoi.py. */

#define VORONOI_F1 0
#define VORONOI_F2 1
#define VORONOI_SMOOTH_F1 2

#define VORONOI_EUCLIDEAN 0
#define VORONOI_MANHATTAN 1 /* also 1D's |b - a| (Cycles' voronoi_distance(float, float)) */
#define VORONOI_CHEBYCHEV 2
#define VORONOI_MINKOWSKI 3

/* The cells' hash, which the Blender reading the file decides (the reader's voronoi_cells): */
#define VORONOI_CELLS_INT 0   /* Cycles 5.0: a cell's integer index, PCG (hash_int*_to_float*) */
#define VORONOI_CELLS_FLOAT 1 /* Cycles 4.x: the cell's float coordinates, lookup3 (hash_float*) */

#define VORONOI_FLT_MAX 3.402823466e+38

/* The node's values; its settings (dimensions, feature, metric, cells' hash) are int arguments of
 * their own, which the compiler folds into the calling variant's code */
struct VoronoiParams {
  float scale;
  float detail;
  float roughness;
  float lacunarity;
  float smoothness;
  float exponent;
  float randomness;
  float max_distance;
  bool normalize;
};

struct VoronoiOctave {
  float distance;
  vec3 color;
  vec4 position;
};

/* What a node's outputs read (Cycles' svm_voronoi_output): Distance, Color, Position, W, Radius;
 * the outputs a feature does not compute are 0. */
struct VoronoiTexture {
  float distance;
  vec4 color;
  vec3 position;
  float w;
  float radius;
};

/* Cycles' mix(a, b, t) = a + t (b - a) (GLSL's mix may round otherwise), unfused */
float voronoi_mix(float a, float b, float t)
{
  PRECISE float m = a + t * (b - a);
  return m;
}

vec3 voronoi_mix(vec3 a, vec3 b, float t)
{
  PRECISE vec3 m = a + t * (b - a);
  return m;
}

vec4 voronoi_mix(vec4 a, vec4 b, float t)
{
  PRECISE vec4 m = a + t * (b - a);
  return m;
}

/* 1 in the components a point of `dims` dimensions uses (1D: x) */
vec4 voronoi_lanes(int dims) { return vec4(1.0, dims > 1 ? 1.0 : 0.0, dims > 2 ? 1.0 : 0.0, dims > 3 ? 1.0 : 0.0); }

/* Cycles' reduce_add and dot of float2, float3 (SSE's pairs) and float4 alike; `precise`: in
 * this order, unfused (a GLSL compiler may otherwise reassociate the sum: llvmpipe fused and
 * reordered a 4D distance's terms, a last-bit difference in 135 of 1089 pixels) */
float voronoi_sum(vec4 v)
{
  PRECISE float sum = (v.x + v.y) + (v.z + v.w);
  return sum;
}

/* Cycles' normalize(a): a / len(a); float2's and float4's `/ float` multiply by the reciprocal,
 * float3's (SSE) divides */
vec4 voronoi_normalize(vec4 v, int dims)
{
  float len = sqrt(voronoi_sum(v * v));
  return dims == 3 ? v / len : v * (1.0 / len);
}

/* Cycles' voronoi_distance_bound: what orders distances as voronoi_distance does, cheaper (the
 * squared Euclidean length, the Minkowski sum before its root) */
float voronoi_distance_bound(int dims, int metric, vec4 d, VoronoiParams p)
{
  vec4 a = abs(d);
  if (metric == VORONOI_EUCLIDEAN) {
    return voronoi_sum(d * d);
  }
  if (metric == VORONOI_MANHATTAN) {
    return voronoi_sum(a);
  }
  if (metric == VORONOI_CHEBYCHEV) {
    return max(max(a.x, a.y), max(a.z, a.w));
  }
  /* the unused components chosen out, not multiplied by 0: pow(0, e) is inf for e < 0 (and
   * GLSL leaves pow(0, e <= 0) undefined, where C's powf(0, 0) is 1: Exponent 0 with a
   * component of exactly 0, which only this edge case of the setting meets) */
  bvec4 used = bvec4(true, dims > 1, dims > 2, dims > 3);
  return voronoi_sum(mix(vec4(0.0), pow(a, vec4(p.exponent)), used));
}

/* Cycles' voronoi_distance of a - b = d */
float voronoi_distance(int dims, int metric, vec4 d, VoronoiParams p)
{
  float bound = voronoi_distance_bound(dims, metric, d, p);
  if (metric == VORONOI_EUCLIDEAN) {
    return sqrt(bound);
  }
  if (metric == VORONOI_MINKOWSKI) {
    return pow(bound, 1.0 / p.exponent);
  }
  return bound;
}

/* The feature point's offset in cell `cell` + `offset` (before Randomness): 1D (every version)
 * and Cycles 4.x hash the cell's float coordinates, Cycles 5.0 its integer index. `cellf` is
 * the cell's float coordinates, `cell` the same as integers. */
vec4 voronoi_cell_hash(int dims, int cells, vec4 cellf, ivec4 cell, ivec4 offset)
{
  vec4 key = cellf + vec4(offset);
  ivec4 index = cell + offset;
  if (dims == 1) {
    return vec4(hash_float_to_float(key.x), 0.0, 0.0, 0.0);
  }
  if (cells == VORONOI_CELLS_FLOAT) {
    return dims == 2 ? vec4(hash_vec2_to_vec2(key.xy), 0.0, 0.0) :
           dims == 3 ? vec4(hash_vec3_to_vec3(key.xyz), 0.0) : hash_vec4_to_vec4(key);
  }
  return dims == 2 ? vec4(hash_ivec2_to_vec2(index.xy), 0.0, 0.0) :
         dims == 3 ? vec4(hash_ivec3_to_vec3(index.xyz), 0.0) : hash_ivec4_to_vec4(index);
}

/* The colour of cell `cell` + `offset` */
vec3 voronoi_cell_color(int dims, int cells, vec4 cellf, ivec4 cell, ivec4 offset)
{
  vec4 key = cellf + vec4(offset);
  ivec4 index = cell + offset;
  if (dims == 1) {
    return hash_float_to_vec3(key.x);
  }
  if (cells == VORONOI_CELLS_FLOAT) {
    return dims == 2 ? hash_vec2_to_vec3(key.xy) : dims == 3 ? hash_vec3_to_vec3(key.xyz) : hash_vec4_to_vec3(key);
  }
  return dims == 2 ? hash_ivec2_to_vec3(index.xy) : dims == 3 ? hash_ivec3_to_vec3(index.xyz) :
                                                                hash_ivec4_to_vec3(index);
}

/* The feature point of cell `cell` + `offset`, relative to cell `cell` */
vec4 voronoi_point(int dims, int cells, vec4 cellf, ivec4 cell, ivec4 offset, float randomness)
{
  return vec4(offset) + voronoi_cell_hash(dims, cells, cellf, cell, offset) * randomness;
}

/* The cells within `r` of a point's along each of its axes, (2r + 1)^dims of them, one loop
 * over them (n) in Cycles' order: x innermost, then y, z, w outermost */
int voronoi_around(int dims, int r)
{
  int side = 2 * r + 1;
  return dims == 1 ? side : dims == 2 ? side * side : dims == 3 ? side * side * side : side * side * side * side;
}

/* The n-th of them: its offset from the point's cell */
ivec4 voronoi_offset(int dims, int r, int n)
{
  int side = 2 * r + 1;
  ivec4 offset = ivec4(0);
  for (int axis = 0; axis < dims; axis++) {
    offset[axis] = n % side - r;
    n /= side;
  }
  return offset;
}

/* The feature point closest to `local` (in cell `cell`) by the metric's voronoi_distance_bound:
 * its cell's offset and its position relative to the cell (Cycles' voronoi_f1 and the first scan
 * of voronoi_n_sphere_radius) */
void voronoi_closest(int dims, int metric, int cells, VoronoiParams p, vec4 cellf, ivec4 cell, vec4 local,
                     out ivec4 closest_offset, out vec4 closest)
{
  float min_distance = VORONOI_FLT_MAX;
  closest_offset = ivec4(0);
  closest = vec4(0.0);
  for (int n = 0; n < voronoi_around(dims, 1); n++) {
    ivec4 offset = voronoi_offset(dims, 1, n);
    vec4 point = voronoi_point(dims, cells, cellf, cell, offset, p.randomness);
    float d = voronoi_distance_bound(dims, metric, point - local, p);
    if (d < min_distance) {
      closest_offset = offset;
      min_distance = d;
      closest = point;
    }
  }
}

/* Cycles' voronoi_f1: the closest feature point */
VoronoiOctave voronoi_f1(int dims, int metric, int cells, VoronoiParams p, vec4 coord)
{
  vec4 cellf = floor(coord);
  vec4 local = coord - cellf;
  ivec4 cell = ivec4(cellf); /* a cell index past 2^31 wraps differently from Cycles' (either is garbage) */
  ivec4 offset;
  vec4 point;
  voronoi_closest(dims, metric, cells, p, cellf, cell, local, offset, point);
  return VoronoiOctave(voronoi_distance(dims, metric, point - local, p),
                       voronoi_cell_color(dims, cells, cellf, cell, offset), point + cellf);
}

/* Cycles' voronoi_smooth_f1: F1 blended over the 5^dims cells around by a smooth minimum */
VoronoiOctave voronoi_smooth_f1(int dims, int metric, int cells, VoronoiParams p, vec4 coord)
{
  vec4 cellf = floor(coord);
  vec4 local = coord - cellf;
  ivec4 cell = ivec4(cellf);
  vec4 lanes = voronoi_lanes(dims); /* the correction moves only the point's own components */
  float smooth_distance = 0.0;
  vec3 smooth_color = vec3(0.0);
  vec4 smooth_position = vec4(0.0);
  float h = -1.0;
  for (int n = 0; n < voronoi_around(dims, 2); n++) {
    ivec4 offset = voronoi_offset(dims, 2, n);
    vec4 point = voronoi_point(dims, cells, cellf, cell, offset, p.randomness);
    float d = voronoi_distance(dims, metric, point - local, p);
    h = h == -1.0 ? 1.0 :
                    node_smoothstep(0.0, 1.0, 0.5 + 0.5 * (smooth_distance - d) / p.smoothness);
    float correction = p.smoothness * h * (1.0 - h);
    smooth_distance = voronoi_mix(smooth_distance, d, h) - correction;
    correction /= 1.0 + 3.0 * p.smoothness;
    smooth_color = voronoi_mix(smooth_color, voronoi_cell_color(dims, cells, cellf, cell, offset), h) - correction;
    smooth_position = voronoi_mix(smooth_position, point, h) - correction * lanes;
  }
  return VoronoiOctave(smooth_distance, smooth_color, cellf + smooth_position);
}

/* Cycles' voronoi_f2: the second closest feature point */
VoronoiOctave voronoi_f2(int dims, int metric, int cells, VoronoiParams p, vec4 coord)
{
  vec4 cellf = floor(coord);
  vec4 local = coord - cellf;
  ivec4 cell = ivec4(cellf);
  float distance_f1 = VORONOI_FLT_MAX;
  float distance_f2 = VORONOI_FLT_MAX;
  ivec4 offset_f1 = ivec4(0);
  vec4 position_f1 = vec4(0.0);
  ivec4 offset_f2 = ivec4(0);
  vec4 position_f2 = vec4(0.0);
  for (int n = 0; n < voronoi_around(dims, 1); n++) {
    ivec4 offset = voronoi_offset(dims, 1, n);
    vec4 point = voronoi_point(dims, cells, cellf, cell, offset, p.randomness);
    float d = voronoi_distance(dims, metric, point - local, p);
    if (d < distance_f1) {
      distance_f2 = distance_f1;
      distance_f1 = d;
      offset_f2 = offset_f1;
      offset_f1 = offset;
      position_f2 = position_f1;
      position_f1 = point;
    }
    else if (d < distance_f2) {
      distance_f2 = d;
      offset_f2 = offset;
      position_f2 = point;
    }
  }
  return VoronoiOctave(distance_f2, voronoi_cell_color(dims, cells, cellf, cell, offset_f2), position_f2 + cellf);
}

/* Cycles' 1D voronoi_distance_to_edge: to the nearer of the midpoints between the cell's point
 * and its neighbours' */
float voronoi_distance_to_edge_1d(VoronoiParams p, float coord)
{
  float cellf = floor(coord);
  float local = coord - cellf;
  float mid = hash_float_to_float(cellf) * p.randomness;
  float left = -1.0 + hash_float_to_float(cellf - 1.0) * p.randomness;
  float right = 1.0 + hash_float_to_float(cellf + 1.0) * p.randomness;
  return min(abs((mid + left) / 2.0 - local), abs((mid + right) / 2.0 - local));
}

/* Cycles' voronoi_distance_to_edge (2D-4D, Euclidean whatever the metric): the closest point,
 * then the nearest of the bisectors between it and the points around */
float voronoi_distance_to_edge(int dims, int cells, VoronoiParams p, vec4 coord)
{
  if (dims == 1) {
    return voronoi_distance_to_edge_1d(p, coord.x);
  }
  vec4 cellf = floor(coord);
  vec4 local = coord - cellf;
  ivec4 cell = ivec4(cellf);
  vec4 to_closest = vec4(0.0);
  float min_distance = VORONOI_FLT_MAX;
  for (int n = 0; n < voronoi_around(dims, 1); n++) {
    vec4 to_point = voronoi_point(dims, cells, cellf, cell, voronoi_offset(dims, 1, n), p.randomness) - local;
    float d = voronoi_sum(to_point * to_point);
    if (d < min_distance) {
      min_distance = d;
      to_closest = to_point;
    }
  }
  min_distance = VORONOI_FLT_MAX;
  for (int n = 0; n < voronoi_around(dims, 1); n++) {
    vec4 to_point = voronoi_point(dims, cells, cellf, cell, voronoi_offset(dims, 1, n), p.randomness) - local;
    vec4 perpendicular = to_point - to_closest;
    /* Cycles' threshold: the closest point itself (and one within 1e-2 of it) has no bisector */
    if (voronoi_sum(perpendicular * perpendicular) > 0.0001) {
      vec4 mid = (to_closest + to_point) / 2.0;
      min_distance = min(min_distance, voronoi_sum(mid * voronoi_normalize(perpendicular, dims)));
    }
  }
  return min_distance;
}

/* Cycles' voronoi_n_sphere_radius: half the distance from the closest point to its own closest
 * point (Euclidean whatever the metric; 1D: |b - a|) */
float voronoi_n_sphere_radius(int dims, int cells, VoronoiParams p, vec4 coord)
{
  int metric = dims == 1 ? VORONOI_MANHATTAN : VORONOI_EUCLIDEAN;
  vec4 cellf = floor(coord);
  vec4 local = coord - cellf;
  ivec4 cell = ivec4(cellf);
  ivec4 closest_offset;
  vec4 closest;
  voronoi_closest(dims, metric, cells, p, cellf, cell, local, closest_offset, closest);
  float min_distance = VORONOI_FLT_MAX;
  vec4 closest_to_closest = vec4(0.0);
  for (int n = 0; n < voronoi_around(dims, 1); n++) {
    ivec4 around = voronoi_offset(dims, 1, n);
    if (around == ivec4(0)) {
      continue;
    }
    ivec4 offset = around + closest_offset;
    vec4 point = voronoi_point(dims, cells, cellf, cell, offset, p.randomness);
    float d = voronoi_distance_bound(dims, metric, closest - point, p);
    if (d < min_distance) {
      min_distance = d;
      closest_to_closest = point;
    }
  }
  return voronoi_distance(dims, metric, closest_to_closest - closest, p) / 2.0;
}

/* Cycles' fractal_voronoi_x_fx: octaves of F1, F2 or Smooth F1 at scales Lacunarity^i, summed
 * (distance, colour) or blended (position) by amplitudes Roughness^i, the last octave by the
 * fraction of Detail; Normalize divides by the amplitudes' sum and the largest distance */
VoronoiOctave voronoi_fractal(int dims, int feature, int metric, int cells, VoronoiParams p, vec4 coord)
{
  float amplitude = 1.0;
  PRECISE float max_amplitude = 0.0; /* precise: the sums unfused, in Cycles' order */
  float scale = 1.0;
  PRECISE VoronoiOctave result = VoronoiOctave(0.0, vec3(0.0), vec4(0.0));
  bool zero_input = p.detail == 0.0 || p.roughness == 0.0;
  for (int i = 0; float(i) <= ceil(p.detail); ++i) {
    vec4 at = coord * scale;
    VoronoiOctave octave = feature == VORONOI_F2 ? voronoi_f2(dims, metric, cells, p, at) :
                           feature == VORONOI_SMOOTH_F1 && p.smoothness != 0.0 ?
                                                   voronoi_smooth_f1(dims, metric, cells, p, at) :
                                                   voronoi_f1(dims, metric, cells, p, at);
    if (zero_input) {
      max_amplitude = 1.0;
      result = octave;
      break;
    }
    vec4 position = octave.position * (1.0 / scale); /* Cycles' float4 / float: times the reciprocal */
    if (float(i) <= p.detail) {
      max_amplitude += amplitude;
      result.distance += octave.distance * amplitude;
      result.color += octave.color * amplitude;
      result.position = voronoi_mix(result.position, position, amplitude);
      scale *= p.lacunarity;
      amplitude *= p.roughness;
    }
    else {
      float remainder = p.detail - floor(p.detail);
      if (remainder != 0.0) {
        max_amplitude = voronoi_mix(max_amplitude, max_amplitude + amplitude, remainder);
        result.distance = voronoi_mix(result.distance, result.distance + octave.distance * amplitude,
                                      remainder);
        result.color = voronoi_mix(result.color, result.color + octave.color * amplitude, remainder);
        result.position = voronoi_mix(result.position, voronoi_mix(result.position, position, amplitude),
                                      remainder);
      }
    }
  }
  if (p.normalize) {
    result.distance /= max_amplitude * p.max_distance;
    result.color *= 1.0 / max_amplitude; /* Cycles' float3 /= float: times the reciprocal */
  }
  /* Cycles' safe_divide(float4, float): 0 for Scale 0, else times the reciprocal */
  result.position = p.scale != 0.0 ? result.position * (1.0 / p.scale) : vec4(0.0);
  return result;
}

/* Cycles' fractal_voronoi_distance_to_edge: the octaves' distances by a running minimum */
float voronoi_fractal_distance_to_edge(int dims, int cells, VoronoiParams p, vec4 coord)
{
  float amplitude = 1.0;
  float max_amplitude = p.max_distance;
  float scale = 1.0;
  float distance = 8.0;
  bool zero_input = p.detail == 0.0 || p.roughness == 0.0;
  for (int i = 0; float(i) <= ceil(p.detail); ++i) {
    float octave_distance = voronoi_distance_to_edge(dims, cells, p, coord * scale);
    if (zero_input) {
      distance = octave_distance;
      break;
    }
    if (float(i) <= p.detail) {
      max_amplitude = voronoi_mix(max_amplitude, p.max_distance / scale, amplitude);
      distance = voronoi_mix(distance, min(distance, octave_distance / scale), amplitude);
      scale *= p.lacunarity;
      amplitude *= p.roughness;
    }
    else {
      float remainder = p.detail - floor(p.detail);
      if (remainder != 0.0) {
        float lerp_amplitude = voronoi_mix(max_amplitude, p.max_distance / scale, amplitude);
        max_amplitude = voronoi_mix(max_amplitude, lerp_amplitude, remainder);
        float lerp_distance = voronoi_mix(distance, min(distance, octave_distance / scale), amplitude);
        distance = voronoi_mix(distance, min(distance, lerp_distance), remainder);
      }
    }
  }
  if (p.normalize) {
    distance /= max_amplitude;
  }
  return distance;
}

/* The node's values as Cycles' svm_node_tex_voronoi reads them: Detail clamped to [0, 15] (its
 * octave count), Roughness and Randomness to [0, 1], Smoothness halved into [0, 0.5]. `fractal`:
 * Scale, Detail, Roughness, Lacunarity; `shape`: Smoothness, Exponent, Randomness. */
VoronoiParams voronoi_params(bool normalize, vec4 fractal, vec3 shape)
{
  return VoronoiParams(fractal.x, clamp(fractal.y, 0.0, 15.0), clamp(fractal.z, 0.0, 1.0), fractal.w,
                       clamp(shape.x / 2.0, 0.0, 0.5), shape.y, clamp(shape.z, 0.0, 1.0), 0.0, normalize);
}

/* The point the node reads: (Vector, W) times Scale, its dimensions' components, the rest 0 */
vec4 voronoi_coord(int dims, vec3 co, float w, float scale)
{
  co *= scale;
  w *= scale;
  return dims == 1 ? vec4(w, 0.0, 0.0, 0.0) : dims == 2 ? vec4(co.xy, 0.0, 0.0) : vec4(co, dims == 4 ? w : 0.0);
}

/* F1, F2, Smooth F1: the fractal's Distance, Color, Position and W; a 1D point's distance is
 * |b - a| whatever the metric. Normalize's largest distance: the distance from the origin to
 * (0.5 + Randomness / 2) in every component, twice that for F2 (1D: without the metric). */
VoronoiTexture voronoi_texture(int dims, int feature, int metric, int cells, bool normalize, vec3 co,
                               float w, vec4 fractal, vec3 shape)
{
  metric = dims == 1 ? VORONOI_MANHATTAN : metric;
  VoronoiParams p = voronoi_params(normalize, fractal, shape);
  float half_cell = 0.5 + 0.5 * p.randomness;
  vec4 corner = vec4(0.0) - vec4(half_cell) * voronoi_lanes(dims);
  float reach = dims == 1 ? half_cell : voronoi_distance(dims, metric, corner, p);
  p.max_distance = reach * (feature == VORONOI_F2 ? 2.0 : 1.0);
  VoronoiOctave o = voronoi_fractal(dims, feature, metric, cells, p, voronoi_coord(dims, co, w, p.scale));
  vec4 position = dims == 1 ? vec4(0.0, 0.0, 0.0, o.position.x) : o.position;
  return VoronoiTexture(o.distance, vec4(o.color, 1.0), position.xyz, position.w, 0.0);
}

/* Distance to Edge: Euclidean whatever the metric; Normalize's largest distance 0.5 + Randomness / 2 */
VoronoiTexture voronoi_texture_distance_to_edge(int dims, int cells, bool normalize, vec3 co, float w,
                                                vec4 fractal, vec3 shape)
{
  VoronoiParams p = voronoi_params(normalize, fractal, shape);
  p.max_distance = 0.5 + 0.5 * p.randomness;
  float d = voronoi_fractal_distance_to_edge(dims, cells, p, voronoi_coord(dims, co, w, p.scale));
  return VoronoiTexture(d, vec4(0.0, 0.0, 0.0, 1.0), vec3(0.0), 0.0, 0.0);
}

/* N-Sphere Radius: one octave, whatever Detail */
VoronoiTexture voronoi_texture_n_sphere_radius(int dims, int cells, vec3 co, float w, vec4 fractal, vec3 shape)
{
  VoronoiParams p = voronoi_params(false, fractal, shape);
  float radius = voronoi_n_sphere_radius(dims, cells, p, voronoi_coord(dims, co, w, p.scale));
  return VoronoiTexture(0.0, vec4(0.0, 0.0, 0.0, 1.0), vec3(0.0), 0.0, radius);
}

/* The node's functions, one per feature and dimension count (textures.py's _voronoi); `metric`
 * and `cells` are the VORONOI_ constants above, `fractal` and `shape` as voronoi_params reads */
#define VORONOI_ARGS vec3 co, float w, vec4 fractal, vec3 shape, int metric, int cells, bool normalize
#define VORONOI_FRACTAL(dims, feature) voronoi_texture(dims, feature, metric, cells, normalize, co, w, fractal, shape)
VoronoiTexture node_tex_voronoi_f1_1d(VORONOI_ARGS) { return VORONOI_FRACTAL(1, VORONOI_F1); }
VoronoiTexture node_tex_voronoi_f1_2d(VORONOI_ARGS) { return VORONOI_FRACTAL(2, VORONOI_F1); }
VoronoiTexture node_tex_voronoi_f1_3d(VORONOI_ARGS) { return VORONOI_FRACTAL(3, VORONOI_F1); }
VoronoiTexture node_tex_voronoi_f1_4d(VORONOI_ARGS) { return VORONOI_FRACTAL(4, VORONOI_F1); }
VoronoiTexture node_tex_voronoi_f2_1d(VORONOI_ARGS) { return VORONOI_FRACTAL(1, VORONOI_F2); }
VoronoiTexture node_tex_voronoi_f2_2d(VORONOI_ARGS) { return VORONOI_FRACTAL(2, VORONOI_F2); }
VoronoiTexture node_tex_voronoi_f2_3d(VORONOI_ARGS) { return VORONOI_FRACTAL(3, VORONOI_F2); }
VoronoiTexture node_tex_voronoi_f2_4d(VORONOI_ARGS) { return VORONOI_FRACTAL(4, VORONOI_F2); }
VoronoiTexture node_tex_voronoi_smooth_f1_1d(VORONOI_ARGS) { return VORONOI_FRACTAL(1, VORONOI_SMOOTH_F1); }
VoronoiTexture node_tex_voronoi_smooth_f1_2d(VORONOI_ARGS) { return VORONOI_FRACTAL(2, VORONOI_SMOOTH_F1); }
VoronoiTexture node_tex_voronoi_smooth_f1_3d(VORONOI_ARGS) { return VORONOI_FRACTAL(3, VORONOI_SMOOTH_F1); }
VoronoiTexture node_tex_voronoi_smooth_f1_4d(VORONOI_ARGS) { return VORONOI_FRACTAL(4, VORONOI_SMOOTH_F1); }
#define VORONOI_EDGE(dims) voronoi_texture_distance_to_edge(dims, cells, normalize, co, w, fractal, shape)
VoronoiTexture node_tex_voronoi_distance_to_edge_1d(VORONOI_ARGS) { return VORONOI_EDGE(1); }
VoronoiTexture node_tex_voronoi_distance_to_edge_2d(VORONOI_ARGS) { return VORONOI_EDGE(2); }
VoronoiTexture node_tex_voronoi_distance_to_edge_3d(VORONOI_ARGS) { return VORONOI_EDGE(3); }
VoronoiTexture node_tex_voronoi_distance_to_edge_4d(VORONOI_ARGS) { return VORONOI_EDGE(4); }
#define VORONOI_RADIUS(dims) voronoi_texture_n_sphere_radius(dims, cells, co, w, fractal, shape)
VoronoiTexture node_tex_voronoi_n_sphere_radius_1d(VORONOI_ARGS) { return VORONOI_RADIUS(1); }
VoronoiTexture node_tex_voronoi_n_sphere_radius_2d(VORONOI_ARGS) { return VORONOI_RADIUS(2); }
VoronoiTexture node_tex_voronoi_n_sphere_radius_3d(VORONOI_ARGS) { return VORONOI_RADIUS(3); }
VoronoiTexture node_tex_voronoi_n_sphere_radius_4d(VORONOI_ARGS) { return VORONOI_RADIUS(4); }
