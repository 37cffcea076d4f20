"""Interactive viewport: incremental scene updates and drawing through the shared renderer.

``ViewportSession.update`` runs on every depsgraph change: it re-reads lights, materials and
matrices (cheap) but only the geometry of objects whose geometry changed, so a transform-only
edit uploads no geometry. ``draw`` renders with the region's own view and projection matrices
into a float target (and through the engine's tone mapper when one is chosen) and returns the
texture for the engine to show through Blender's display transform.
"""

from __future__ import annotations

import time

import gpu
import numpy as np

from . import extract
from . import snapshot as S
from .renderer import Renderer, frame_views

_NO_CAMERA = S.Camera(np.eye(4, dtype=np.float32), np.eye(4, dtype=np.float32), True, (0.0, 0.0, 0.0),
                      (0.0, 0.0, -1.0))


class ViewportSession:
    def __init__(self):
        self.snapshot: S.Snapshot | None = None
        self.pending: set[str] = set()  # geometry keys read anew and not yet uploaded
        self.renderer = Renderer()
        self.last_update_ms = 0.0

    def update(self, depsgraph) -> None:
        start = time.perf_counter()
        dirty = None if self.snapshot is None else extract.geometry_updates(depsgraph)
        extract.IMAGES.forget(extract.image_updates(depsgraph))
        self.snapshot = extract.snapshot(depsgraph, 1, 1, camera=_NO_CAMERA, previous=self.snapshot,
                                         dirty=dirty)
        self.pending |= self.snapshot.fresh
        self.last_update_ms = 1e3 * (time.perf_counter() - start)

    def draw(self, width: int, height: int, view_matrix, window_matrix, is_perspective: bool,
             background=(0.0, 0.0, 0.0, 1.0)) -> gpu.types.GPUTexture:
        """Render the last snapshot as the region sees it; returns the texture to display."""
        snap = self.snapshot
        snap.camera = S.Camera.from_matrices(np.array(view_matrix), np.array(window_matrix), is_perspective)
        snap.width, snap.height = width, height
        pending = self.pending
        self.renderer.sync(snap, keep=lambda key: key not in pending)
        self.pending = set()
        views, comparison, shown, _ = frame_views(snap, lambda model: background, half_target=True)
        return self.renderer.run(views, comparison).outputs[shown].texture_color

    def free(self) -> None:
        self.renderer.free()
