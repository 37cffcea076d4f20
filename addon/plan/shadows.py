"""Where each light's shadow maps look: one layer of a 2D-array depth texture per map, a
projection per layer, chosen from the lights and the scene's bounds. Pure numpy (no ``bpy`` or
``gpu``): the shadow pass (``passes.ShadowPass``) draws the layers, the shading programs
(glsl/shadows.glsl) read them.

- A **sun** has one orthographic map along its direction, fitted to the bounds of everything
  that casts or receives (so it does not change while the camera moves) -- or, where the camera
  sees deep into the scene (the drawn box's far depth over its near one above
  ``CASCADE_DEPTH_RATIO``), ``CASCADES`` maps, each fitted to one slice of the view's depth
  (cascaded shadow maps: fine texels near the camera, coarse far away), which follow the camera.
- A **spot** whose cone fits in 120 degrees has one perspective map over its cone; a wider spot,
  a **point** light and an **area** light have six (a cube's faces, each widened by
  ``FACE_MARGIN`` so that filter taps near a face's edge stay on it).

Each map stores a distance, not the projection's depth: the distance from the light's centre
(perspective maps) or from the map's near plane along the light (orthographic), divided by the
layer's far distance -- so the shading can compare distances in metres, size penumbrae from them
(percentage-closer soft shadows) and evaluate the receiver's plane at each filter tap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene.matrices import cross3, invert
from ..scene.snapshot import Light, Snapshot

#: Layers one frame may use (a point light takes six): lights beyond them cast no shadow (a warning
#: says so). The uniform block holds 160 bytes per layer.
MAX_SHADOW_LAYERS = 48
#: tan(half the field of view) of a cube face: 1 would be exactly 90 degrees.
FACE_MARGIN = 1.08
#: The widest spot drawn in one map; wider cones use six.
MAX_SPOT_ANGLE = math.radians(120.0)
#: The cube's faces: (axis the face looks along, its up vector), in the order shadows.glsl picks.
CUBE_FACES = (((1, 0, 0), (0, -1, 0)), ((-1, 0, 0), (0, -1, 0)), ((0, 1, 0), (0, 0, 1)),
              ((0, -1, 0), (0, 0, -1)), ((0, 0, 1), (0, -1, 0)), ((0, 0, -1), (0, -1, 0)))
KIND_CUBE, KIND_PERSPECTIVE, KIND_ORTHOGRAPHIC = 0.0, 1.0, 2.0
#: A sun's maps when the view is deep, and how deep that is: the far depth of what is drawn over its
#: near depth (the camera's clip start, or the nearest drawn point).
CASCADES = 4
CASCADE_DEPTH_RATIO = 8.0
#: The cascades' split between logarithmic (1) and uniform (0) depths (Zhang et al. 2006's
#: practical split scheme).
CASCADE_SPLIT_LOG = 0.8


@dataclass(frozen=True)
class ShadowPlan:
    """The layers of one frame's shadow maps.

    ``matrices`` (n, 4, 4): world -> clip of each layer (``views`` then the projection, whose
    half extents ``extents`` holds, z a sun's number of cascades in its first layer, w the light's
    shadow Filter in texels, -(Filter + 1) with Jitter on); ``info`` (n, 4): far distance (metres
    per unit of stored depth), the width of one texel per metre of distance (perspective) or in
    metres (orthographic), the light's size for penumbrae (radius in metres; a sun's tan of half
    its angle), and the light's Resolution Limit (m); ``origins`` (n, 4): the light's position
    (perspective) or the map's near-plane centre (orthographic), w the layer's kind. ``first_layer[i]`` is
    light i's first layer, -1 without shadows."""

    size: int
    matrices: np.ndarray
    info: np.ndarray
    origins: np.ndarray
    first_layer: tuple[int, ...]
    views: np.ndarray = None  # (n, 4, 4) world -> the layer's view (camera looking down -Z)
    extents: np.ndarray = None  # (n, 4) x, y: tan of the half field of view, or half widths (m)
    dropped: int = 0  # shadowed lights left out (no layers left)
    box: tuple[np.ndarray, np.ndarray] | None = None  # (min, max): the drawn items' world box, padded

    @property
    def layers(self) -> int:
        return len(self.matrices)

    def key(self) -> bytes:
        """Changes whenever a map must be drawn again for the same casters."""
        return (np.int64(self.size).tobytes() + self.matrices.tobytes() + self.info.tobytes()
                + self.origins.tobytes())


