"""The numpy twin of the pattern textures: Gradient, Checker, Magic and Brick
(``glsl/node_tex_gradient.glsl``, ``node_tex_checker.glsl``, ``node_tex_magic.glsl``,
``node_tex_brick.glsl``) and Radial Tiling (``node_tex_radial_tiling.glsl``). Vectorised over
coordinates (..., 3); float32 throughout, operation for operation as Cycles' CPU kernel computes
them (intern/cycles/kernel/svm/gradient.h, checker.h, magic.h, brick.h, radial_tiling_shared.h).

Cycles' CPU kernels are compiled with fast math and, on a CPU with FMA (its AVX2 kernel), the
compiler fuses some products into the sum that uses them (a * b + c rounded once) and divides by
a constant, or by one divisor three times, through its reciprocal. Which ones is the compiler's
choice: each ``fma`` here was found against Cycles 5.0's renders (tests/test_texture_patterns.py:
undone, it fails a case; a few the cases cannot tell apart are written as their siblings), as
were the products it does not fuse. The same roundings give the same bits. Sines, cosines and
arc tangents are C's (the platform's libm: sinf, cosf, atan2f ... through ctypes, as Cycles calls
them); where no C library is found, numpy's in double precision, rounded (within an ulp of C's)."""

from __future__ import annotations

import ctypes
import ctypes.util

import numpy as np

from .noise import fma

F32 = np.float32
#: Cycles' M_2PI_F and M_PI_F (util/math_base.h), in single precision.
TWO_PI = F32(6.2831853071795864)
PI = F32(3.1415926535897932)


def _libm():
    name = ctypes.util.find_library("m") or ctypes.util.find_library("c")
    try:
        return ctypes.CDLL(name) if name else None
    except OSError:
        return None


_LIBM = _libm()


def _c(name: str, arity: int, fallback):
    """C's single-precision ``name`` (sinf ...) over float32 arrays; ``fallback`` (numpy, in
    double precision) where the C library has none."""
    fn = getattr(_LIBM, name, None) if _LIBM is not None else None
    if fn is None:
        return lambda *a: fallback(*(np.asarray(x, np.float64) for x in a)).astype(F32)
    fn.restype = ctypes.c_float
    fn.argtypes = [ctypes.c_float] * arity
    each = np.vectorize(fn, otypes=[F32])
    return lambda *a: np.asarray(each(*(np.asarray(x, F32) for x in a)), F32)


sinf = _c("sinf", 1, np.sin)
cosf = _c("cosf", 1, np.cos)
tanf = _c("tanf", 1, np.tan)
atanf = _c("atanf", 1, np.arctan)
atan2f = _c("atan2f", 2, np.arctan2)
fmodf = _c("fmodf", 2, np.fmod)  # exact in either


def f32(x) -> np.ndarray:
    return np.asarray(x, F32)


def saturate(x) -> np.ndarray:
    return np.clip(f32(x), F32(0.0), F32(1.0))


# --- Gradient ---------------------------------------------------------------------------------

def gradient(kind: str, co, reciprocal: bool = True) -> np.ndarray:
    """The Gradient Texture's Fac (Cycles' svm_gradient, saturated) of ``kind`` (Blender's
    gradient_type: LINEAR ...) at co (..., 3). ``reciprocal``: Radial divides by 2 pi through its
    reciprocal (Cycles 4.5 and 5.0; 4.2's divides, measured)."""
    co = f32(co)
    x, y, z = co[..., 0], co[..., 1], co[..., 2]
    if kind == "LINEAR":
        f = x
    elif kind == "QUADRATIC":
        r = np.maximum(x, F32(0.0))
        f = r * r
    elif kind == "EASING":
        r = saturate(x)
        t = r * r
        f = fma(F32(3.0), t, -(F32(2.0) * t * r))  # 3t fused into 3t - 2tr
    elif kind == "DIAGONAL":
        f = (x + y) * F32(0.5)
    elif kind == "RADIAL":
        a = atan2f(y, x)
        f = fma(a, F32(1.0) / TWO_PI, F32(0.5)) if reciprocal else a / TWO_PI + F32(0.5)  # fused
    elif kind in ("SPHERICAL", "QUADRATIC_SPHERE"):
        r = np.maximum(F32(0.999999) - np.sqrt(fma(z, z, fma(x, x, y * y))), F32(0.0))
        f = r if kind == "SPHERICAL" else r * r
    else:
        raise ValueError(f"unknown gradient type {kind!r}")
    return saturate(f)


