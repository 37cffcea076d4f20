"""Light culling: which lights can reach which tiles of the screen.

A light with an influence radius r (``Light.influence``: Blender's *Custom Distance*, else the
distance at which its inverse-square irradiance I / d^2 falls to the scene's *Light Threshold*)
is windowed to nothing at r (glsl/lights.glsl, light_window: (1 - (d / r)^4)^2, the window EEVEE
and Unreal use; the irradiance it removes is below the threshold everywhere: I / d^2 (1 - w) =
t (2 x^2 - x^6) <= t with x = d / r <= 1). So a light needs shading only where the surface lies
within r of it: on the screen, inside the projection of the box around its sphere. Per view the
screen is cut into tiles of TILE pixels; each tile lists, in light order, the lights whose box
covers it and whose sphere meets the tile's frustum (for a perspective view its four side
planes and the cone about the tile, for an orthographic one its rectangle: the box's corners drop
out, and the planes' own false positives at the tile's corners), lights without a radius in every
tile; each
fragment loops over its tile's list instead of every light. Skipped lights would have added
exactly 0, so a culled frame equals the unculled one bit for bit.

Pure numpy (no ``bpy``, no ``gpu``): ``tile_lists`` builds what the shaders read.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..scene.matrices import invert

#: Pixels per tile side, in final-image pixels (a supersampled target scales it).
TILE = 8
#: Light indices per texture row (the index list is a width x rows float texture).
LIST_WIDTH = 4096
#: The most list entries a frame holds; beyond, one list of every light serves all fragments.
MAX_ENTRIES = LIST_WIDTH * 2048
#: Up to this many (light, tile) pairs from the boxes are also tested sphere against tile.
SPHERE_TESTED = 1 << 21
#: The share of the lights a view's tiles must leave out, on average, for their lists to pay
#: (``lists_pay``).
SKIPPED_TO_PAY = 0.2


@dataclass(frozen=True)
class TileLists:
    """``header[ty, tx]`` = (first entry, count) of tile (tx, ty); ``entries`` the light indices
    of all tiles one after the other, padded to rows of LIST_WIDTH; ``tile`` the tile's side in
    target pixels."""

    tile: int
    header: np.ndarray  # (rows, columns, 2) float32
    entries: np.ndarray  # (list rows, LIST_WIDTH) float32 (integers, exact below 2^24)

    @property
    def entry_count(self) -> int:
        return int(self.header[..., 1].sum())

    @property
    def columns(self) -> int:
        return self.header.shape[1]

    @property
    def header_texels(self) -> int:
        return self.header.shape[0] * self.header.shape[1]

    @property
    def mean_listed(self) -> float:
        """Lights a tile lists, on average over the view's tiles."""
        return self.entry_count / self.header_texels

    def texels(self) -> np.ndarray:
        """What the shaders read (one RG32F texture, LIST_WIDTH texels a row): each tile's (first,
        count), row by row, then the light indices (in x) from texel ``header_texels`` on."""
        flat = np.zeros((self.header_texels + self.entries.size, 2), np.float32)
        flat[:self.header_texels] = self.header.reshape(-1, 2)
        flat[self.header_texels:, 0] = self.entries.reshape(-1)
        rows = -(-len(flat) // LIST_WIDTH)
        out = np.zeros((rows * LIST_WIDTH, 2), np.float32)
        out[:len(flat)] = flat
        return out.reshape(rows, LIST_WIDTH, 2)


#: The most a window (1 - (d/r)^4)^2 at reach r removes of an inverse-square irradiance I / d^2,
#: in units of I / r^2: with x = (d/r)^2 the loss is (I / r^2)(2x - x^3), largest at x = sqrt(2/3),
#: 4/3 sqrt(2/3) = 1.0887. The reach is set where I / r^2 is the threshold over this, so that the
#: window removes at most the threshold anywhere.
WINDOW_PEAK_LOSS = 4.0 / 3.0 * math.sqrt(2.0 / 3.0)


def influence_radius(kind: str, intensity, threshold: float, custom: float | None = None) -> float:
    """How far a light reaches (m): ``custom`` if set, else where its inverse-square irradiance
    max(I) / d^2 falls to ``threshold`` / WINDOW_PEAK_LOSS W/m^2, so that its window removes at
    most ``threshold`` anywhere; unbounded (inf) for suns and a threshold of 0. A sphere light's
    and an area light's irradiance stay below I / d^2 (I / (d^2 + r^2) and I A / (A + pi d^2) on
    the axis), so the radius holds for them too."""
    if kind == "SUN":
        return math.inf
    if custom is not None and custom > 0.0:
        return float(custom)
    peak = max(float(max(intensity)), 0.0)
    if threshold <= 0.0:
        return math.inf
    return math.sqrt(peak * WINDOW_PEAK_LOSS / threshold)


def screen_boxes(centres: np.ndarray, radii: np.ndarray, view_projection: np.ndarray,
                 width: int, height: int) -> np.ndarray:
    """(n, 4) pixel boxes (x0, y0, x1, y1) covering the spheres' projections; a sphere whose box
    reaches behind the camera covers the whole screen."""
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float64)
    corners = centres[:, None, :] + signs[None] * radii[:, None, None]  # (n, 8, 3)
    clip = np.concatenate([corners, np.ones(corners.shape[:2] + (1,))], axis=-1) @ view_projection.T
    w = clip[..., 3]
    behind = (w <= 1e-6).any(axis=1)
    w = np.where(w > 1e-6, w, 1.0)
    px = (clip[..., 0] / w * 0.5 + 0.5) * width
    py = (clip[..., 1] / w * 0.5 + 0.5) * height
    boxes = np.stack([px.min(1), py.min(1), px.max(1), py.max(1)], axis=1)
    boxes[behind] = (0.0, 0.0, width, height)
    return boxes


