"""The numpy twin of ``glsl/node_tex_voronoi.glsl``: the Voronoi Texture as Cycles 5.0 computes it
(kernel/svm/voronoi.h), operation for operation in float32, vectorised over points. As the GLSL, a
point of any dimension count is an (N, 4) array whose unused components stay 0 (1D in x), summed
in Cycles' order ((x + y) + (z + w) covers float2, float3 and float4). Pure numpy."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from . import hashing

F32 = np.float32
FEATURES = ("F1", "F2", "SMOOTH_F1", "DISTANCE_TO_EDGE", "N_SPHERE_RADIUS")
METRICS = ("EUCLIDEAN", "MANHATTAN", "CHEBYCHEV", "MINKOWSKI")
_FLT_MAX = F32(3.402823466e38)


@dataclass(frozen=True)
class Params:
    """Cycles' VoronoiParams after svm_node_tex_voronoi's clamps; ``cells``: how a cell is hashed
    (``INT``: Cycles 5.0's integer index; ``FLOAT``: 4.x's float coordinates)."""

    dims: int
    feature: str
    metric: str
    scale: np.float32
    detail: np.float32
    roughness: np.float32
    lacunarity: np.float32
    smoothness: np.float32
    exponent: np.float32
    randomness: np.float32
    normalize: bool
    cells: str = "INT"
    max_distance: np.float32 = F32(0.0)

    @property
    def lanes(self) -> np.ndarray:
        return (np.arange(4) < self.dims).astype(F32)


def _sum(v: np.ndarray) -> np.ndarray:
    return (v[..., 0] + v[..., 1]) + (v[..., 2] + v[..., 3])


def _mix(a, b, t):
    """Cycles' mix: a + t (b - a)."""
    return a + t * (b - a)


def _smoothstep(x: np.ndarray) -> np.ndarray:
    """Cycles' smoothstep(0, 1, x)."""
    t = x / F32(1.0)
    return np.where(x < 0, F32(0.0), np.where(x >= 1, F32(1.0), (F32(3.0) - F32(2.0) * t) * (t * t)))


def distance_bound(d: np.ndarray, p: Params) -> np.ndarray:
    """Cycles' voronoi_distance_bound of a - b = d (..., 4)."""
    a = np.abs(d)
    if p.metric == "EUCLIDEAN":
        return _sum(d * d)
    if p.metric == "MANHATTAN":
        return _sum(a)
    if p.metric == "CHEBYCHEV":
        return np.maximum(np.maximum(a[..., 0], a[..., 1]), np.maximum(a[..., 2], a[..., 3]))
    with np.errstate(divide="ignore"):  # 0 ** e for e < 0: the unused components are chosen out
        return _sum(np.where(p.lanes > 0, np.power(a, p.exponent), F32(0.0)))


def distance(d: np.ndarray, p: Params) -> np.ndarray:
    """Cycles' voronoi_distance of a - b = d (..., 4)."""
    bound = distance_bound(d, p)
    if p.metric == "EUCLIDEAN":
        return np.sqrt(bound)
    if p.metric == "MINKOWSKI":
        return np.power(bound, F32(1.0) / p.exponent)
    return bound


def _keys(cellf, cell, offset, p: Params):
    offset = np.asarray(offset, np.int32)
    return cellf + offset.astype(F32), cell + offset


def cell_hash(cellf, cell, offset, p: Params) -> np.ndarray:
    """The feature point's offset in cell + offset, before Randomness: (..., 4)."""
    key, index = _keys(cellf, cell, offset, p)
    out = np.zeros(key.shape, F32)
    n = p.dims
    if n == 1:
        out[..., 0] = hashing.hash_float(key[..., :1])
    elif p.cells == "FLOAT":
        out[..., :n] = hashing.hash_float_n(key[..., :n])
    else:
        out[..., :n] = hashing.hash_int_n(index[..., :n])
    return out


def cell_color(cellf, cell, offset, p: Params) -> np.ndarray:
    """The colour of cell + offset: (..., 3)."""
    key, index = _keys(cellf, cell, offset, p)
    n = p.dims
    if n == 1 or p.cells == "FLOAT":
        return hashing.hash_float3(key[..., :n])
    return hashing.hash_int3(index[..., :n])