def look_at(eye, forward, up) -> np.ndarray:
    """World -> view (the view looking along ``forward``, -Z, with ``up`` as +Y as far as it can)."""
    f = np.asarray(forward, np.float64)
    f = f / np.linalg.norm(f)
    up = np.asarray(up, np.float64)
    if abs(float(np.dot(up, f))) > 0.999:
        up = np.array([1.0, 0.0, 0.0]) if abs(f[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    r = cross3(f, up)
    r /= np.linalg.norm(r)
    u = cross3(r, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = r, u, -f
    m[:3, 3] = -m[:3, :3] @ np.asarray(eye, np.float64)
    return m


def perspective(tan_half: float, near: float, far: float) -> np.ndarray:
    """OpenGL's symmetric perspective with square aspect."""
    m = np.zeros((4, 4))
    m[0, 0] = m[1, 1] = 1.0 / tan_half
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def orthographic(half_x: float, half_y: float, far: float) -> np.ndarray:
    """OpenGL's orthographic projection of x in [-half_x, half_x], y likewise, depth [0, far]."""
    m = np.eye(4)
    m[0, 0], m[1, 1] = 1.0 / half_x, 1.0 / half_y
    m[2, 2], m[2, 3] = -2.0 / far, -1.0
    return m


def scene_bounds(snapshot: Snapshot, bounds: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray] | None:
    """World-space box (min, max) around every drawn item, from each geometry's object-space box
    ``bounds[key]`` ((2, 3) min and max); None for an empty scene."""
    corners = []
    for item in snapshot.items:
        box = bounds.get(item.geometry)
        if box is None:
            continue
        c = np.array([[box[i][0], box[j][1], box[k][2], 1.0]
                      for i in (0, 1) for j in (0, 1) for k in (0, 1)])
        corners.append((np.asarray(item.matrix, np.float64) @ c.T).T[:, :3])
    if not corners:
        return None
    points = np.concatenate(corners)
    return points.min(0), points.max(0)


def box_corners(lo, hi) -> np.ndarray:
    """(8, 3) the corners of the box (lo, hi), corner i taking hi's coordinate where its bit (4, 2, 1:
    x, y, z) is set."""
    return np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                     for i in (0, 1) for j in (0, 1) for k in (0, 1)], np.float64)


def _far_near(position, lo, hi) -> tuple[float, float]:
    """Near and far distances of a perspective map at ``position`` that hold the whole box."""
    corners = box_corners(lo, hi)
    far = float(np.linalg.norm(corners - np.asarray(position), axis=1).max()) * 1.01 + 1e-3
    near = max(far * 1e-4, 1e-3)
    return near, far


def _filter_code(light: Light) -> float:
    """A layer's extents.w: the light's shadow Filter (texels), stored as -(Filter + 1) with Jitter
    on (glsl/shadows.glsl: twice the filter taps)."""
    return -(light.shadow_filter + 1.0) if light.shadow_jitter else light.shadow_filter


def penumbra_size(light: Light) -> float:
    """What sizes the light's penumbrae (a layer's info z): a sun's tan of half its angle, else
    its radius (m); 0: hard shadows whatever the Soft Shadows setting."""
    return math.tan(0.5 * light.angle) if light.kind == "SUN" else float(light.radius)


def _sun_view(light: Light, lo, hi) -> np.ndarray:
    return look_at(0.5 * (lo + hi), np.asarray(light.direction, np.float64), (0.0, 0.0, 1.0))


def _sun_layer(light: Light, lo, hi, size: int, region=None, cascades: int = 1):
    """One orthographic map along the sun over the box (lo, hi), or over ``region`` (points, world)
    where it lies within the box's shadow of the sun; its depth always spans the whole box (every
    caster upstream). ``cascades``: the sun's number of maps, kept in its first map's extents."""
    direction = np.asarray(light.direction, np.float64)
    view = _sun_view(light, lo, hi)
    points = (view[:3, :3] @ box_corners(lo, hi).T).T + view[:3, 3]
    x_lo, x_hi = points[:, 0].min(), points[:, 0].max()
    y_lo, y_hi = points[:, 1].min(), points[:, 1].max()
    if region is not None:
        seen = (view[:3, :3] @ np.asarray(region, np.float64).T).T + view[:3, 3]
        x_lo, x_hi = max(x_lo, seen[:, 0].min()), min(x_hi, seen[:, 0].max())
        y_lo, y_hi = max(y_lo, seen[:, 1].min()), min(y_hi, seen[:, 1].max())
        x_hi, y_hi = max(x_hi, x_lo + 1e-3), max(y_hi, y_lo + 1e-3)
    centre_x, centre_y = 0.5 * (x_lo + x_hi), 0.5 * (y_lo + y_hi)
    half_x = max(0.5 * (x_hi - x_lo), 1e-3)
    half_y = max(0.5 * (y_hi - y_lo), 1e-3)
    # room for the filter at the box's edge: a few texels
    half_x *= 1.0 + 8.0 / size
    half_y *= 1.0 + 8.0 / size
    top = float(points[:, 2].max()) + 1e-3  # view space looks down -Z: the box's side nearest the sun
    depth = max(top - float(points[:, 2].min()) + 2e-3, 1e-3)
    to_world = invert(view)
    near_centre = (to_world @ np.array([centre_x, centre_y, top, 1.0]))[:3]  # the map's near plane
    view = look_at(near_centre, direction, (0.0, 0.0, 1.0))
    matrix = orthographic(half_x, half_y, depth) @ view
    texel = 2.0 * max(half_x, half_y) / size
    return [(matrix, (depth, texel, penumbra_size(light), light.shadow_resolution_limit),
             (*near_centre, KIND_ORTHOGRAPHIC), view, (half_x, half_y, float(cascades), _filter_code(light)))]


def view_depths(camera, lo, hi) -> tuple[float, float] | None:
    """(near, far) depth along a perspective camera of what lies in the box (lo, hi), within its
    clip range; None for an orthographic camera (its view is never deep)."""
    if camera is None or not camera.is_perspective:
        return None
    projection = np.asarray(camera.projection, np.float64)
    a, b = projection[2, 2], projection[2, 3]
    clip_start, clip_end = b / (a - 1.0), b / (a + 1.0)
    corners = box_corners(lo, hi)
    view = np.asarray(camera.view, np.float64)
    depth = -((view[:3, :3] @ corners.T).T + view[:3, 3])[:, 2]
    far = min(float(depth.max()), clip_end)
    near = max(float(depth.min()), clip_start, 1e-4 * far)
    return (near, far) if far > near else None


def cascade_splits(near: float, far: float, count: int = CASCADES) -> np.ndarray:
    """count + 1 depths from near to far: the practical split scheme, CASCADE_SPLIT_LOG between
    logarithmic and uniform."""
    i = np.arange(count + 1) / count
    uniform = near + (far - near) * i
    return CASCADE_SPLIT_LOG * near * (far / near) ** i + (1.0 - CASCADE_SPLIT_LOG) * uniform


def _frustum_slice(camera, near: float, far: float) -> np.ndarray:
    """(8, 3): the world corners of a perspective camera's view between two depths."""
    projection = np.asarray(camera.projection, np.float64)
    # x_ndc = (P00 x + P02 z) / -z: at depth d the view spans x in d (-1 -+ P02) / P00
    corners = []
    for d in (near, far):
        for sx in (-1.0, 1.0):
            for sy in (-1.0, 1.0):
                x = d * (sx + projection[0, 2]) / projection[0, 0]
                y = d * (sy + projection[1, 2]) / projection[1, 1]
                corners.append((x, y, -d, 1.0))
    to_world = invert(np.asarray(camera.view, np.float64))
    return (to_world @ np.array(corners).T).T[:, :3]


def _sun_layers(light: Light, lo, hi, size: int, camera, depths) -> list:
    """A sun's maps: one over the box, or CASCADES over the slices of the view's depths."""
    if depths is None:
        return _sun_layer(light, lo, hi, size)
    splits = cascade_splits(*depths)
    layers = []
    for i in range(CASCADES):
        region = _frustum_slice(camera, splits[i], splits[i + 1])
        layers += _sun_layer(light, lo, hi, size, region, CASCADES if i == 0 else 0)
    return layers


def _perspective_layers(light: Light, lo, hi, size: int, cube: bool):
    position = np.asarray(light.position, np.float64)
    near, far = _far_near(position, lo, hi)
    if cube:
        tan_half = FACE_MARGIN
        faces = CUBE_FACES
        kind = KIND_CUBE
    else:
        half = math.acos(max(min(light.spot_cos_half, 1.0), -1.0))
        tan_half = math.tan(half) * (1.0 + 8.0 / size) + 2.0 / size
        faces = ((light.direction, (0.0, 0.0, 1.0)),)
        kind = KIND_PERSPECTIVE
    projection = perspective(tan_half, near, far)
    texel = 2.0 * tan_half / size
    layers = []
    for forward, up in faces:
        view = look_at(position, forward, up)
        layers.append((projection @ view, (far, texel, penumbra_size(light), light.shadow_resolution_limit),
                       (*position, kind), view, (tan_half, tan_half, 0.0, _filter_code(light))))
    return layers


def _cube(light: Light) -> bool:
    return light.kind != "SPOT" or 2.0 * math.acos(max(min(light.spot_cos_half, 1.0), -1.0)) > MAX_SPOT_ANGLE


def _layer_count(light: Light, deep: bool) -> int:
    if light.kind == "SUN":
        return CASCADES if deep else 1
    return 6 if _cube(light) else 1


def assign(snapshot: Snapshot, deep: bool = False) -> tuple[tuple[int, ...], int, int]:
    """(each light's first layer or -1, layers used, shadowed lights dropped): nothing when shadows
    are off, no light casts or nothing casts; else the shadowed lights in order while
    ``MAX_SHADOW_LAYERS`` last (a sun one, or CASCADES where the view is ``deep``; a spot up to 120
    degrees one; the others six)."""
    first = [-1] * len(snapshot.lights)
    if not snapshot.settings.shadows or not any(item.casts_shadow for item in snapshot.items):
        return tuple(first), 0, 0
    used = dropped = 0
    for i, light in enumerate(snapshot.lights):
        if not light.shadow:
            continue
        count = _layer_count(light, deep)
        if used + count > MAX_SHADOW_LAYERS:
            dropped += 1
            continue
        first[i], used = used, used + count
    return tuple(first), used, dropped


def deep_view(snapshot: Snapshot, lo, hi):
    """The view's (near, far) depths over the drawn box where it is deep enough for a sun's
    cascades (far / near > CASCADE_DEPTH_RATIO, a perspective camera, a sun that casts), else None."""
    if not any(light.kind == "SUN" and light.shadow for light in snapshot.lights):
        return None
    depths = view_depths(snapshot.camera, lo, hi)
    return depths if depths is not None and depths[1] > CASCADE_DEPTH_RATIO * depths[0] else None


def plan(snapshot: Snapshot, bounds: dict[str, np.ndarray]) -> ShadowPlan:
    """The shadow maps ``snapshot`` needs (see ``assign``), fitted to the scene's bounds
    (``bounds[key]``: each geometry's object-space (min, max)) and, for cascaded suns, to the view."""
    size = int(snapshot.settings.shadow_map_size)
    first, used, dropped = assign(snapshot)
    box = scene_bounds(snapshot, bounds) if used else None
    if box is None:
        return ShadowPlan(size, np.zeros((0, 4, 4), np.float32), np.zeros((0, 4), np.float32),
                          np.zeros((0, 4), np.float32), tuple(-1 for _ in first),
                          views=np.zeros((0, 4, 4), np.float32), extents=np.zeros((0, 4), np.float32),
                          dropped=dropped)
    lo, hi = box
    pad = 1e-3 * max(float(np.max(hi - lo)), 1.0)
    lo, hi = lo - pad, hi + pad
    depths = deep_view(snapshot, lo, hi)
    if depths is not None:
        first, used, dropped = assign(snapshot, deep=True)
    layers = []
    for light, start in zip(snapshot.lights, first):
        if start < 0:
            continue
        if light.kind == "SUN":
            layers += _sun_layers(light, lo, hi, size, snapshot.camera, depths)
        else:
            layers += _perspective_layers(light, lo, hi, size, _cube(light))
    matrices, info, origins, views, extents = zip(*layers)
    return ShadowPlan(size, np.stack(matrices).astype(np.float32), np.array(info, np.float32),
                      np.array(origins, np.float32), first, views=np.stack(views).astype(np.float32),
                      extents=np.array(extents, np.float32), dropped=dropped, box=(lo, hi))


def bounding_spheres(boxes: np.ndarray, matrices: np.ndarray) -> np.ndarray:
    """(n, 4) world-space spheres (centre, radius) holding object-space boxes ``boxes`` (n, 2, 3:
    min, max) under ``matrices`` (n, 4, 4, object -> world): the box's centre moved, its half
    diagonal scaled by the matrix's largest axis scale."""
    boxes = np.asarray(boxes, np.float64).reshape(-1, 2, 3)
    matrices = np.asarray(matrices, np.float64).reshape(-1, 4, 4)
    centre = 0.5 * (boxes[:, 0] + boxes[:, 1])
    half = 0.5 * np.linalg.norm(boxes[:, 1] - boxes[:, 0], axis=1)
    world = np.einsum("nij,nj->ni", matrices[:, :3, :3], centre) + matrices[:, :3, 3]
    scale = np.linalg.norm(matrices[:, :3, :3], axis=1).max(axis=1)  # the columns' lengths
    return np.column_stack([world, half * scale])


def layer_casters(matrices: np.ndarray, spheres: np.ndarray) -> np.ndarray:
    """(layers, n) bool: which casters (world spheres, ``bounding_spheres``) reach each layer's
    clip volume (``matrices``, world -> clip): not wholly outside one of its six planes (Gribb &
    Hartmann 2001, the planes from the matrix's rows: w +- x, w +- y, w +- z >= 0). A caster
    wholly outside would be clipped away in the layer's map, so leaving it out draws the same
    map; a sphere meeting a plane's outside near a corner is kept (conservative)."""
    m = np.asarray(matrices, np.float64).reshape(-1, 4, 4)
    planes = np.concatenate([m[:, 3:4] + m[:, :3], m[:, 3:4] - m[:, :3]], axis=1)  # (layers, 6, 4)
    return _within_planes(planes, np.asarray(spheres, np.float64).reshape(-1, 4))


def _within_planes(planes: np.ndarray, spheres: np.ndarray) -> np.ndarray:
    """(layers, n) bool: which spheres (n, 4) are not wholly outside any of each layer's planes
    ((layers, p, 4), inside: n.x + d >= 0, n not normalised)."""
    norms = np.linalg.norm(planes[..., :3], axis=-1)  # (layers, p)
    signed = np.einsum("lpk,nk->lpn", planes[..., :3], spheres[:, :3]) + planes[..., 3:4]
    return np.all(signed >= -(spheres[:, 3][None, None] * norms[..., None]), axis=1)


#: How far from a receiver's own position a shadow lookup reads its map, in texels: the penumbra's
#: blocker search and filter reach SHADOW_MAX_RADIUS (48, glsl/shadows.glsl) at most, a tap's
#: bilinear filter one texel beyond, rounded up (tests/test_shadows.py reads the GLSL's value).
LOOKUP_REACH = 50

#: The 12 edges of a box or frustum whose 8 corners are indexed by 3 bits (``box_corners``' order,
#: the clip volume's corners in ``visible_region``): pairs of corners differing in one bit.
_EDGES = np.array([(a, a | bit) for bit in (1, 2, 4) for a in range(8) if not a & bit])


def _edge_crossings(corners: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """(m, 3): where the edges of a box-like solid (``corners`` (8, 3), ``_EDGES``) cross
    ``planes`` ((p, 4), n.x + d = 0)."""
    a, b = corners[_EDGES[:, 0]], corners[_EDGES[:, 1]]  # (12, 3)
    da = a @ planes[:, :3].T + planes[:, 3]  # (12, p)
    db = b @ planes[:, :3].T + planes[:, 3]
    cross = (da * db <= 0.0) & (da != db)
    t = np.divide(da, da - db, out=np.zeros_like(da), where=cross)
    points = a[:, None] + t[..., None] * (b - a)[:, None]  # (12, p, 3)
    return points[cross]


def visible_region(view_projection: np.ndarray, lo, hi) -> np.ndarray | None:
    """(k, 3) world points whose convex hull holds every point of the box (lo, hi) that a view
    (``view_projection``: world -> clip) sees: the vertices of the box clipped to the view's clip
    volume (each solid's corners inside the other, each one's edges across the other's faces).
    Empty where the view sees none of the box; None where the clip volume is not a bounded
    solid (a projection without an inverse)."""
    m = np.asarray(view_projection, np.float64)
    try:
        to_world = invert(m)
    except (ValueError, np.linalg.LinAlgError):
        return None
    ndc = np.concatenate([box_corners(-np.ones(3), np.ones(3)), np.ones((8, 1))], axis=1)
    corners = ndc @ to_world.T
    if not np.all(np.isfinite(corners)) or np.any(corners[:, 3] <= 0.0):
        return None
    view_corners = corners[:, :3] / corners[:, 3:]
    view_planes = np.concatenate([m[3:4] + m[:3], m[3:4] - m[:3]])  # (6, 4): inside >= 0
    view_planes /= np.maximum(np.linalg.norm(view_planes[:, :3], axis=1), 1e-300)[:, None]
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    eye = np.eye(3)
    box_planes = np.concatenate([np.column_stack([eye, -lo]), np.column_stack([-eye, hi])])
    solid = box_corners(lo, hi)
    eps = 1e-6 * max(float(np.max(hi - lo)), 1.0)
    if np.all(solid @ view_planes[:, :3].T + view_planes[:, 3] >= -eps):
        return solid  # the whole box in view
    candidates = np.concatenate([view_corners, solid, _edge_crossings(view_corners, box_planes),
                                 _edge_crossings(solid, view_planes)])
    inside = np.all(candidates @ view_planes[:, :3].T + view_planes[:, 3] >= -eps, axis=1) & \
        np.all(candidates @ box_planes[:, :3].T + box_planes[:, 3] >= -eps, axis=1)
    return candidates[inside]


def _map_rectangles(clip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per layer, the (lo, hi) normalised device xy of the convex hull of points given in its clip
    coordinates (``clip``: (layers, k, 4)) clipped to the side of its eye's plane it looks into
    (w > 0: the points there and, where some are not, each segment between two points across
    the plane cut at it -- the hull's edges among them); lo > hi where no point lies there."""
    w = clip[..., 3]
    eps = 1e-6 * np.abs(w).max(axis=1, keepdims=True) + 1e-12  # (layers, 1)
    front = w >= eps
    ndc = clip[..., :2] / np.where(front, w, 1.0)[..., None]
    lo = np.where(front[..., None], ndc, np.inf).min(axis=1)
    hi = np.where(front[..., None], ndc, -np.inf).max(axis=1)
    across = np.flatnonzero(front.any(axis=1) & ~front.all(axis=1))  # layers whose eye's plane cuts it
    if len(across):
        c, wa, e = clip[across], w[across], eps[across][..., None]  # (a, k, 4), (a, k), (a, 1, 1)
        pair = (wa[:, :, None] >= e) & (wa[:, None, :] < e)  # (a, k, k): i in front, j behind
        t = np.divide(wa[:, :, None] - e, wa[:, :, None] - wa[:, None, :], out=np.zeros(pair.shape),
                      where=pair)
        cut = c[:, :, None, :] + t[..., None] * (c[:, None, :, :] - c[:, :, None, :])  # (a, k, k, 4)
        cut_ndc = cut[..., :2] / np.where(pair, cut[..., 3], 1.0)[..., None]
        lo[across] = np.minimum(lo[across], np.where(pair[..., None], cut_ndc, np.inf).min(axis=(1, 2)))
        hi[across] = np.maximum(hi[across], np.where(pair[..., None], cut_ndc, -np.inf).max(axis=(1, 2)))
    return lo, hi


def receiving_casters(matrices: np.ndarray, size: int, spheres: np.ndarray, regions: list) -> np.ndarray:
    """(layers, n) bool: which casters (world spheres, ``bounding_spheres``) a layer's map holds
    where a shadow lookup from a point the views see can read it: the caster's sphere not wholly
    beyond the rectangle of the map that holds the views' ``regions`` (``visible_region``; any of
    them None holds everything), widened by ``LOOKUP_REACH`` texels. The lookups of the points the
    views see read only there, so a caster left out elsewhere (its shadow falls where no view
    looks) changes no pixel. No test of depth: a receiver's plane, extrapolated over the filter's
    texels, can pass behind a caster beyond every visible point."""
    m = np.asarray(matrices, np.float64).reshape(-1, 4, 4)
    spheres = np.asarray(spheres, np.float64).reshape(-1, 4)
    out = np.zeros((len(m), len(spheres)), bool)
    if any(region is None for region in regions):
        return ~out
    reach = LOOKUP_REACH * 2.0 / size
    rows, w_row = m[:, :2], m[:, 3:4]  # (layers, 2, 4), (layers, 1, 4)
    for region in regions:
        if not len(region) or not len(spheres):
            continue
        homogeneous = np.concatenate([region, np.ones((len(region), 1))], axis=1)
        lo, hi = _map_rectangles(np.einsum("lij,pj->lpi", m, homogeneous))
        whole = np.all(lo <= -1.0, axis=1) & np.all(hi >= 1.0, axis=1)  # the whole map: every caster
        out[whole] = True
        part = np.flatnonzero(np.all(lo <= hi, axis=1) & ~whole)
        if not len(part):
            continue
        lo = np.maximum(lo[part], -1.0) - reach
        hi = np.minimum(hi[part], 1.0) + reach
        planes = np.concatenate([rows[part] - lo[..., None] * w_row[part],
                                 hi[..., None] * w_row[part] - rows[part]], axis=1)
        out[part] |= _within_planes(planes, spheres)
    return out


#: A sun's cascade serves a point only where the finer cascades cannot hold it this many texels
#: inside their edges (glsl/shadows.glsl's SHADOW_CASCADE_ROOM: room for the filter).
CASCADE_ROOM = 32


def finer_cascades_hold(plan: ShadowPlan, spheres: np.ndarray) -> np.ndarray:
    """(layers, n) bool: the casters (world spheres, ``bounding_spheres``) a sun's cascade can
    leave out because no lookup reads them there. A point reads the finest cascade that holds it
    ``CASCADE_ROOM`` texels inside its edges (glsl/shadows.glsl's sun_shadow_point; the cascades
    share the sun's rotation, so "across" coordinates are the same in each); a lookup in cascade k
    reads within ``LOOKUP_REACH`` texels of k of the point. So a caster whose disc across the sun,
    widened by that reach, lies inside a finer cascade's held rectangle is read in cascade k by no
    point: every point near enough to read it is served by the finer one. Casters near the camera
    leave the coarse cascades, whose maps cover the whole view; the same image."""
    spheres = np.asarray(spheres, np.float64).reshape(-1, 4)
    out = np.zeros((plan.layers, len(spheres)), bool)
    for first in plan.first_layer:
        if first < 0 or plan.origins[first][3] != KIND_ORTHOGRAPHIC:
            continue
        count = int(round(float(plan.extents[first][2])))
        if count < 2 or not len(spheres):
            continue
        axes = np.asarray(plan.views[first], np.float64)[:2, :3]  # the sun's right and up
        across = spheres[:, :3] @ axes.T  # (n, 2)
        layers = range(first, first + count)
        centres = np.array([axes @ np.asarray(plan.origins[i][:3], np.float64) for i in layers])
        # the held rectangles' half widths, a texel short of them (float32 in the program)
        held = np.array([np.asarray(plan.extents[i][:2], np.float64) * (1.0 - CASCADE_ROOM / plan.size)
                         - float(plan.info[i][1]) for i in layers])
        for k in range(1, count):
            radius = spheres[:, 3] + LOOKUP_REACH * float(plan.info[first + k][1])
            for j in range(k):
                inside = np.all(np.abs(across - centres[j]) + radius[:, None] <= held[j], axis=1)
                out[first + k] |= inside
    return out


#: A box this thin along one of its axes, relative to its largest extent, holds a flat object (a
#: plane): ``shadowless_casters`` may leave it out of the maps.
FLAT = 1e-6


def light_extent(light: Light) -> float:
    """The radius of a sphere about the light's position holding all of its emitting surface: an
    area light's rectangle or ellipse, a point or spot light's sphere (0 for a sun)."""
    if light.kind == "AREA":
        return math.hypot(*light.half_size)
    return 0.0 if light.kind == "SUN" else float(light.radius)


def world_corners(boxes: np.ndarray, matrices: np.ndarray) -> np.ndarray:
    """(n, 8, 3) world corners of object-space boxes ``boxes`` (n, 2, 3) under ``matrices``."""
    boxes = np.asarray(boxes, np.float64).reshape(-1, 2, 3)
    matrices = np.asarray(matrices, np.float64).reshape(-1, 4, 4)
    pick = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])  # (8, 3): min or max
    corners = boxes[:, pick, np.arange(3)]  # (n, 8, 3)
    return np.einsum("nij,nkj->nki", matrices[:, :3, :3], corners) + matrices[:, None, :3, 3]


def flat_planes(boxes: np.ndarray, matrices: np.ndarray) -> np.ndarray:
    """(n, 4) world planes (unit normal, offset: n.x + offset = 0) of the objects whose
    object-space boxes ``boxes`` (n, 2, 3) are flat along an axis (``FLAT``), under ``matrices``
    (n, 4, 4); NaN rows for the others (and for a matrix that flattens the object)."""
    boxes = np.asarray(boxes, np.float64).reshape(-1, 2, 3)
    matrices = np.asarray(matrices, np.float64).reshape(-1, 4, 4)
    out = np.full((len(boxes), 4), np.nan)
    extent = boxes[:, 1] - boxes[:, 0]
    axis = np.argmin(extent, axis=1)
    flat = extent[np.arange(len(boxes)), axis] <= FLAT * np.maximum(extent.max(axis=1), 1e-30)
    m3 = matrices[:, :3, :3]
    flat &= np.abs(np.linalg.det(m3)) > 1e-30
    for i in np.flatnonzero(flat):
        normal = invert(m3[i]).T[:, axis[i]]  # the axis's normal carried to the world
        normal /= np.linalg.norm(normal)
        point = m3[i] @ (0.5 * (boxes[i, 0] + boxes[i, 1])) + matrices[i, :3, 3]
        out[i] = (*normal, -float(normal @ point))
    return out


def shadowless_casters(plan: ShadowPlan, lights, planes: np.ndarray, receivers: np.ndarray) -> np.ndarray:
    """(layers, n) bool: the flat casters (``planes``, ``flat_planes``; NaN rows are not flat)
    that can hide no part of a layer's light from anything: the whole light (``light_extent``; a
    sun's cone of directions) lies on one side of the caster's plane and every object's box
    (``receivers``: (m, 8, 3) world corners) on that side or in the plane. A segment from such a
    point to the light stays on that side, so the caster can shadow nothing (a ground under a
    scene lit from above: on the CPU rasteriser the largest caster of most maps). Left out of a
    layer, its texels hold the far distance instead of the ground's: the ground, tested against
    its own plane, was never behind itself; the one change is near silhouettes at grazing light,
    where a receiver's plane extrapolated over the filter's texels passed behind the ground and
    the ground darkened it (measured on the presets: <= 0.5 % of the pixels, error against Cycles
    unchanged or lower)."""
    out = np.zeros((plan.layers, len(planes)), bool)
    flat = ~np.isnan(planes[:, 0])
    if not flat.any() or not plan.layers:
        return out
    corners = np.asarray(receivers, np.float64).reshape(-1, 3)
    scale = max(float(np.ptp(corners, axis=0).max()) if len(corners) else 1.0, 1.0)
    eps = 1e-5 * scale
    p = planes[flat]
    signed = corners @ p[:, :3].T + p[:, 3]  # (corners, flat casters)
    starts = sorted(s for s in plan.first_layer if s >= 0) + [plan.layers]
    for light, start in zip(lights, plan.first_layer):
        if start < 0:
            continue
        end = starts[starts.index(start) + 1]
        if light.kind == "SUN":  # the light arrives from -direction, within half its angle
            towards = -(p[:, :3] @ np.asarray(light.direction, np.float64))
            clear = np.abs(towards) > math.sin(0.5 * light.angle) + 1e-6
        else:
            towards = p[:, :3] @ np.asarray(light.position, np.float64) + p[:, 3]
            clear = np.abs(towards) > light_extent(light) + eps
        side = np.sign(towards)
        clear &= np.all(signed * side >= -eps, axis=0)
        out[start:end, np.flatnonzero(flat)[clear]] = True
    return out
