/* Shadows: how much of a light reaches a point, read from the light's shadow maps (addon/plan/shadows.py
 * plans the layers, passes.ShadowPass draws them, glsl/shadow.frag.glsl stores distances).
 *
 * Each map texel holds the distance to the nearest caster along its ray, from the light's centre
 * (perspective and cube layers) or from the map's near plane (orthographic), over the layer's far
 * distance. A receiver is compared with the texels around it as the plane through it (its
 * geometric normal) would be at each texel's centre (receiver-plane depth bias): a flat lit surface
 * is never behind itself, whatever its slope, so no acne and only a small constant bias.
 *
 * Penumbrae (soft shadows) by percentage-closer soft shadows (Fernando 2005): the casters' mean
 * distance d_b found around the receiver, then the light's size R projected through them onto
 * the receiver at distance d, w = R (d - d_b) / d_b (a sun: w = (d - d_b) tan(angle / 2)), sets
 * the filter's radius. Without a size, a bilinear filter over one texel. */

#ifdef SL_SHADOWS

#define SHADOW_CUBE 0
#define SHADOW_PERSPECTIVE 1
#define SHADOW_ORTHOGRAPHIC 2
/* half of them for a search within 2 texels; 8, not 16: softbox's shading 0.89x, its FLIP against
 * Cycles 0.0343 either way, the penumbra tests' errors within 3 % (tests/test_shadows.py) */
#define SHADOW_SEARCH_TAPS 8
#define SHADOW_FILTER_TAPS 24 /* half of them for a penumbra within 3 texels */
#define SHADOW_MAX_RADIUS 48.0 /* texels (addon/plan/shadows.py LOOKUP_REACH: it and a tap's texel) */
#define SHADOW_CASCADE_ROOM 32.0 /* texels: a cascade is left this far inside its edge */

/* The cube face holding direction d (from the light), in addon/plan/shadows.py's CUBE_FACES order. */
int shadow_face(vec3 d)
{
  vec3 a = abs(d);
  if (a.x >= a.y && a.x >= a.z) {
    return d.x > 0.0 ? 0 : 1;
  }
  if (a.y >= a.z) {
    return d.y > 0.0 ? 2 : 3;
  }
  return d.z > 0.0 ? 4 : 5;
}

/* Where the map ray through texel position uv_texels (in texels) meets the receiver's plane, as
 * a stored distance in metres, for a layer seen from a point (`tan_half` its projection's half
 * extent): the ray from the view and half extent, not the inverse projection (with the near plane
 * close to the light, its depth rows lose float precision). The ray r = (ndc tan_half, -1) in
 * the layer's view and the plane's normal in that view, n_view: the ray's cosine with the plane
 * dot(r, n_view) / |r|, no rotation per ray; plane_offset the plane's distance from the point
 * along its normal. */
float shadow_plane_distance(vec2 uv_texels, float tan_half, vec3 n_view, float plane_offset)
{
  vec3 r = vec3((uv_texels * (2.0 / float(SL_SHADOW_SIZE)) - 1.0) * tan_half, -1.0);
  float cosine = dot(r, n_view) * inversesqrt(dot(r, r));
  return plane_offset / (abs(cosine) > 1e-4 ? cosine : (cosine < 0.0 ? -1e-4 : 1e-4));
}

/* The receiver's plane (p, ng) at the texels right of and above uv_texels, less at uv_texels
 * (stored metres per texel), for a layer seen from o (`to_world`: the layer's view -> world
 * rotation; shadow_plane_distance). A cube's faces give to_world without reading it
 * (cube_face_view). */
vec2 perspective_gradient(mat3 to_world, vec3 o, float tan_half, vec2 uv_texels, vec3 p, vec3 ng)
{
  vec3 n_view = ng * to_world;
  float plane_offset = dot(p - o, ng);
  float at = shadow_plane_distance(uv_texels, tan_half, n_view, plane_offset);
  return vec2(shadow_plane_distance(uv_texels + vec2(1.0, 0.0), tan_half, n_view, plane_offset),
              shadow_plane_distance(uv_texels + vec2(0.0, 1.0), tan_half, n_view, plane_offset)) - at;
}

/* Where a receiver falls in a light's shadow map: the layer and texel position, its stored
 * distance, the receiver's plane (stored metres per texel), the bias, and the layer's far
 * distance and info (glsl/uniforms.glsl). */
struct ShadowPoint {
  int layer;
  vec2 uv_texels;
  float d;
  vec2 gradient;
  float bias;
  vec4 info;
};