def _point(cellf, cell, offset, p: Params) -> np.ndarray:
    return np.asarray(offset, np.int32).astype(F32) + cell_hash(cellf, cell, offset, p) * p.randomness


def _offsets(p: Params, r: int):
    """The cells around in Cycles' order (w outermost, x innermost), an unused axis over one."""
    reach = [r if axis < p.dims else 0 for axis in range(4)]
    for u in range(-reach[3], reach[3] + 1):
        for k in range(-reach[2], reach[2] + 1):
            for j in range(-reach[1], reach[1] + 1):
                for i in range(-reach[0], reach[0] + 1):
                    yield np.array([i, j, k, u], np.int32)


def _cells(coord: np.ndarray):
    cellf = np.floor(coord)
    return cellf, coord - cellf, cellf.astype(np.int32)


def _pick(mask, new, old):
    """Per point: ``new`` where ``mask``, else ``old`` (rows of (N, k) arrays)."""
    return np.where(mask[:, None] if np.ndim(old) > 1 else mask, new, old)


def _closest(p: Params, cellf, cell, local):
    """The feature point closest to ``local`` by the metric's bound: its cell's offset and its
    position relative to the cell (voronoi_f1's scan, voronoi_n_sphere_radius's first)."""
    n = len(local)
    best = np.full(n, _FLT_MAX, F32)
    closest_offset = np.zeros((n, 4), np.int32)
    closest = np.zeros((n, 4), F32)
    for offset in _offsets(p, 1):
        point = _point(cellf, cell, offset, p)
        d = distance_bound(point - local, p)
        closer = d < best
        closest_offset = _pick(closer, offset, closest_offset)
        best = np.where(closer, d, best)
        closest = _pick(closer, point, closest)
    return closest_offset, closest


def f1(p: Params, coord: np.ndarray):
    """Cycles' voronoi_f1: (distance, colour, position)."""
    cellf, local, cell = _cells(coord)
    offset, point = _closest(p, cellf, cell, local)
    return distance(point - local, p), cell_color(cellf, cell, offset, p), point + cellf


def smooth_f1(p: Params, coord: np.ndarray):
    """Cycles' voronoi_smooth_f1."""
    cellf, local, cell = _cells(coord)
    n = len(coord)
    s = p.smoothness
    smooth_distance = np.zeros(n, F32)
    smooth_color = np.zeros((n, 3), F32)
    smooth_position = np.zeros((n, 4), F32)
    first = True
    for offset in _offsets(p, 2):
        point = _point(cellf, cell, offset, p)
        d = distance(point - local, p)
        h = np.ones(n, F32) if first else _smoothstep(F32(0.5) + F32(0.5) * (smooth_distance - d) / s)
        first = False
        correction = s * h * (F32(1.0) - h)
        smooth_distance = _mix(smooth_distance, d, h) - correction
        correction = correction / (F32(1.0) + F32(3.0) * s)
        color = cell_color(cellf, cell, offset, p)
        smooth_color = _mix(smooth_color, color, h[:, None]) - correction[:, None]
        smooth_position = _mix(smooth_position, point, h[:, None]) - correction[:, None] * p.lanes
    return smooth_distance, smooth_color, cellf + smooth_position


def f2(p: Params, coord: np.ndarray):
    """Cycles' voronoi_f2."""
    cellf, local, cell = _cells(coord)
    n = len(coord)
    d1 = np.full(n, _FLT_MAX, F32)
    d2 = np.full(n, _FLT_MAX, F32)
    off1 = np.zeros((n, 4), np.int32)
    off2 = np.zeros((n, 4), np.int32)
    pos1 = np.zeros((n, 4), F32)
    pos2 = np.zeros((n, 4), F32)
    for offset in _offsets(p, 1):
        point = _point(cellf, cell, offset, p)
        d = distance(point - local, p)
        first = d < d1
        second = ~first & (d < d2)
        d2 = np.where(first, d1, np.where(second, d, d2))
        d1 = np.where(first, d, d1)
        off2 = _pick(first, off1, _pick(second, offset, off2))
        off1 = _pick(first, offset, off1)
        pos2 = _pick(first, pos1, _pick(second, point, pos2))
        pos1 = _pick(first, point, pos1)
    return d2, cell_color(cellf, cell, off2, p), pos2 + cellf