# --- Checker ----------------------------------------------------------------------------------

def checker(co, scale) -> np.ndarray:
    """The Checker Texture's Fac (Cycles' svm_checker of co * scale): 1 or 0."""
    co, scale = f32(co), f32(scale)
    p = (co * scale + F32(0.000001)) * F32(0.999999)  # (co x scale not fused: measured)
    i = np.abs(np.floor(p).astype(np.int64))
    parity = i % 2
    return np.where((parity[..., 0] == parity[..., 1]).astype(np.int64) == parity[..., 2], F32(1.0), F32(0.0))


# --- Magic ------------------------------------------------------------------------------------

def magic(co, scale, distortion, depth: int, reciprocal: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The Magic Texture's (Color (..., 3), Fac) (Cycles' svm_magic, depth 0 .. 10). ``reciprocal``:
    the three divisions by 2 x distortion through one reciprocal (Cycles 4.5 and 5.0; 4.2's
    divides, measured)."""
    co, scale, d = f32(co), f32(scale), f32(distortion)
    px, py, pz = (fmodf(co[..., i], TWO_PI) for i in range(3))
    x = sinf((px + py + pz) * F32(5.0) * scale)
    y = cosf((-px + py - pz) * F32(5.0) * scale)
    z = -cosf((-px - py + pz) * F32(5.0) * scale)
    if depth > 0:
        y = -cosf(fma(-y, d, x * d) + z * d) * d  # y d fused into x d - y d
        x, z = x * d, z * d
    if depth > 1:
        x = cosf(x - y - z) * d
    if depth > 2:
        z = sinf(-x - y - z) * d
    if depth > 3:
        x = -cosf(-x + y - z) * d
    if depth > 4:
        y = -sinf(-x + y + z) * d
    if depth > 5:
        y = -cosf(-x + y + z) * d
    if depth > 6:
        x = cosf(x + y + z) * d
    if depth > 7:
        z = sinf(x + y - z) * d
    if depth > 8:
        x = -cosf(-x - y + z) * d
    if depth > 9:
        y = -sinf(x - y + z) * d
    if d != 0.0:
        if reciprocal:
            inverse = F32(1.0) / (d * F32(2.0))
            x, y, z = x * inverse, y * inverse, z * inverse
        else:
            x, y, z = x / (d * F32(2.0)), y / (d * F32(2.0)), z / (d * F32(2.0))
    color = np.stack([F32(0.5) - x, F32(0.5) - y, F32(0.5) - z], -1)
    return color, (color[..., 0] + color[..., 1] + color[..., 2]) * (F32(1.0) / F32(3.0))


# --- Brick ------------------------------------------------------------------------------------

def brick_noise(n) -> np.ndarray:
    """Cycles' brick_noise: an integer hash of n (uint32) to [0, 1)."""
    n = np.asarray(n).astype(np.uint32)
    n = (n + np.uint32(1013)) & np.uint32(0x7FFFFFFF)
    n = (n >> np.uint32(13)) ^ n
    u = np.uint32
    nn = (n * (n * n * u(60493) + u(19990303)) + u(1376312589)) & u(0x7FFFFFFF)
    return F32(0.5) * (nn.astype(F32) / F32(1073741824.0))


def smoothstep(f) -> np.ndarray:
    """Cycles' smoothstepf: 3f^2 - 2f^3 on [0, 1] (3f^2 fused), 0 below, 1 above."""
    f = f32(f)
    ff = f * f
    return np.where(f <= 0.0, F32(0.0), np.where(f >= 1.0, F32(1.0), fma(F32(3.0), ff, -(F32(2.0) * ff * f))))


