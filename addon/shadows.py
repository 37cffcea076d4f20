"""Where each light's shadow maps look: one layer of a 2D-array depth texture per map, a
projection per layer, chosen from the lights and the scene's bounds. Pure numpy (no ``bpy`` or
``gpu``): the shadow pass (``passes.ShadowPass``) draws the layers, the shading programs
(glsl/shadows.glsl) read them.

- A **sun** has one orthographic map along its direction, fitted to the bounds of everything
  that casts or receives (so it does not change while the camera moves).
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

from .snapshot import Light, Snapshot

#: Layers one frame may use (a point light takes six): lights beyond them cast no shadow (a warning
#: says so). The uniform block holds 144 bytes per layer.
MAX_SHADOW_LAYERS = 48
#: tan(half the field of view) of a cube face: 1 would be exactly 90 degrees.
FACE_MARGIN = 1.08
#: The widest spot drawn in one map; wider cones use six.
MAX_SPOT_ANGLE = math.radians(120.0)
#: The cube's faces: (axis the face looks along, its up vector), in the order shadows.glsl picks.
CUBE_FACES = (((1, 0, 0), (0, -1, 0)), ((-1, 0, 0), (0, -1, 0)), ((0, 1, 0), (0, 0, 1)),
              ((0, -1, 0), (0, 0, -1)), ((0, 0, 1), (0, -1, 0)), ((0, 0, -1), (0, -1, 0)))
KIND_CUBE, KIND_PERSPECTIVE, KIND_ORTHOGRAPHIC = 0.0, 1.0, 2.0


@dataclass(frozen=True)
class ShadowPlan:
    """The layers of one frame's shadow maps.

    ``matrices`` (n, 4, 4): world -> clip of each layer (``views`` then the projection, whose
    half extents ``extents`` holds); ``info`` (n, 4): far distance (metres
    per unit of stored depth), the width of one texel per metre of distance (perspective) or in
    metres (orthographic), the light's size for penumbrae (radius in metres; a sun's tan of half
    its angle), and the layer's kind; ``origins`` (n, 4): the light's position (perspective) or
    the map's near-plane centre (orthographic), w the layer's kind again. ``first_layer[i]`` is
    light i's first layer, -1 without shadows."""

    size: int
    matrices: np.ndarray
    info: np.ndarray
    origins: np.ndarray
    first_layer: tuple[int, ...]
    views: np.ndarray = None  # (n, 4, 4) world -> the layer's view (camera looking down -Z)
    extents: np.ndarray = None  # (n, 4) x, y: tan of the half field of view, or half widths (m)
    dropped: int = 0  # shadowed lights left out (no layers left)

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
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
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


def _box_corners(lo, hi) -> np.ndarray:
    return np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                     for i in (0, 1) for j in (0, 1) for k in (0, 1)], np.float64)


def _far_near(position, lo, hi) -> tuple[float, float]:
    """Near and far distances of a perspective map at ``position`` that hold the whole box."""
    corners = _box_corners(lo, hi)
    far = float(np.linalg.norm(corners - np.asarray(position), axis=1).max()) * 1.01 + 1e-3
    near = max(far * 1e-4, 1e-3)
    return near, far


def _sun_layer(light: Light, lo, hi, size: int):
    direction = np.asarray(light.direction, np.float64)
    centre = 0.5 * (lo + hi)
    view = look_at(centre, direction, (0.0, 0.0, 1.0))
    points = (view[:3, :3] @ _box_corners(lo, hi).T).T + view[:3, 3]
    half_x = max(np.abs(points[:, 0]).max(), 1e-3)
    half_y = max(np.abs(points[:, 1]).max(), 1e-3)
    # room for the filter at the box's edge: a few texels
    half_x *= 1.0 + 8.0 / size
    half_y *= 1.0 + 8.0 / size
    top = float(points[:, 2].max()) + 1e-3  # view space looks down -Z: the box's side nearest the sun
    depth = max(top - float(points[:, 2].min()) + 2e-3, 1e-3)
    near_centre = centre - direction * top  # the map's near plane passes here
    view = look_at(near_centre, direction, (0.0, 0.0, 1.0))
    matrix = orthographic(half_x, half_y, depth) @ view
    texel = 2.0 * max(half_x, half_y) / size
    return [(matrix, (depth, texel, math.tan(0.5 * light.angle), KIND_ORTHOGRAPHIC),
             (*near_centre, KIND_ORTHOGRAPHIC), view, (half_x, half_y, 0.0, 0.0))]


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
        layers.append((projection @ view, (far, texel, light.radius, kind), (*position, kind), view,
                       (tan_half, tan_half, 0.0, 0.0)))
    return layers


def _cube(light: Light) -> bool:
    return light.kind != "SPOT" or 2.0 * math.acos(max(min(light.spot_cos_half, 1.0), -1.0)) > MAX_SPOT_ANGLE


def assign(snapshot: Snapshot) -> tuple[tuple[int, ...], int, int]:
    """(each light's first layer or -1, layers used, shadowed lights dropped): nothing when shadows
    are off, no light casts or nothing casts; else the shadowed lights in order while
    ``MAX_SHADOW_LAYERS`` last (a sun or a spot up to 120 degrees takes one, the others six)."""
    first = [-1] * len(snapshot.lights)
    if not snapshot.settings.shadows or not any(item.casts_shadow for item in snapshot.items):
        return tuple(first), 0, 0
    used = dropped = 0
    for i, light in enumerate(snapshot.lights):
        if not light.shadow:
            continue
        count = 6 if light.kind != "SUN" and _cube(light) else 1
        if used + count > MAX_SHADOW_LAYERS:
            dropped += 1
            continue
        first[i], used = used, used + count
    return tuple(first), used, dropped


def plan(snapshot: Snapshot, bounds: dict[str, np.ndarray]) -> ShadowPlan:
    """The shadow maps ``snapshot`` needs (see ``assign``), fitted to the scene's bounds
    (``bounds[key]``: each geometry's object-space (min, max))."""
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
    layers = []
    for light, start in zip(snapshot.lights, first):
        if start < 0:
            continue
        if light.kind == "SUN":
            layers += _sun_layer(light, lo, hi, size)
        else:
            layers += _perspective_layers(light, lo, hi, size, _cube(light))
    matrices, info, origins, views, extents = zip(*layers)
    return ShadowPlan(size, np.stack(matrices).astype(np.float32), np.array(info, np.float32),
                      np.array(origins, np.float32), first, views=np.stack(views).astype(np.float32),
                      extents=np.array(extents, np.float32), dropped=dropped)