def distance_to_edge(p: Params, coord: np.ndarray) -> np.ndarray:
    """Cycles' voronoi_distance_to_edge (Euclidean whatever the metric)."""
    cellf, local, cell = _cells(coord)
    if p.dims == 1:
        c, x = cellf[:, 0], local[:, 0]
        mid = hashing.hash_float(c[:, None]) * p.randomness
        left = F32(-1.0) + hashing.hash_float((c - F32(1.0))[:, None]) * p.randomness
        right = F32(1.0) + hashing.hash_float((c + F32(1.0))[:, None]) * p.randomness
        return np.minimum(np.abs((mid + left) / F32(2.0) - x), np.abs((mid + right) / F32(2.0) - x))
    n = len(coord)
    best = np.full(n, _FLT_MAX, F32)
    to_closest = np.zeros((n, 4), F32)
    for offset in _offsets(p, 1):
        to_point = _point(cellf, cell, offset, p) - local
        d = _sum(to_point * to_point)
        closer = d < best
        best = np.where(closer, d, best)
        to_closest = _pick(closer, to_point, to_closest)
    best = np.full(n, _FLT_MAX, F32)
    for offset in _offsets(p, 1):
        to_point = _point(cellf, cell, offset, p) - local
        perpendicular = to_point - to_closest
        length2 = _sum(perpendicular * perpendicular)
        far = length2 > F32(0.0001)
        with np.errstate(divide="ignore", invalid="ignore"):  # the closest point itself: left out
            length = np.sqrt(length2)[:, None]
            unit = perpendicular / length if p.dims == 3 else perpendicular * (F32(1.0) / length)
            edge = _sum((to_closest + to_point) / F32(2.0) * unit)
        best = np.where(far, np.minimum(best, edge), best)
    return best


def n_sphere_radius(p: Params, coord: np.ndarray) -> np.ndarray:
    """Cycles' voronoi_n_sphere_radius (Euclidean whatever the metric; 1D: |b - a|)."""
    p = replace(p, metric="MANHATTAN" if p.dims == 1 else "EUCLIDEAN")
    cellf, local, cell = _cells(coord)
    n = len(coord)
    closest_offset, closest = _closest(p, cellf, cell, local)
    best = np.full(n, _FLT_MAX, F32)
    other = np.zeros((n, 4), F32)
    for offset in _offsets(p, 1):
        if not offset.any():
            continue
        around = offset + closest_offset
        point = _point(cellf, cell, around, p)
        d = distance_bound(closest - point, p)
        closer = d < best
        best = np.where(closer, d, best)
        other = _pick(closer, point, other)
    return distance(other - closest, p) / F32(2.0)


def fractal(p: Params, coord: np.ndarray):
    """Cycles' fractal_voronoi_x_fx of F1, F2 or Smooth F1: (distance, colour, position)."""
    smooth = p.feature == "SMOOTH_F1" and p.smoothness != 0
    octave_of = f2 if p.feature == "F2" else smooth_f1 if smooth else f1
    amplitude, max_amplitude, scale = F32(1.0), F32(0.0), F32(1.0)
    n = len(coord)
    dist, color, position = np.zeros(n, F32), np.zeros((n, 3), F32), np.zeros((n, 4), F32)
    zero_input = p.detail == 0 or p.roughness == 0
    i = 0
    while i <= np.ceil(p.detail):
        o_dist, o_color, o_position = octave_of(p, coord * scale)
        if zero_input:
            max_amplitude = F32(1.0)
            dist, color, position = o_dist, o_color, o_position
            break
        o_position = o_position * (F32(1.0) / scale)  # Cycles' float4 / float
        if i <= p.detail:
            max_amplitude = max_amplitude + amplitude
            dist = dist + o_dist * amplitude
            color = color + o_color * amplitude
            position = _mix(position, o_position, amplitude)
            scale = scale * p.lacunarity
            amplitude = amplitude * p.roughness
        else:
            remainder = p.detail - np.floor(p.detail)
            if remainder != 0:
                max_amplitude = _mix(max_amplitude, max_amplitude + amplitude, remainder)
                dist = _mix(dist, dist + o_dist * amplitude, remainder)
                color = _mix(color, color + o_color * amplitude, remainder)
                position = _mix(position, _mix(position, o_position, amplitude), remainder)
        i += 1
    if p.normalize:
        dist = dist / (max_amplitude * p.max_distance)
        color = color * (F32(1.0) / max_amplitude)  # Cycles' float3 /= float
    position = position * (F32(1.0) / p.scale) if p.scale != 0 else np.zeros_like(position)
    return dist, color, position