def tile_lists(centres, radii, view_projection, width: int, height: int, tile: int) -> TileLists:
    """The lights' tile lists for a ``width`` x ``height`` target seen through ``view_projection``
    (lights at ``centres``, reaching ``radii``, inf: everywhere)."""
    centres = np.asarray(centres, np.float64).reshape(-1, 3)
    radii = np.asarray(radii, np.float64).reshape(-1)
    n = len(radii)
    columns, rows = -(-width // tile), -(-height // tile)
    # int32 throughout: the pairs' arrays are tens of thousands long, made afresh each frame
    x0 = np.zeros(n, np.int32)
    y0 = np.zeros(n, np.int32)
    x1 = np.full(n, columns, np.int32)
    y1 = np.full(n, rows, np.int32)
    vp = np.asarray(view_projection, np.float64)
    bounded = np.isfinite(radii)
    if not _orthographic(vp) and bounded.any():
        # a sphere that holds the camera's centre meets every tile's frustum (they share its
        # apex): listed everywhere without the tests (often the scene's few large lights)
        bounded &= np.linalg.norm(centres - _camera_centre(invert(vp)), axis=1) > radii
    if bounded.any():
        boxes = screen_boxes(centres[bounded], radii[bounded], vp, width, height)
        x0[bounded] = np.clip(np.floor(boxes[:, 0] / tile), 0, columns)
        y0[bounded] = np.clip(np.floor(boxes[:, 1] / tile), 0, rows)
        x1[bounded] = np.clip(np.floor(boxes[:, 2] / tile) + 1, 0, columns)
        y1[bounded] = np.clip(np.floor(boxes[:, 3] / tile) + 1, 0, rows)
    spans_x, spans_y = np.maximum(x1 - x0, 0), np.maximum(y1 - y0, 0)
    counts = spans_x * spans_y
    total = int(counts.sum())
    if total > MAX_ENTRIES:  # too many to list: one tile, every light
        return _one_list(n)
    light, tx, ty = _box_pairs(x0, y0, spans_x, spans_y)
    tested = bounded[light]
    if total <= SPHERE_TESTED and tested.any():
        edges = _tile_edges(tile, width, height, columns, rows)
        finite = np.where(bounded, radii, 0.0)
        every = bool(tested.all())  # (often: no sun among the lights)
        pairs = (light, tx, ty) if every else (light[tested], tx[tested], ty[tested])
        met = _within_tile_bound(centres, finite, *pairs, edges, vp)
        if not _orthographic(vp):  # (orthographic: the rectangle is exact, the planes add nothing)
            met &= _meets_tile(centres, finite, *pairs, edges, vp)
        if every:
            keep = met
        else:
            keep = ~tested
            keep[tested] = met
        light, tx, ty = light[keep], tx[keep], ty[keep]
    tiles = ty * columns + tx
    # by tile, lights in their own order within one (16-bit keys sort by radix: ~5x faster)
    order = np.argsort(tiles.astype(np.uint16) if columns * rows <= 1 << 16 else tiles, kind="stable")
    per_tile = np.bincount(tiles, minlength=columns * rows)
    first = np.concatenate([[0], np.cumsum(per_tile)[:-1]])
    header = np.stack([first, per_tile], axis=-1).reshape(rows, columns, 2).astype(np.float32)
    return TileLists(tile, header, _padded(light[order]))


def lists_pay(tiles: TileLists, lights: int) -> bool:
    """Whether a view's tile lists save more than they cost: where its tiles leave out at least
    SKIPPED_TO_PAY of the ``lights`` on average. A fragment reads its tile's list (a gather a
    light on the software rasteriser: glsl/README.md) and shades each listed light; without lists it
    shades every light, two or fewer each by its own call (programs.light_sequence). Measured
    (640 x 360, frames, in-process alternating medians, culling on / off): hdr's two point lights,
    6.5 % left out, 1.06x; softbox's two area lights with Custom Distance 5 m, 8 % left out, 1.03x;
    4 m, 20 %, 1.00x; 3 m, 31 %, its shading 0.84x; 1.5 m, 79 %, 0.68x."""
    return lights > 0 and tiles.mean_listed <= (1.0 - SKIPPED_TO_PAY) * lights


def _box_pairs(x0, y0, spans_x, spans_y):
    """(light, tx, ty) of every tile in each light's box (columns x0 + [0, spans_x), rows y0 +
    [0, spans_y)), light by light, each box row by row: made from the boxes' rows (a few
    thousand), without a division per pair."""
    n = len(x0)
    row_light = np.repeat(np.arange(n, dtype=np.int32), spans_y)  # one per (light, row)
    row_start = np.cumsum(spans_y, dtype=np.int32) - spans_y
    row = y0[row_light] + (np.arange(len(row_light), dtype=np.int32) - row_start[row_light])
    widths = spans_x[row_light]
    light = np.repeat(row_light, widths)
    # each row's first pair is its box's column x0
    pair_start = np.cumsum(widths, dtype=np.int32) - widths
    tx = np.arange(len(light), dtype=np.int32) - np.repeat(pair_start - x0[row_light], widths)
    return light, tx, np.repeat(row, widths)


def _camera_centre(inverse: np.ndarray) -> np.ndarray:
    """A perspective view's centre of projection, from its view-projection's inverse: the point
    where clip x = y = w = 0."""
    eye = inverse @ np.array([0.0, 0.0, 1.0, 0.0])
    return eye[:3] / eye[3]


def _orthographic(vp: np.ndarray) -> bool:
    return bool(np.allclose(vp[3, :3], 0.0))


def _tile_edges(tile: int, width: int, height: int, columns: int, rows: int):
    """The tiles' edges in ndc: x of columns + 1 vertical edges, y of rows + 1 horizontal ones."""
    xs = np.minimum(np.arange(columns + 1) * tile, width) / width * 2.0 - 1.0
    ys = np.minimum(np.arange(rows + 1) * tile, height) / height * 2.0 - 1.0
    return xs, ys


def _meets_tile(centres, radii, light, tx, ty, edges, vp: np.ndarray) -> np.ndarray:
    """Whether sphere ``light`` reaches the frustum of tile (tx, ty), for each pair: inside or
    within r of each of the tile's four side planes (x = x0 w, x = x1 w, y = y0 w, y = y1 w in
    clip space, as world planes from the view-projection's rows). Conservative: near a frustum's
    edges a sphere outside it can pass; none inside fails."""
    xs, ys = edges
    # each edge's plane normal's length (per edge, not per pair)
    nx = np.linalg.norm(vp[0, :3][None] - xs[:, None] * vp[3, :3][None], axis=1)
    ny = np.linalg.norm(vp[1, :3][None] - ys[:, None] * vp[3, :3][None], axis=1)
    clip = centres @ vp[(0, 1, 3), :3].T + vp[(0, 1, 3), 3]  # the centres' clip x, y, w, per light
    rx, ry, rw = (clip[:, i].take(light) for i in range(3))
    r = radii.take(light)
    return ((rx - xs.take(tx) * rw >= -r * nx.take(tx))
            & (xs.take(tx + 1) * rw - rx >= -r * nx.take(tx + 1))
            & (ry - ys.take(ty) * rw >= -r * ny.take(ty))
            & (ys.take(ty + 1) * rw - ry >= -r * ny.take(ty + 1)))


def _within_tile_bound(centres, radii, light, tx, ty, edges, vp: np.ndarray) -> np.ndarray:
    """Whether sphere ``light`` meets a tighter bound of tile (tx, ty)'s frustum than its side
    planes (which let a sphere near a corner through: it meets all four planes and misses the
    tile), exactly: for a perspective view, the narrowest cone about the tile's centre ray that
    holds its four corner rays (apex at the camera), met iff the angle between the cone's axis
    and the sphere's centre is within the cone's half-angle plus the sphere's angular radius (two
    cones with one apex meet iff so); for an orthographic view, the tile's rectangle in the view
    plane, met iff the sphere's centre lies within its radius of it."""
    xs, ys = edges
    if _orthographic(vp):  # parallel rays: the rectangle is exact
        w = centres @ vp[3, :3] + vp[3, 3]
        cx, cy = ((centres @ vp[i, :3] + vp[i, 3]) / w for i in (0, 1))  # the centres' ndc
        # world units per unit of ndc along the view's x and y (the camera's axes)
        sx, sy = (1.0 / np.linalg.norm(vp[i, :3]) for i in (0, 1))
        # the squared distances per light and column, and per light and row (tables a few
        # thousand entries large, where the pairs are tens of thousands), read per pair
        dx = np.maximum(np.maximum(xs[None, :-1] - cx[:, None], cx[:, None] - xs[None, 1:]), 0.0) * sx
        dy = np.maximum(np.maximum(ys[None, :-1] - cy[:, None], cy[:, None] - ys[None, 1:]), 0.0) * sy
        reach = radii ** 2 * (1.0 + 1e-9)  # rounding keeps a tangent sphere
        return ((dx * dx).take(light * dx.shape[1] + tx) + (dy * dy).take(light * dy.shape[1] + ty)
                <= reach.take(light))

    eye, axis, half_angle = _tile_cones(vp.tobytes(), xs.tobytes(), ys.tobytes())
    v = centres - eye  # per light
    dist = np.linalg.norm(v, axis=1)
    reach = np.arcsin(np.clip(radii / np.maximum(dist, 1e-300), 0.0, 1.0))
    unit = v / np.maximum(dist, 1e-300)[:, None]
    tile = ty * axis.shape[1] + tx
    axes = axis.reshape(-1, 3)
    # per pair by flat reads of small tables (each component apart: no (pairs, 3) arrays)
    cosine = unit[:, 0].take(light) * axes[:, 0].take(tile)
    for i in (1, 2):
        cosine += unit[:, i].take(light) * axes[:, i].take(tile)
    angle = np.arccos(np.clip(cosine, -1.0, 1.0))
    inside = dist.take(light) <= radii.take(light)
    # (rounding, as above)
    return inside | (angle <= half_angle.reshape(-1).take(tile) + reach.take(light) + 1e-9)


@lru_cache(maxsize=4)
def _tile_cones(vp_bytes: bytes, xs_bytes: bytes, ys_bytes: bytes):
    """(the camera's centre, each tile's cone axis (rows, columns, 3) and half-angle (rows,
    columns)) for a perspective view-projection and the tiles' ndc edges (as bytes, to be kept
    by them: a view's renders and passes ask again, and the cones are most of the lists' work)."""
    vp = np.frombuffer(vp_bytes).reshape(4, 4)
    xs, ys = np.frombuffer(xs_bytes), np.frombuffer(ys_bytes)
    inverse = invert(vp)

    def unproject(x, y):  # points on the rays through ndc (x, y), at ndc depth 0
        q = np.stack([x, y, np.zeros_like(x), np.ones_like(x)], axis=-1) @ inverse.T
        return q[..., :3] / q[..., 3:]

    eye = _camera_centre(inverse)
    columns, rows = len(xs) - 1, len(ys) - 1
    cx, cy = np.meshgrid(0.5 * (xs[:-1] + xs[1:]), 0.5 * (ys[:-1] + ys[1:]))  # (rows, columns)
    axis = unproject(cx, cy) - eye
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    cos_half = np.ones(cx.shape)
    for ix, iy in ((0, 0), (1, 0), (0, 1), (1, 1)):
        gx, gy = np.meshgrid(xs[ix:columns + ix], ys[iy:rows + iy])
        corner = unproject(gx, gy) - eye
        corner /= np.linalg.norm(corner, axis=-1, keepdims=True)
        cos_half = np.minimum(cos_half, np.sum(corner * axis, axis=-1))
    half_angle = np.arccos(np.clip(cos_half, -1.0, 1.0))
    for array in (eye, axis, half_angle):
        array.flags.writeable = False  # shared by every caller
    return eye, axis, half_angle


def _one_list(n: int) -> TileLists:
    header = np.array([[[0.0, float(n)]]], np.float32)
    return TileLists(1 << 24, header, _padded(np.arange(n)))


def _padded(entries: np.ndarray) -> np.ndarray:
    list_rows = max(-(-len(entries) // LIST_WIDTH), 1)
    out = np.zeros(list_rows * LIST_WIDTH, np.float32)
    out[:len(entries)] = entries
    return out.reshape(list_rows, LIST_WIDTH)
