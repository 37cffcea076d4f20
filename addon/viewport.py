"""Interactive viewport: incremental scene updates and drawing through the shared renderer.

``ViewportSession.update`` runs on every depsgraph change: it re-reads lights, materials and
matrices (cheap) but only the geometry of objects whose geometry changed, so a transform-only
edit uploads no geometry. ``draw`` renders with the region's own view and projection matrices
into a float target (and through the engine's tone mapper when one is chosen) and returns the
texture for the engine to show through Blender's display transform.
"""

from __future__ import annotations

import time
from dataclasses import replace

import gpu
import numpy as np

from . import extract, programs
from . import snapshot as S
from .renderer import Renderer, SceneTarget, compare_pass, post_pass

_NO_CAMERA = S.Camera(np.eye(4, dtype=np.float32), np.eye(4, dtype=np.float32), True, (0.0, 0.0, 0.0),
                      (0.0, 0.0, -1.0))


class ViewportSession:
    def __init__(self):
        self.snapshot: S.Snapshot | None = None
        self.pending: set[str] = set()  # geometry keys read anew and not yet uploaded
        self.renderer = Renderer(image_loader=extract.image_texture)
        self._targets: dict[str, SceneTarget] = {}
        self.last_update_ms = 0.0

    def update(self, depsgraph) -> None:
        start = time.perf_counter()
        dirty = None if self.snapshot is None else extract.geometry_updates(depsgraph)
        self.snapshot = extract.snapshot(depsgraph, 1, 1, camera=_NO_CAMERA, previous=self.snapshot,
                                         dirty=dirty)
        self.pending |= self.snapshot.fresh
        self.last_update_ms = 1e3 * (time.perf_counter() - start)

    def _target(self, name: str, width: int, height: int, depth: bool = False) -> SceneTarget:
        """The float target ``name`` at this size (remade when the region is resized); scene
        targets have a depth buffer, display and compare targets only colour."""
        target = self._targets.get(name)
        if target is None or (target.width, target.height) != (width, height):
            if target is not None:
                target.free()
            target = self._targets[name] = SceneTarget(width, height, format="RGBA16F", depth=depth)
        return target

    def draw(self, width: int, height: int, view_matrix, window_matrix, is_perspective: bool,
             background=(0.0, 0.0, 0.0, 1.0)) -> gpu.types.GPUTexture:
        """Render the last snapshot as the region sees it; returns the texture to display."""
        snap = self.snapshot
        snap.camera = S.Camera.from_matrices(np.array(view_matrix), np.array(window_matrix), is_perspective)
        snap.width, snap.height = width, height
        pending = self.pending
        self.renderer.sync(snap, keep=lambda key: key not in pending)
        self.pending = set()
        settings = snap.settings
        if settings.compare_mode == "OFF":
            return self._draw_model(snap, "scene", background)
        compare = programs.CompareFeatures(settings.compare_mode)
        textures = []
        for name, model in zip(("a", "b"), settings.compare_models):
            model_snap = replace(snap, settings=replace(settings, model=model))
            # a split shows what each model displays; a difference map compares radiance
            textures.append(self._draw_model(model_snap, name, background, tone_map=compare.mode == "SPLIT"))
        shown = self._target("compare", width, height)
        compare_pass(textures[0], textures[1], width, height, compare, settings.compare_split,
                     settings.compare_range, target=shown)
        return shown.texture_color

    def _draw_model(self, snap: S.Snapshot, name: str, background, tone_map: bool = True):
        """Draw ``snap`` into the target ``name``; through the engine's tone mapper if chosen."""
        width, height = snap.width, snap.height
        scene_target = self._target(name, width, height, depth=True)
        with scene_target.bind():
            fb = gpu.state.active_framebuffer_get()
            fb.clear(color=background, depth=1.0)
            self.renderer.draw(snap, half_target=True, target=scene_target)
        settings = snap.settings
        if settings.tone_mapper == "BLENDER" or not tone_map:
            return scene_target.texture_color
        shown = self._target(name + "-display", width, height)
        post_pass(scene_target.texture_color, width, height,
                  programs.PostFeatures(1, settings.tone_mapper, settings.transfer), settings.exposure,
                  target=shown)
        return shown.texture_color

    def free(self) -> None:
        for target in self._targets.values():
            target.free()
        self._targets.clear()
        self.renderer.free()