def fractal_distance_to_edge(p: Params, coord: np.ndarray) -> np.ndarray:
    """Cycles' fractal_voronoi_distance_to_edge."""
    amplitude, max_amplitude, scale = F32(1.0), p.max_distance, F32(1.0)
    dist = np.full(len(coord), F32(8.0), F32)
    zero_input = p.detail == 0 or p.roughness == 0
    i = 0
    while i <= np.ceil(p.detail):
        octave = distance_to_edge(p, coord * scale)
        if zero_input:
            return octave / max_amplitude if p.normalize else octave
        if i <= p.detail:
            max_amplitude = _mix(max_amplitude, p.max_distance / scale, amplitude)
            dist = _mix(dist, np.minimum(dist, octave / scale), amplitude)
            scale = scale * p.lacunarity
            amplitude = amplitude * p.roughness
        else:
            remainder = p.detail - np.floor(p.detail)
            if remainder != 0:
                lerp_amplitude = _mix(max_amplitude, p.max_distance / scale, amplitude)
                max_amplitude = _mix(max_amplitude, lerp_amplitude, remainder)
                lerp_distance = _mix(dist, np.minimum(dist, octave / scale), amplitude)
                dist = _mix(dist, np.minimum(dist, lerp_distance), remainder)
        i += 1
    return dist / max_amplitude if p.normalize else dist


def voronoi(dims: int, feature: str, metric: str, co, w, scale=5.0, detail=0.0, roughness=0.5,
            lacunarity=2.0, smoothness=1.0, exponent=0.5, randomness=1.0, normalize=False,
            cells: str = "INT") -> dict[str, np.ndarray]:
    """The node's outputs at Vector ``co`` (N, 3) and ``w`` (N,): Distance (N,), Color (N, 3),
    Position (N, 3), W (N,), Radius (N,), as svm_node_tex_voronoi writes them (0 where the
    feature does not compute an output). Settings as the node's sockets read them."""
    co, w = np.asarray(co, F32).reshape(-1, 3), np.asarray(w, F32).reshape(-1)
    p = Params(dims, feature, "MANHATTAN" if dims == 1 else metric, F32(scale),
               np.clip(F32(detail), F32(0.0), F32(15.0)), np.clip(F32(roughness), F32(0.0), F32(1.0)),
               F32(lacunarity), np.clip(F32(smoothness) / F32(2.0), F32(0.0), F32(0.5)), F32(exponent),
               np.clip(F32(randomness), F32(0.0), F32(1.0)), bool(normalize), cells)
    co, w = co * p.scale, w * p.scale
    coord = np.zeros((len(co), 4), F32)
    if dims == 1:
        coord[:, 0] = w
    else:
        coord[:, :min(dims, 3)] = co[:, :min(dims, 3)]
        if dims == 4:
            coord[:, 3] = w
    n = len(coord)
    zero = np.zeros(n, F32)
    out = {"distance": zero, "color": np.zeros((n, 3), F32), "position": np.zeros((n, 3), F32), "w": zero,
           "radius": zero}
    half_cell = F32(0.5) + F32(0.5) * p.randomness
    if feature == "DISTANCE_TO_EDGE":
        out["distance"] = fractal_distance_to_edge(replace(p, max_distance=half_cell), coord)
    elif feature == "N_SPHERE_RADIUS":
        out["radius"] = n_sphere_radius(p, coord)
    else:
        corner = F32(0.0) - np.full((1, 4), half_cell, F32) * p.lanes
        reach = half_cell if dims == 1 else distance(corner, p)[0]
        p = replace(p, max_distance=F32(reach * F32(2.0 if feature == "F2" else 1.0)))
        dist, color, position = fractal(p, coord)
        if dims == 1:
            position = np.stack([zero, zero, zero, position[:, 0]], -1)
        out.update(distance=dist, color=color, position=position[:, :3], w=position[:, 3])
    return out
