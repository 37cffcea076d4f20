/* Ground-truth ambient occlusion (Jimenez, Wu, Pesce & Jarabo 2016, "Practical Real-Time
 * Strategies for Accurate Indirect Occlusion") with occluders of measured thickness (a visibility
 * bitmask, Therrien, Levesque & Gilet 2023, "Screen Space Indirect Lighting with Visibility
 * Bitmask"). For SL_DIRECTIONS slices through the view vector, SL_STEPS samples on each side (out
 * to the occlusion distance) each occlude the arc of the slice between their front surface and
 * their back surface: the nearest surface by which the ray leaves the object (a prepass of the
 * faces turned away), or, where there is none (a floor, an open surface, a face seen from inside),
 * everything behind the front (the classic horizon). The arc's sectors, SL_SECTORS across the
 * normal's hemisphere, are marked occluded; the cosine-weighted visible part is integrated in
 * closed form per run of visible sectors (Jimenez et al.'s eq. 10), weighted by the normal's
 * length in the slice and averaged over the slices (their eq. 3). The result is the fraction of
 * the world's light a Lambertian surface still receives, for a uniform world what Cycles'
 * occluded world light gives where the occluders are on screen. No multiple-bounce term: Cycles
 * is compared with direct light only. Beside it, the bent normal: the cosine-weighted mean of
 * the visible directions (the same integrals with the direction inside), which says from where
 * the unoccluded light comes (the normal itself where nothing occludes).
 *
 * Interleaved (Keller & Heidrich 2001, "Interleaved Sampling"; as in GTAO's spatial denoiser):
 * each pixel of a 2 x 2 block traces SL_DIRECTIONS / 4 of the slices (its class c = x mod 2 +
 * 2 (y mod 2) takes slices c, c + 4, ...: perpendicular ones), and glsl/occlusion_resolve.frag.glsl
 * merges each pixel's 3 x 3 neighbourhood with tent weights, which give the four classes equal
 * weight: every pixel ends with all SL_DIRECTIONS slices, a quarter of the tracing. At half
 * resolution (SL_OCCLUSION_SCALE 2, glsl/occlusion.glsl's traced_texel) the pattern runs over the
 * cells of the trace, each tracing one of its 2 x 2 pixels, and the resolve merges the 2 x 2 cells
 * nearest a pixel (equally: one of each class): a sixteenth of the full-resolution trace.
 * The visibility is a ratio: the slices' cosine-weighted visible arcs over what the same slices
 * give with nothing occluded (cos n + n sin n each, weighted alike), so a few slices estimate it
 * without bias where nothing occludes (2 slices alone are off by up to 2 % of the hemisphere's
 * cosine), and the resolve merges numerators and denominators.
 * Output: xyz the world-space bent normal's unnormalised sum over the pixel's slices, w both
 * sums of the ratio as two halves (packHalf2x16: visible, unoccluded) in an RGBA32F texel; cell_data:
 * the traced pixel's world normal (xyz, normal_map's) and view depth (w, depths' x), which the resolve
 * reads for each of its neighbours in one texel instead of two.
 *
 * occlusion: inverse_projection, projection, view (world -> view rotation), params: x = the
 * occlusion distance in world units, y = 1 perspective / 0 orthographic, zw = target size.
 * normal_map: world normal; depths: view depths, x the nearest surface's, y where the ray leaves
 * its object, SKY_Z where unknown (glsl/occlusion_depths.frag.glsl). */

/* A surface occluding within HORIZON_BIAS of the point's own tangent plane is the surface itself,
 * facetted and quantised (a convex sphere would otherwise occlude itself at its rim). */
#define HORIZON_BIAS 0.1 /* radians */
#define SL_SECTORS 32

/* acos to within 7e-5 radians, a fraction of a sector (Abramowitz & Stegun 4.4.45): the
 * occlusion pass takes two per sample. */