/* Stored distance (metres) of a texel, clamped to the map: sampled at the texel's centre, where
 * any filter returns the texel itself. Not texelFetch: the CPU rasteriser's code for it loaded
 * per-lane offsets before each fetch of the array texture, and the blocker search's reads (16 a
 * light then) were the hottest code of a softbox frame (perf); sampling took 2-3 % off its shading
 * (fenced minima over 20-25 draws, three runs; the same image bit for bit). */
float shadow_texel(ShadowPoint q, ivec2 texel)
{
  texel = clamp(texel, ivec2(0), ivec2(SL_SHADOW_SIZE - 1));
  vec2 centre = (vec2(texel) + 0.5) * (1.0 / float(SL_SHADOW_SIZE));
  return textureLod(shadow_maps, vec3(centre, float(q.layer)), 0.0).r * q.info.x;
}

/* The receiver's plane at a texel's centre, as a stored distance less the bias: a caster stored
 * nearer than this hides the light there. */
float shadow_receiver(ShadowPoint q, ivec2 texel)
{
  return q.d + dot(vec2(texel) + 0.5 - q.uv_texels, q.gradient) - q.bias;
}

/* The stored distances (metres) of the 2 x 2 texels from t, in textureGather's order: (0, 1),
 * (1, 1), (1, 0), (0, 0) from t; clamped to the map as shadow_texel (the gather's coordinate is
 * the four texels' shared corner, so the block is t's whatever the rounding). */
vec4 shadow_gather(ShadowPoint q, ivec2 t)
{
  return textureGather(shadow_maps, vec3((vec2(t) + 1.0) / float(SL_SHADOW_SIZE), float(q.layer)), 0) *
         q.info.x;
}

/* shadow_receiver at the same four texels. */
vec4 shadow_receivers(ShadowPoint q, ivec2 t)
{
  return shadow_receiver(q, t) + vec4(q.gradient.y, q.gradient.x + q.gradient.y, q.gradient.x, 0.0);
}

/* Bilinear percentage-closer filter of the four texels around position `at` (texels): 1 where
 * no caster is in front of the receiver's plane. */
float shadow_bilinear_at(ShadowPoint q, vec2 at)
{
  vec2 base = at - 0.5;
  ivec2 t = ivec2(floor(base));
  vec2 f = base - vec2(t);
  vec4 v = vec4(greaterThanEqual(shadow_gather(q, t), shadow_receivers(q, t)));
  return mix(mix(v.w, v.z, f.x), mix(v.x, v.y, f.x), f.y);
}

/* Vogel (golden-angle) disc points, k = 0, 1, ...: radius sqrt((k + 0.5) / n), each turned from
 * the last by the golden angle (a fixed rotation: no sine or cosine per tap). */
const mat2 GOLDEN_TURN = mat2(-0.7373688, 0.6754903, -0.6754903, -0.7373688);

/* The first Vogel point's direction, turned per pixel (interleaved gradient noise). */
vec2 shadow_first_direction()
{
  float turn = 6.2831853 * fract(52.9829189 * fract(dot(gl_FragCoord.xy, vec2(0.06711056, 0.00583715))));
  return vec2(cos(turn), sin(turn));
}

/* Vogel point k of `taps` over a disc of `radius` texels about `centre`, from `direction`, which
 * it turns on to the next point's (the blocker search and the filter share the pattern). */
vec2 vogel_tap(vec2 centre, float radius, int k, int taps, inout vec2 direction)
{
  vec2 at = centre + (radius * sqrt((float(k) + 0.5) / float(taps))) * direction;
  direction = GOLDEN_TURN * direction;
  return at;
}

/* Percentage-closer filter over a disc of `radius` texels (Vogel points from first_direction),
 * each tap a bilinear filter of the four texels around it (one gather): a tap's test is
 * continuous in its position, and on the CPU rasteriser a gather costs what one texel's read did
 * (measured: the same frame time on softbox; penumbrae against Cycles' 9 % closer). A radius
 * within a texel: one bilinear tap at the point. */
float shadow_pcf(ShadowPoint q, float radius, vec2 first_direction, int tap_scale)
{
  float lit = 0.0;
  vec2 direction = first_direction;
  int taps = (radius <= 3.0 ? SHADOW_FILTER_TAPS / 2 : SHADOW_FILTER_TAPS) * tap_scale;
  if (radius <= 1.0) {
    taps = 1;
    radius = 0.0;
  }
  int k = 0;
  do { /* tested at the end: glsl/README.md */
    lit += shadow_bilinear_at(q, vogel_tap(q.uv_texels, radius, k, taps, direction));
  } while (++k < taps);
  return lit / float(taps);
}

