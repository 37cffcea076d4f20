/* Ground-truth ambient occlusion (Jimenez, Wu, Pesce & Jarabo 2016, "Practical Real-Time
 * Strategies for Accurate Indirect Occlusion"): for SL_DIRECTIONS slices through the view
 * vector, the two horizons are searched in screen space (SL_STEPS samples each, out to the
 * occlusion distance), clamped to the hemisphere of the normal projected into the slice, and
 * the cosine-weighted visible arc integrated in closed form (their eq. 10). The result is the
 * fraction of the world's light a Lambertian surface still receives, for a uniform world
 * exactly what Cycles' occluded world light gives where the occluders are on screen. No
 * multiple-bounce term: Cycles is compared with direct light only.
 *
 * occlusion: inverse_projection, projection, view (world -> view rotation), params: x = the
 * occlusion distance in world units, y = 1 perspective / 0 orthographic, zw = target size. */

/* The view-space position of the surface at a texel (its centre; depth nearest, not blended). */
#define HORIZON_BIAS 0.1 /* radians */

vec3 view_position(ivec2 texel, vec2 size)
{
  float d = texelFetch(depth_map, texel, 0).r;
  vec2 uv = (vec2(texel) + 0.5) / size;
  vec4 p = occlusion.inverse_projection * vec4(uv * 2.0 - 1.0, d * 2.0 - 1.0, 1.0);
  return p.xyz / p.w;
}

void main()
{
  vec2 size = occlusion.params.zw;
  ivec2 texel = ivec2(gl_FragCoord.xy);
  vec2 uv = gl_FragCoord.xy / size;
  float depth = texelFetch(depth_map, texel, 0).r;
  if (depth >= 1.0) {
    frag_color = vec4(1.0);  /* the sky: nothing to occlude */
    return;
  }
  vec3 P = view_position(texel, size);
  vec3 V = occlusion.params.y > 0.5 ? normalize(-P) : vec3(0.0, 0.0, 1.0);
  vec3 N = normalize(mat3(occlusion.view) * texelFetch(normal_map, texel, 0).xyz);
  /* the occlusion distance on screen, in uv units, at this point's depth */
  vec4 edge = occlusion.projection * vec4(P + vec3(occlusion.params.x, 0.0, 0.0), 1.0);
  vec4 centre = occlusion.projection * vec4(P, 1.0);
  float radius_uv = abs(edge.x / edge.w - centre.x / centre.w) * 0.5;
  float visibility = 0.0;
  float weight = 0.0;
  for (int i = 0; i < SL_DIRECTIONS; i++) {
    float phi = PI * (float(i) + 0.5) / float(SL_DIRECTIONS);
    vec2 dir = vec2(cos(phi), sin(phi));
    vec3 slice_dir = vec3(dir, 0.0);
    vec3 axis = normalize(cross(slice_dir, V));
    vec3 n_proj = N - axis * dot(N, axis);
    float proj_len = length(n_proj);
    if (proj_len < 1e-6) {
      continue;
    }
    vec3 ortho = slice_dir - V * dot(slice_dir, V);
    float cos_n = clamp(dot(n_proj, V) / proj_len, -1.0, 1.0);
    float n = (dot(ortho, n_proj) < 0.0 ? -1.0 : 1.0) * acos_accurate(cos_n);
    float h[2];
    for (int side = 0; side < 2; side++) {
      float s = side == 0 ? -1.0 : 1.0;
      float best = -1.0;
      for (int j = 0; j < SL_STEPS; j++) {
        float t = (float(j) + 0.5) / float(SL_STEPS);
        /* at least two texels out: the next texel is the same surface, its depth quantised */
        vec2 step_uv = max(t * radius_uv * size.x, 2.0) / size;
        vec2 suv = uv + s * dir * step_uv;
        if (any(lessThan(suv, vec2(0.0))) || any(greaterThan(suv, vec2(1.0)))) {
          break;  /* off screen: nothing known there, nothing occludes */
        }
        vec3 H = view_position(ivec2(suv * size), size) - P;
        float dist = length(H);
        if (dist < 1e-6 || dist > occlusion.params.x) {
          continue;  /* beyond the occlusion distance: does not occlude */
        }
        best = max(best, dot(H / dist, V));
      }
      /* a horizon within HORIZON_BIAS of the surface's own tangent plane is the surface itself,
       * facetted and quantised (a convex sphere would otherwise occlude itself at its rim) */
      float angle = acos_accurate(best) + HORIZON_BIAS;
      h[side] = side == 0 ? n + max(-angle - n, -0.5 * PI) : n + min(angle - n, 0.5 * PI);
    }
    float arc = -cos(2.0 * h[0] - n) + cos(n) + 2.0 * h[0] * sin(n) +
                -cos(2.0 * h[1] - n) + cos(n) + 2.0 * h[1] * sin(n);
    visibility += proj_len * 0.25 * arc;
    weight += proj_len;
  }
  frag_color = vec4(vec3(weight > 0.0 ? clamp(visibility / weight, 0.0, 1.0) : 1.0), 1.0);
}
