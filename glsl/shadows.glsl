/* Shadows: how much of a light reaches a point, read from the light's shadow maps (addon/shadows.py
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
#define SHADOW_SEARCH_TAPS 16 /* half of them for a search within 2 texels */
#define SHADOW_FILTER_TAPS 24 /* half of them for a penumbra within 3 texels */
#define SHADOW_MAX_RADIUS 48.0 /* texels */
#define SHADOW_CASCADE_ROOM 32.0 /* texels: a cascade is left this far inside its edge */

/* The cube face holding direction d (from the light), in addon/shadows.py's CUBE_FACES order. */
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

/* Where the map ray through texel position uv_texels (in texels) meets the plane (p, ng), as a
 * stored distance in metres. The ray from the layer's view and half extents (not the inverse
 * projection: with the near plane close to the light, its depth rows lose float precision). */
float shadow_plane_distance(int layer, vec2 uv_texels, vec3 p, vec3 ng)
{
  vec2 ndc = uv_texels * (2.0 / float(SL_SHADOW_SIZE)) - 1.0;
  mat4 to_world = shadow.layer_view_inverse[layer];
  vec2 extent = shadow.layer_extent[layer].xy;
  vec3 o, dir;
  if (int(shadow.layer_origin[layer].w + 0.5) != SHADOW_ORTHOGRAPHIC) { /* rays leave the light's centre */
    o = to_world[3].xyz;
    dir = normalize(mat3(to_world) * vec3(ndc * extent, -1.0));
  }
  else { /* orthographic: parallel rays from the near plane */
    o = (to_world * vec4(ndc * extent, 0.0, 1.0)).xyz;
    dir = -to_world[2].xyz;
  }
  float cosine = dot(dir, ng);
  return dot(p - o, ng) / (abs(cosine) > 1e-4 ? cosine : (cosine < 0.0 ? -1e-4 : 1e-4));
}

/* Stored distance (metres) of a texel, clamped to the map. */
float shadow_texel(int layer, ivec2 texel)
{
  texel = clamp(texel, ivec2(0), ivec2(SL_SHADOW_SIZE - 1));
  return texelFetch(shadow_maps, ivec3(texel, layer), 0).r * shadow.layer_info[layer].x;
}

/* The receiver's plane at a texel's centre, as a stored distance less the bias: a caster stored
 * nearer than this hides the light there. */
float shadow_receiver(ivec2 texel, vec2 uv_texels, float d, vec2 gradient, float bias)
{
  return d + dot(vec2(texel) + 0.5 - uv_texels, gradient) - bias;
}

/* 1 where the texel's caster is not in front of the receiver's plane there, else 0. */
float shadow_test(int layer, ivec2 texel, vec2 uv_texels, float d, vec2 gradient, float bias)
{
  return shadow_texel(layer, texel) >= shadow_receiver(texel, uv_texels, d, gradient, bias) ? 1.0 : 0.0;
}