def brick_pattern(p, mortar_size, mortar_smooth, bias, brick_width, row_height, offset_amount,
                  offset_frequency: int, squash_amount, squash_frequency: int) -> tuple[np.ndarray, ...]:
    """(tint, mortar) at p (..., 3), Cycles' svm_brick."""
    p = f32(p)
    mortar_size, mortar_smooth, bias = f32(mortar_size), f32(mortar_smooth), f32(bias)
    row_height, offset_amount, squash_amount = f32(row_height), f32(offset_amount), f32(squash_amount)
    row = np.floor(p[..., 1] / row_height).astype(np.int32)
    width = np.full(row.shape, brick_width, F32)
    offset = np.zeros(row.shape, F32)
    if offset_frequency and squash_frequency:
        width = np.where(np.fmod(row, squash_frequency) != 0, width, width * squash_amount)
        offset = np.where(np.fmod(row, offset_frequency) != 0, F32(0.0), width * offset_amount)
    shifted = p[..., 0] + offset
    brick = np.floor(shifted / width).astype(np.int32)
    x = shifted - width * brick.astype(F32)  # (not fused: measured)
    y = p[..., 1] - row_height * row.astype(F32)
    key = (row.astype(np.uint32) << np.uint32(16)) + (brick.astype(np.uint32) & np.uint32(0xFFFF))
    tint = saturate(brick_noise(key) + bias)
    min_dist = np.minimum(np.minimum(x, y), np.minimum(width - x, row_height - y))
    if mortar_smooth == 0.0:
        smooth = np.ones(row.shape, F32)
    else:
        smooth = smoothstep((F32(1.0) - min_dist / mortar_size) / mortar_smooth)
    return tint, np.where(min_dist >= mortar_size, F32(0.0), smooth)


def brick(co, color1, color2, mortar, scale, mortar_size, mortar_smooth, bias, brick_width, row_height,
          offset_amount, offset_frequency: int, squash_amount, squash_frequency: int) -> tuple:
    """The Brick Texture's (Color (..., 3), Fac) (Cycles' svm_node_tex_brick); colours RGB."""
    tint, f = brick_pattern(f32(co) * f32(scale), mortar_size, mortar_smooth, bias, brick_width, row_height,
                            offset_amount, offset_frequency, squash_amount, squash_frequency)
    tint, f = tint[..., None], f[..., None]
    color1, color2, mortar = f32(color1)[..., :3], f32(color2)[..., :3], f32(mortar)[..., :3]
    blended = fma(tint, color2, (F32(1.0) - tint) * color1)  # tint x Color2 fused
    color = np.where(f != 1.0, blended, color1)
    return fma(mortar, f, color * (F32(1.0) - f)), f[..., 0]  # mortar x Fac fused


# --- Radial Tiling ----------------------------------------------------------------------------
# Names follow Cycles' (radial_tiling_shared.h), shortened: ``bisector`` the angle from a
# segment's border to its bisector (pi / sides), ``segment`` a segment's angle, ``coord`` the
# coordinate's angle from its segment's border, ``bevel`` the angle from the border where a rounded
# corner starts, ``last`` the last (narrower) segment's half angle where Sides is not whole.

def _straight(l_bisector, bisector, angle):
    """The segment coordinate across a straight edge: l tan|bisector - angle|, negative before the
    bisector."""
    r = l_bisector * tanf(np.abs(bisector - angle))
    return np.where(angle < bisector, -r, r)


def _normalizer(l, angle, spline, roundness, bevel, fused_k: bool = False):
    """Half a segment's width at distance ``l`` along its bisector (Cycles'
    normalize_based_on_l_angle_bisector): l tan(angle) + spline (l / 2 + 1/2) + roundness bevel,
    the first product fused; the last too where ``fused_k`` (as Cycles' kernel does, measured)."""
    t = fma(l, tanf(angle), spline * (F32(0.5) * l + F32(0.5)))
    return fma(roundness, bevel, t) if fused_k else t + roundness * bevel