float acos_fast(float x)
{
  float a = abs(clamp(x, -1.0, 1.0));
  float r = sqrt(1.0 - a) * (1.5707288 + a * (-0.2121144 + a * (0.0742610 - 0.0187293 * a)));
  return x < 0.0 ? PI - r : r;
}

/* The cosine-weighted integral of the slice from its view direction (h = 0) to the signed angle
 * h, for the normal's angle n in the slice: sign(h) int_0^|h| cos(t - n) |sin t| dt (the
 * antiderivative of Jimenez et al.'s eq. 10; 1 across the whole hemisphere when n = 0). */
float slice_integral(float h, float n)
{
  return sign(h) * 0.25 * (-cos(2.0 * h - n) + cos(n) + 2.0 * h * sin(n));
}

/* The cosine-weighted integral of the direction itself, as (view-vector, slice-direction)
 * components: sign(h) int_0^|h| (cos t, sin t) cos(t - n) |sin t| dt. */
vec2 slice_direction_integral(float h, float n)
{
  float c = cos(h), s = sin(h), cn = cos(n), sn = sin(n);
  vec2 g = vec2(-cn * c * c * c + sn * s * s * s, cn * s * s * s + sn * (c * c * c - 3.0 * c)) / 3.0;
  vec2 g0 = vec2(-cn, -2.0 * sn) / 3.0;
  return sign(h) * (g - g0);
}

/* Sectors [first, last) of the hemisphere [n - pi/2, n + pi/2] covering signed angles [a, b]. */
uint sector_mask(float a, float b, float n)
{
  float lo = clamp((a - n) / PI + 0.5, 0.0, 1.0);
  float hi = clamp((b - n) / PI + 0.5, 0.0, 1.0);
  int first = int(floor(lo * float(SL_SECTORS) + 0.5));
  int last = int(floor(hi * float(SL_SECTORS) + 0.5));
  if (last <= first) {
    return 0u;
  }
  uint below_last = last >= 32 ? 0xFFFFFFFFu : (1u << uint(last)) - 1u;
  uint below_first = (1u << uint(first)) - 1u;
  return below_last & ~below_first;
}