/* Bilinear percentage-closer filter of the four texels around uv_texels. */
float shadow_bilinear(int layer, vec2 uv_texels, float d, vec2 gradient, float bias)
{
  vec2 base = uv_texels - 0.5;
  ivec2 t = ivec2(floor(base));
  vec2 f = base - floor(base);
  float v00 = shadow_test(layer, t, uv_texels, d, gradient, bias);
  float v10 = shadow_test(layer, t + ivec2(1, 0), uv_texels, d, gradient, bias);
  float v01 = shadow_test(layer, t + ivec2(0, 1), uv_texels, d, gradient, bias);
  float v11 = shadow_test(layer, t + ivec2(1, 1), uv_texels, d, gradient, bias);
  return mix(mix(v00, v10, f.x), mix(v01, v11, f.x), f.y);
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

/* Percentage-closer filter over a disc of `radius` texels (Vogel points from first_direction). */
float shadow_pcf(int layer, vec2 uv_texels, float radius, vec2 first_direction, float d, vec2 gradient,
                 float bias, int tap_scale)
{
  float lit = 0.0;
  vec2 direction = first_direction;
  int taps = (radius <= 3.0 ? SHADOW_FILTER_TAPS / 2 : SHADOW_FILTER_TAPS) * tap_scale;
  for (int k = 0; k < taps; k++) {
    vec2 at = vogel_tap(uv_texels, radius, k, taps, direction);
    lit += shadow_test(layer, ivec2(floor(at)), uv_texels, d, gradient, bias);
  }
  return lit / float(taps);
}

/* The fraction of `light` that reaches p (geometric normal ng): 1 unshadowed. */
float light_visibility(LightData light, vec3 p, vec3 ng)
{
  int first = int(light.factors.w);
  if (first < 0) {
    return 1.0;
  }
  vec3 from_light = p - light.position_kind.xyz;
  int layer = first;
  int kind = int(shadow.layer_origin[first].w + 0.5);
  if (kind == SHADOW_CUBE) {
    layer += shadow_face(from_light);
  }
  else if (kind == SHADOW_ORTHOGRAPHIC) {
    /* a sun's cascades (addon/shadows.py), finest first: the first whose map holds p with room
     * for the filter, else the last */
    int cascades = int(shadow.layer_extent[first].z + 0.5);
    for (int c = 1; c < cascades; c++) {
      vec2 at = (shadow.layer_matrix[layer] * vec4(p, 1.0)).xy;
      if (all(lessThan(abs(at), vec2(1.0 - SHADOW_CASCADE_ROOM / float(SL_SHADOW_SIZE))))) {
        break;
      }
      layer++;
    }
  }
  vec4 clip = shadow.layer_matrix[layer] * vec4(p, 1.0);
  if (clip.w <= 0.0) {
    return 1.0;
  }
  vec2 uv_texels = (clip.xy / clip.w * 0.5 + 0.5) * float(SL_SHADOW_SIZE);
  if (any(lessThan(uv_texels, vec2(0.0))) || any(greaterThan(uv_texels, vec2(SL_SHADOW_SIZE)))) {
    return 1.0; /* outside the map: nothing was drawn there to cast */
  }
  vec4 info = shadow.layer_info[layer];
  bool ortho = kind == SHADOW_ORTHOGRAPHIC;
  float d = ortho ? dot(p - shadow.layer_origin[layer].xyz, light.direction_cone.xyz) : length(from_light);
  float texel = ortho ? info.y : info.y * d; /* a texel's width at the receiver (m) */
  /* the receiver's plane: its distance's change per texel, limited to 64 texels (89 degrees from
   * the light: a limit much lower predicts a steep plane too close to the light on one side of the
   * point and shadows a lit convex surface there) */
  vec2 gradient = vec2(shadow_plane_distance(layer, uv_texels + vec2(1.0, 0.0), p, ng),
                       shadow_plane_distance(layer, uv_texels + vec2(0.0, 1.0), p, ng)) -
                  shadow_plane_distance(layer, uv_texels, p, ng);
  gradient = clamp(gradient, vec2(-64.0 * texel), vec2(64.0 * texel));
  float bias = 0.5 * texel + 1e-5 * d;
  /* the light's Filter (texels) and Resolution Limit (the smallest texel, m): the narrowest filter */
  float filter_code = shadow.layer_extent[layer].w; /* -(Filter + 1) with Jitter: twice the taps */
  int tap_scale = filter_code < 0.0 ? 2 : 1;
  float filter_radius = min(max(filter_code < 0.0 ? -filter_code - 1.0 : filter_code, info.w / texel),
                            SHADOW_MAX_RADIUS);
#ifdef SL_SOFT_SHADOWS
  float size = info.z;
  if (size > 0.0) {
    vec2 first_direction = shadow_first_direction();
    /* blocker search: casters between the receiver and a quarter of its distance (the sun: the
     * map's top) that hide some of the light */
    float search = ortho ? d * size / texel : 3.0 * size / info.y / d;
    search = clamp(search, 1.0, SHADOW_MAX_RADIUS);
    float blockers = 0.0;
    float blocker_sum = 0.0;
    vec2 direction = first_direction;
    /* a search a few texels wide needs fewer taps (half of them within 2 texels) */
    int taps = (search <= 2.0 ? SHADOW_SEARCH_TAPS / 2 : SHADOW_SEARCH_TAPS) * tap_scale;
    for (int k = 0; k < taps; k++) {
      ivec2 t = ivec2(floor(vogel_tap(uv_texels, search, k, taps, direction)));
      float stored = shadow_texel(layer, t);
      if (stored < shadow_receiver(t, uv_texels, d, gradient, bias)) {
        blockers += 1.0;
        blocker_sum += stored;
      }
    }
    if (blockers == 0.0) {
      return 1.0;
    }
    float d_blocker = max(blocker_sum / blockers, 1e-4);
    float penumbra = ortho ? (d - d_blocker) * size : size * (d - d_blocker) / d_blocker;
    float radius = min(max(max(penumbra, 0.0) / texel, filter_radius), SHADOW_MAX_RADIUS);
    if (radius > 1.0) {
      return shadow_pcf(layer, uv_texels, radius, first_direction, d, gradient, bias, tap_scale);
    }
  }
#endif
  if (filter_radius > 1.0) {
    return shadow_pcf(layer, uv_texels, filter_radius, shadow_first_direction(), d, gradient, bias,
                      tap_scale);
  }
  return shadow_bilinear(layer, uv_texels, d, gradient, bias);
}

#endif