/* The kind of a light's maps: a sun's are orthographic, a point or area light's a cube's
 * (addon/plan/shadows.py); a spot's follow its cone. A constant where the light's kind is one (the
 * light loop's groups), so each path below is compiled only where a light can take it: reading a
 * layer's data is a per-pixel gather on the software rasteriser (glsl/README.md), and the paths
 * of suns and cube faces read a few values instead of the layer's matrices. */
int shadow_kind(LightData light, int first)
{
  int kind = int(light.position_kind.w);
  if (kind == LIGHT_SUN) {
    return SHADOW_ORTHOGRAPHIC;
  }
  if (kind == LIGHT_SPOT) {
    return int(shadow.layer_origin[first].w + 0.5);
  }
  return SHADOW_CUBE;
}

/* A cube face's view -> world rotation: its columns the face's right, up and backward axes, as
 * addon/plan/shadows.py's look_at makes them from CUBE_FACES (the face looking along +-axis, up -y,
 * but +z for +y and -z for -y). */
mat3 cube_face_view(int face)
{
  int axis = face / 2;
  float sign = (face & 1) == 0 ? 1.0 : -1.0;
  vec3 forward = vec3(0.0);
  forward[axis] = sign;
  vec3 up = axis == 1 ? vec3(0.0, 0.0, sign) : vec3(0.0, -1.0, 0.0);
  vec3 right = cross(forward, up);
  return mat3(right, cross(right, forward), -forward);
}

/* The point p on its cube face (light at `position`): false where it is outside the map. */
bool cube_shadow_point(int first, vec3 position, vec3 p, vec3 ng, out ShadowPoint q)
{
  vec3 from_light = p - position;
  int face = shadow_face(from_light);
  mat3 to_world = cube_face_view(face);
  vec3 local = from_light * to_world; /* the face's view coordinates */
  float tan_half = shadow.layer_extent[first].x; /* every face's projection is the first's */
  q.layer = first + face;
  q.info = shadow.layer_info[first];
  q.uv_texels = (local.xy / (-local.z * tan_half) * 0.5 + 0.5) * float(SL_SHADOW_SIZE);
  q.d = length(from_light);
  q.gradient = perspective_gradient(to_world, position, tan_half, q.uv_texels, p, ng);
  return -local.z > 0.0;
}

/* The point p in a sun's maps (`direction` the light's): its cascades (addon/plan/shadows.py) share
 * one rotation, so p's coordinates across the light are taken once and each cascade's fit
 * (glsl/uniforms.glsl's layer_fit) and half extents place them; the finest cascade whose map
 * holds p with room for the filter, else the last. The receiver's plane in closed form: the rays
 * are parallel, a texel's step moves the ray's origin by the map's half extent / (size / 2). */
bool sun_shadow_point(int first, vec3 direction, vec3 p, vec3 ng, out ShadowPoint q)
{
  mat4 axes = shadow.layer_view_inverse[first]; /* columns: right, up (every cascade's) */
  vec3 right = axes[0].xyz;
  vec3 up = axes[1].xyz;
  vec2 across = vec2(dot(right, p), dot(up, p));
  q.layer = first;
  vec4 fit = shadow.layer_fit[first];
  vec2 half_extent = shadow.layer_extent[first].xy;
  vec2 at = (across - fit.xy) / half_extent;
  int cascades = int(shadow.layer_extent[first].z + 0.5);
  if (cascades > 1) {
    int c = 1;
    do { /* tested at the end: glsl/README.md */
      if (all(lessThan(abs(at), vec2(1.0 - SHADOW_CASCADE_ROOM / float(SL_SHADOW_SIZE))))) {
        break;
      }
      q.layer++;
      fit = shadow.layer_fit[q.layer];
      half_extent = shadow.layer_extent[q.layer].xy;
      at = (across - fit.xy) / half_extent;
    } while (++c < cascades);
  }
  q.info = shadow.layer_info[q.layer];
  q.uv_texels = (at * 0.5 + 0.5) * float(SL_SHADOW_SIZE);
  q.d = dot(p, direction) - fit.z;
  float cosine = dot(direction, ng);
  cosine = abs(cosine) > 1e-4 ? cosine : (cosine < 0.0 ? -1e-4 : 1e-4);
  q.gradient = -(2.0 / float(SL_SHADOW_SIZE)) * half_extent * vec2(dot(right, ng), dot(up, ng)) / cosine;
  return true;
}