def _normalizer_coord(l, angle, spline, roundness, bevel, first: bool = False, fused_k: bool = False):
    """The same at the coordinate's distance (normalize_based_on_l_coord): l sin(angle) + spline
    (l cos(angle) / 2 + 1/2) + roundness bevel; the second product fused (the first where
    ``first``), the last where ``fused_k``."""
    inner = fma(F32(0.5) * l, cosf(angle), F32(0.5))
    t = fma(l, sinf(angle), spline * inner) if first else fma(spline, inner, l * sinf(angle))
    return fma(roundness, bevel, t) if fused_k else t + roundness * bevel


def _rounded_terms(l_coord, angle, to_bevel, spline):
    """What a rounded corner adds to l sin(angle): along its spline, then along its arc."""
    cos = l_coord * cosf(angle)
    spline_part = fma(cos, to_bevel, F32(0.5) * (F32(1.0) - cos) * (to_bevel * to_bevel) / spline)
    arc_part = fma(spline, fma(F32(0.5) * l_coord, cosf(angle), F32(-0.5)), to_bevel)
    return np.where(to_bevel < spline, spline_part, arc_part)


def _mix(a, b, t):
    """Cycles' mix: a + t (b - a), fused."""
    return fma(t, b - a, a)


def radial_tiling(co, sides, roundness, normalize: bool) -> tuple[np.ndarray, ...]:
    """The Radial Tiling node's (Segment Coordinates (..., 3), Segment ID, Segment Width, Segment
    Rotation) at co (..., 3) (its x and y), as Cycles' svm_node_radial_tiling
    (radial_tiling_shared.h: calculate_out_variables, calculate_out_segment_id). Sides and
    Roundness are numbers (the node's sockets unlinked)."""
    co = f32(co)
    x, y = co[..., 0], co[..., 1]
    n = np.maximum(F32(sides), F32(2.0))
    k = np.clip(F32(roundness), F32(0.0), F32(1.0))
    below = (y < 0).astype(F32)
    with np.errstate(all="ignore"):  # every branch is computed, each pixel takes its own
        l_coord = np.sqrt(fma(y, y, x * x))
        x_axis_coord = atan2f(y, x) + below * TWO_PI
        bisector = PI / n
        segment = F32(2.0) * bisector
        segment_id = np.floor(x_axis_coord / segment)
        coord = x_axis_coord - segment_id * segment
        rotation = segment_id * segment + bisector
        if n - np.floor(n) == 0.0:
            out = _regular(normalize, n, k, l_coord, bisector, segment, coord, rotation)
        elif k == 0.0:
            out = _irregular_straight(normalize, n, l_coord, x_axis_coord, bisector, segment_id, segment,
                                      coord, rotation)
        else:
            out = _irregular_circular(normalize, n, k, x, y, l_coord, x_axis_coord, bisector, segment_id,
                                      segment, coord, rotation)
        l_bisector, parameter, width, rotation = out
        parameter = np.where((x == 0.0) & (y == 0.0), F32(0.0), parameter)
        if normalize:
            parameter = F32(0.5) * parameter + F32(0.5)
        else:
            l_bisector = l_bisector - F32(1.0)
        ids = np.floor(n * fma(atan2f(y, x), F32(1.0) / TWO_PI, below))
    coordinates = np.stack([parameter, l_bisector, np.zeros_like(parameter)], -1)
    return coordinates, ids, np.broadcast_to(f32(width), x.shape), rotation


def _regular(normalize, n, k, l_coord, bisector, segment, coord, rotation):
    """Sides a whole number: every segment alike (straight, round, or straight with rounded
    corners)."""
    if k == 0.0:
        l_bisector = l_coord * cosf(bisector - coord)
        parameter = _straight(l_bisector, bisector, coord)
        if normalize and n != 2.0:
            parameter = parameter / (l_bisector * tanf(bisector))
        return l_bisector, parameter, tanf(bisector) if n != 2.0 else F32(0.0), rotation
    if k == 1.0:
        parameter = np.abs(bisector - coord)
        parameter = np.where(coord < bisector, -parameter, parameter)
        if normalize:
            parameter = parameter / bisector
        return l_coord, parameter, bisector, rotation
    bevel = bisector - atanf((F32(1.0) - k) * tanf(bisector))
    return (*_bevelled(normalize, k, l_coord, bisector, segment, coord, bevel), rotation)