void main()
{
  vec2 size = occlusion.params.zw;
  ivec2 cell = ivec2(gl_FragCoord.xy);
  ivec2 texel = traced_texel(cell);
  vec2 uv = (vec2(texel) + 0.5) / size;
  float z = texelFetch(depths, texel, 0).r;
  vec3 world_normal = texelFetch(normal_map, texel, 0).xyz;
  cell_data = vec4(world_normal, z);
  if (z >= 0.0) {
    frag_color = vec4(0.0); /* the sky: nothing to occlude (the resolve leaves it out) */
    return;
  }
  vec3 P = view_at(uv * 2.0 - 1.0, z);
  vec3 V = occlusion.params.y > 0.5 ? normalize(-P) : vec3(0.0, 0.0, 1.0);
  vec3 N = normalize(mat3(occlusion.view) * world_normal);
  /* the occlusion distance on screen, in uv units, at this point's depth */
  vec4 edge = occlusion.projection * vec4(P + vec3(occlusion.params.x, 0.0, 0.0), 1.0);
  vec4 centre = occlusion.projection * vec4(P, 1.0);
  float radius_uv = abs(edge.x / edge.w - centre.x / centre.w) * 0.5;
  float visibility = 0.0, unoccluded = 0.0;
  vec3 bent = vec3(0.0);
  int pattern = (cell.x & 1) + 2 * (cell.y & 1);
  /* the loops test at their end (glsl/README.md): tested at the top, each ran its body once more,
   * masked (the trace 15.3 -> 13.3 ms at 640x360) */
  int i = pattern;
  do {
    float phi = PI * (float(i) + 0.5) / float(SL_DIRECTIONS);
    vec2 dir = vec2(cos(phi), sin(phi));
    vec3 slice_dir = vec3(dir, 0.0);
    vec3 axis = normalize(cross(slice_dir, V));
    vec3 n_proj = N - axis * dot(N, axis);
    float proj_len = length(n_proj);
    if (proj_len < 1e-6) {
      continue; /* the normal is perpendicular to the slice: it weighs nothing */
    }
    vec3 ortho = normalize(slice_dir - V * dot(slice_dir, V));
    float cos_n = clamp(dot(n_proj, V) / proj_len, -1.0, 1.0);
    float n = (dot(ortho, n_proj) < 0.0 ? -1.0 : 1.0) * acos_accurate(cos_n);
    uint occluded = 0u;
    int side = 0;
    do {
      float s = side == 0 ? -1.0 : 1.0;
      int j = 0;
      do {
        float t = (float(j) + 0.5) / float(SL_STEPS);
        t *= t; /* denser near the point, where occluders subtend most */
        /* at least two texels out: the next texel is the same surface, its depth quantised */
        vec2 step_uv = max(t * radius_uv * size.x, 2.0) / size;
        vec2 suv = uv + s * dir * step_uv;
        if (any(lessThan(suv, vec2(0.0))) || any(greaterThan(suv, vec2(1.0)))) {
          break; /* off screen: nothing known there, nothing occludes */
        }
        ivec2 stexel = ivec2(suv * size);
        vec2 sndc = (vec2(stexel) + 0.5) * (2.0 / size) - 1.0;
        vec2 pair = texelFetch(depths, stexel, 0).rg; /* view depths: front, back */
        if (pair.x >= 0.0) {
          continue; /* the sky */
        }
        vec3 F = view_at(sndc, pair.x);
        vec3 H = F - P;
        float dist = length(H);
        if (dist < 1e-6 || dist > occlusion.params.x) {
          continue; /* beyond the occlusion distance: does not occlude */
        }
        float front = acos_fast(dot(H / dist, V));
        float back = PI; /* everything behind the front surface */
        if (pair.y < 0.0) {
          /* the same pixel's ray, further */
          back = acos_fast(dot(normalize(view_at(sndc, pair.y) - P), V));
        }
        front += HORIZON_BIAS;
        back = max(back + HORIZON_BIAS, front);
        /* one mask a sample (the side's arc mirrored), not one of two chosen between, which
         * the compiled loop computed both of (the trace 4-5 % faster) */
        occluded |= sector_mask(s * (side == 0 ? back : front), s * (side == 0 ? front : back), n);
      } while (++j < SL_STEPS);
    } while (++side < 2);
    /* integrate the runs of visible sectors */
    uint visible = ~occluded;
    float arc = 0.0;
    vec2 mean = vec2(0.0);
    if (visible != 0u) {
      do { /* tested at the end: glsl/README.md */
        int first = findLSB(visible);
        uint rest = ~visible & ~((1u << uint(first)) - 1u);
        int last = rest == 0u ? 32 : findLSB(rest);
        float a = n + PI * (float(first) / float(SL_SECTORS) - 0.5);
        float b = n + PI * (float(last) / float(SL_SECTORS) - 0.5);
        arc += slice_integral(b, n) - slice_integral(a, n);
        mean += slice_direction_integral(b, n) - slice_direction_integral(a, n);
        visible = last >= 32 ? 0u : visible & ~((1u << uint(last)) - 1u);
      } while (visible != 0u);
    }
    visibility += proj_len * arc;
    unoccluded += proj_len * (cos(n) + n * sin(n)); /* the arc over [n - pi/2, n + pi/2] */
    bent += proj_len * (mean.x * V + mean.y * ortho);
  } while ((i += 4) < SL_DIRECTIONS);
  /* the bent normal's sum in world space (view is a rotation: its transpose inverts it) */
  frag_color = vec4(transpose(mat3(occlusion.view)) * bent,
                    uintBitsToFloat(packHalf2x16(vec2(visibility, unoccluded))));
}