/* The point p in a spot's one perspective map (its layer's matrices). */
bool spot_shadow_point(int first, vec3 position, vec3 p, vec3 ng, out ShadowPoint q)
{
  vec4 clip = shadow.layer_matrix[first] * vec4(p, 1.0);
  float tan_half = shadow.layer_extent[first].x;
  q.layer = first;
  q.info = shadow.layer_info[first];
  q.uv_texels = (clip.xy / clip.w * 0.5 + 0.5) * float(SL_SHADOW_SIZE);
  q.d = length(p - position);
  q.gradient = perspective_gradient(mat3(shadow.layer_view_inverse[first]), position, tan_half,
                                    q.uv_texels, p, ng);
  return clip.w > 0.0;
}

/* The fraction of `light` that reaches p (geometric normal ng): 1 unshadowed. */
float light_visibility(LightData light, vec3 p, vec3 ng)
{
  int first = int(light.factors.w);
  if (first < 0) {
    return 1.0;
  }
  int kind = shadow_kind(light, first);
  ShadowPoint q;
  bool ahead;
  if (kind == SHADOW_ORTHOGRAPHIC) {
    ahead = sun_shadow_point(first, light.direction_cone.xyz, p, ng, q);
  }
  else if (kind == SHADOW_CUBE) {
    ahead = cube_shadow_point(first, light.position_kind.xyz, p, ng, q);
  }
  else {
    ahead = spot_shadow_point(first, light.position_kind.xyz, p, ng, q);
  }
  if (!ahead || any(lessThan(q.uv_texels, vec2(0.0))) ||
      any(greaterThan(q.uv_texels, vec2(SL_SHADOW_SIZE))))
  {
    return 1.0; /* outside the map: nothing was drawn there to cast */
  }
  bool ortho = kind == SHADOW_ORTHOGRAPHIC;
  float texel = ortho ? q.info.y : q.info.y * q.d; /* a texel's width at the receiver (m) */
  /* the receiver's plane limited to 64 texels (89 degrees from the light: a limit much lower
   * predicts a steep plane too close to the light on one side of the point and shadows a lit
   * convex surface there) */
  q.gradient = clamp(q.gradient, vec2(-64.0 * texel), vec2(64.0 * texel));
  q.bias = 0.5 * texel + 1e-5 * q.d;
  /* the light's Filter (texels) and Resolution Limit (the smallest texel, m): the narrowest filter */
  float filter_code = shadow.layer_extent[first].w; /* -(Filter + 1) with Jitter: twice the taps */
  int tap_scale = filter_code < 0.0 ? 2 : 1;
  float filter_radius = min(max(filter_code < 0.0 ? -filter_code - 1.0 : filter_code, q.info.w / texel),
                            SHADOW_MAX_RADIUS);
  /* one filter for every path, so the program holds one copy of its loop (each copy ran at least
   * once, its lanes masked: glsl/README.md): softbox's shading 0.96x, the same images bit for bit */
  float radius = filter_radius;
  vec2 first_direction = shadow_first_direction();
#ifdef SL_SOFT_SHADOWS
  float size = q.info.z;
  if (size > 0.0) {
    /* blocker search: casters between the receiver and a quarter of its distance (the sun: the
     * map's top) that hide some of the light */
    float search = ortho ? q.d * size / texel : 3.0 * size / q.info.y / q.d;
    search = clamp(search, 1.0, SHADOW_MAX_RADIUS);
    float blockers = 0.0;
    float blocker_sum = 0.0;
    vec2 direction = first_direction;
    /* a search a few texels wide needs fewer taps (half of them within 2 texels) */
    int taps = (search <= 2.0 ? SHADOW_SEARCH_TAPS / 2 : SHADOW_SEARCH_TAPS) * tap_scale;
    int k = 0;
    do { /* tested at the end: glsl/README.md */
      ivec2 t = ivec2(floor(vogel_tap(q.uv_texels, search, k, taps, direction)));
      float stored = shadow_texel(q, t);
      if (stored < shadow_receiver(q, t)) {
        blockers += 1.0;
        blocker_sum += stored;
      }
    } while (++k < taps);
    if (blockers == 0.0) {
      return 1.0;
    }
    float d_blocker = max(blocker_sum / blockers, 1e-4);
    float penumbra = ortho ? (q.d - d_blocker) * size : size * (q.d - d_blocker) / d_blocker;
    radius = min(max(max(penumbra, 0.0) / texel, filter_radius), SHADOW_MAX_RADIUS);
  }
#endif
  return shadow_pcf(q, radius, first_direction, tap_scale);
}

#endif