def _bevelled(normalize, k, l_coord, bisector, segment, coord, bevel):
    """(l, parameter, width) of a regular segment with rounded corners: its straight middle and
    its arcs (Cycles' "Regular straight part" and "Regular rounded part" of 0 < roundness < 1)."""
    to_bisector = bisector - bevel
    spline = (F32(1.0) - k) * bevel
    width = tanf(to_bisector) + spline + k * bevel
    l_straight = l_coord * cosf(bisector - coord)
    p_straight = _straight(l_straight, bisector, coord)
    if normalize:
        p_straight = p_straight / _normalizer(l_straight, to_bisector, spline, k, bevel)
    # the arcs about the segment's borders
    signed = coord - (coord > bisector).astype(F32) * segment
    l_center = (F32(1.0) - k) / cosf(bisector)
    along = cosf(signed) * l_center
    l_round = l_coord / (along + np.sqrt(fma(-l_center, l_center, fma(along, along, k * k))))
    to_bevel = bevel - np.abs(signed)
    p_round = l_coord * sinf(to_bisector) + _rounded_terms(l_coord, to_bisector, to_bevel, spline)
    p_round = np.where(coord < bisector, -p_round, p_round)
    if normalize:
        p_round = p_round / _mix(_normalizer(l_round, to_bisector, spline, k, bevel),
                                 _normalizer_coord(l_coord, to_bisector, spline, k, bevel), to_bevel / bevel)
    rounded = (coord >= segment - bevel) | (coord < bevel)
    return np.where(rounded, l_round, l_straight), np.where(rounded, p_round, p_straight), width


def _irregular_straight(normalize, n, l_coord, x_axis_coord, bisector, segment_id, segment, coord, rotation):
    """Sides not a whole number, roundness 0: whole segments, and a last, narrower one."""
    last = fma(-np.floor(n), bisector, PI)
    l_regular = l_coord * cosf(bisector - coord)
    p_regular = _straight(l_regular, bisector, coord)
    ratio = cosf(bisector) / cosf(last)
    l_last = ratio * (l_coord * cosf(last - coord))
    p_last = _straight(l_last, last, coord)
    if normalize:
        p_regular = p_regular / (l_regular * tanf(bisector))
        p_last = p_last / (l_last * tanf(last))
    regular = x_axis_coord < TWO_PI - F32(2.0) * last
    return (np.where(regular, l_regular, l_last), np.where(regular, p_regular, p_last),
            np.where(regular, tanf(bisector), tanf(last)),
            np.where(regular, rotation, segment_id * segment + last))


def _irregular_circular(normalize, n, k, x, y, l_coord, x_axis_coord, bisector, segment_id, segment, coord,
                        rotation):
    """Sides not a whole number, roundness above 0 (Cycles' calculate_out_variables_irregular_circular):
    whole segments with rounded corners; the last one's straight part and its two arcs."""
    one, half = F32(1.0), F32(0.5)
    bevel = bisector - atanf((one - k) * tanf(bisector))
    last = PI - np.floor(n) * bisector
    last_segment = F32(2.0) * last
    inner_bevel = last - atanf((one - k) * tanf(last))
    radius = k * tanf(last) / tanf(half * (bisector + last))
    c = cosf(last - inner_bevel)
    center_x = fma(-radius, cosf(last), cosf(inner_bevel) / c)
    center_y = radius * sinf(last) - (sinf(inner_bevel) / c)
    outer_bevel = atanf((center_y + radius * sinf(bisector)) / fma(radius, cosf(bisector), center_x))
    outer_to_bisector = bisector - outer_bevel
    effective = one - tanf(bisector - outer_bevel) / tanf(bisector)
    outer_spline = (one - effective) * outer_bevel
    # the whole segments: straight middles and rounded corners as a regular polygon's, but the
    # straight parts beside the last segment normalised by its outer arc
    l_whole, p_whole, width_whole = _bevelled(normalize, k, l_coord, bisector, segment, coord, bevel)
    straight = (((coord >= bevel) & (coord < segment - bevel))
                | (x_axis_coord >= TWO_PI - last_segment - bevel) | (x_axis_coord < bevel))
    beside_last = (x_axis_coord >= TWO_PI - last_segment - bisector) | (x_axis_coord < bisector)
    l_straight = l_coord * cosf(bisector - coord)
    p_straight = _straight(l_straight, bisector, coord)
    if normalize:
        beside = _normalizer(l_straight, outer_to_bisector, outer_spline, effective, outer_bevel, True)
        regular = _normalizer(l_straight, bisector - bevel, (one - k) * bevel, k, bevel)
        p_straight = p_straight / np.where(beside_last, beside, regular)
    l_whole = np.where(straight, l_straight, l_whole)
    p_whole = np.where(straight, p_straight, p_whole)
    # the last segment's straight part
    to_last = last - inner_bevel
    ratio = cosf(bisector) / cosf(last)
    spline = (one - k) * inner_bevel
    l_last = l_coord * cosf(last - coord)
    l_last_straight = ratio * l_last
    p_last_straight = _straight(l_last_straight, last, coord)
    if normalize:
        p_last_straight = p_last_straight / (ratio * _normalizer(l_last, to_last, spline, k, inner_bevel))
    width_last = tanf(to_last) + ratio * (spline * ((half / ratio) + half) + k * inner_bevel)
    # the last segment's arcs, their angle mirrored about its bisector
    mirrored = atan2f(y, x)
    flip = (x_axis_coord >= TWO_PI - last_segment - outer_bevel) & (x_axis_coord < TWO_PI - last)
    mirrored = np.where(flip, -(mirrored + last_segment), mirrored)
    along = fma(sinf(mirrored), center_y, cosf(mirrored) * center_x)
    inside = fma(-center_x, center_x, fma(along, along, radius * radius)) - center_y * center_y
    l_arc_last = l_coord / (along + np.sqrt(inside))
    l_arc = ratio * l_arc_last
    # the inner arc (towards the last segment's bisector)
    to_bevel = inner_bevel - np.abs(mirrored)
    p_inner = fma(ratio, _rounded_terms(l_coord, to_last, to_bevel, spline), ratio * l_coord * sinf(to_last))
    p_inner = np.where(coord < last, -p_inner, p_inner)
    if normalize:
        along_bisector = _normalizer(l_arc_last, to_last, spline, k, inner_bevel)
        at_coord = _normalizer_coord(l_coord, to_last, spline, k, inner_bevel, first=True)
        p_inner = p_inner / (ratio * _mix(along_bisector, at_coord, to_bevel / inner_bevel))
    # the outer arc (towards the whole segment beside it)
    to_outer = outer_bevel - np.abs(mirrored)
    p_outer = l_coord * sinf(outer_to_bisector) + _rounded_terms(l_coord, outer_to_bisector, to_outer,
                                                                 outer_spline)
    p_outer = np.where(coord < bisector, -p_outer, p_outer)
    if normalize:
        p_outer = p_outer / _mix(
            _normalizer(l_arc, outer_to_bisector, outer_spline, effective, outer_bevel, fused_k=True),
            _normalizer_coord(l_coord, outer_to_bisector, outer_spline, effective, outer_bevel, fused_k=True),
            to_outer / outer_bevel)
    width_outer = fma(k, bevel, tanf(bisector - bevel) + (one - k) * bevel)
    inner = mirrored < 0.0
    rotation_last = segment_id * segment + last
    # each pixel's part
    whole = (x_axis_coord >= outer_bevel) & (x_axis_coord < TWO_PI - last_segment - outer_bevel)
    last_straight = ((x_axis_coord >= TWO_PI - last_segment + inner_bevel)
                     & (x_axis_coord < TWO_PI - inner_bevel))
    part = np.where(whole, 0, np.where(last_straight, 1, np.where(inner, 2, 3)))
    return (np.choose(part, [l_whole, l_last_straight, l_arc, l_arc]),
            np.choose(part, [p_whole, p_last_straight, p_inner, p_outer]),
            np.choose(part, [width_whole, width_last, width_last, width_outer]),
            np.choose(part, [rotation, rotation_last, rotation_last, rotation]))
