"""Interactive viewport: incremental scene updates and drawing through the shared renderer.

``ViewportSession.update`` runs on every depsgraph change: it re-reads lights and matrices (cheap)
but only the geometry of objects whose geometry changed, so a transform-only edit uploads no
geometry, and only the materials an update names (their node graphs read and compiled again).
``draw`` renders with the region's own view and projection matrices into a float target (and
through the engine's tone mapper when one is chosen) and returns the texture for the engine to show
through Blender's display transform. A frame that fails (a program that does not compile after an
edit, say) leaves the last good image to show, and the failure in ``error`` for the engine to draw
over it. Automatic exposure adapts from draw to draw by the time between them (``adapting`` asks
the engine for another redraw until it settles).

Nodes the compiler cannot compile are baked by Cycles (``bake``), never inside an update or a
draw: the update queues them for a timer on the main thread (``bake.schedule``) and the frame
shows their socket values meanwhile, saying so (``notice``); once the timer has baked them, the
next draw takes the bakes (``extract.apply_bakes``).
"""

from __future__ import annotations

import time

import gpu
import numpy as np

from ..frame.gpu_library import ShaderCompileError
from ..frame.renderer import Renderer, frame_views
from ..scene import exposure
from ..scene import snapshot as S
from . import bake, extract, images

_NO_CAMERA = S.Camera(np.eye(4, dtype=np.float32), np.eye(4, dtype=np.float32), True, (0.0, 0.0, 0.0),
                      (0.0, 0.0, -1.0))


#: Automatic exposure closer than this to its target counts as settled (no further redraw).
ADAPTED_STOPS = 0.01


class ViewportSession:
    def __init__(self):
        self.snapshot: S.Snapshot | None = None
        self.pending: set[str] = set()  # geometry keys read anew and not yet uploaded
        self.renderer = Renderer()
        self.last_update_ms = 0.0
        self.error = ""  # why the last frame failed ("" when it did not)
        self.error_reported = False  # the engine reports each new error once, not every redraw
        self.clock = time.perf_counter  # seconds; automatic exposure adapts by the time between draws
        self.adapting = False  # the last draw's automatic exposure had not reached its target
        self._exposures: dict[tuple, float] = {}
        self._last_draw: float | None = None
        self._last_good: gpu.types.GPUTexture | None = None
        # the Auto term set chooses per material as the last drawn view sees it (re-chosen on scene
        # edits, not on view changes); before the first draw there is none
        self._view: S.Camera | None = None
        self._unchosen = False
        self.notice = ""  # what the frame shows in place of what is being baked ("" when nothing)
        self._bakes_seen = bake.GENERATION[0]

    def update(self, depsgraph) -> None:
        start = time.perf_counter()
        dirty = None if self.snapshot is None else extract.geometry_updates(depsgraph)
        materials = None if self.snapshot is None else extract.material_updates(depsgraph)
        images.IMAGES.forget(images.image_updates(depsgraph))
        self.snapshot = extract.snapshot(depsgraph, 1, 1, camera=_NO_CAMERA, previous=self.snapshot,
                                         dirty=dirty, auto_camera=self._view,
                                         auto_choice=self._view is not None, materials_dirty=materials)
        self._unchosen = self._view is None and self.snapshot.settings.auto_error_bound is not None
        self.pending |= self.snapshot.fresh
        if self.snapshot.bake_requests:
            bake.schedule(self.snapshot.bake_requests)
        self._say_bakes()
        self.last_update_ms = 1e3 * (time.perf_counter() - start)

    def _say_bakes(self) -> None:
        waiting = bake.count_missing(self.snapshot.bake_requests)
        self.notice = (f"Baking {waiting} node output(s) Shading Lab does not compile: they show their "
                       f"socket's value until baked" if waiting else "")
        if bake.LAST_PROBLEMS:
            self.notice = "; ".join([self.notice] * bool(self.notice) + bake.LAST_PROBLEMS[:2])

    def take_bakes(self) -> bool:
        """Give the snapshot the bakes the timer made since the last draw (``bake.run_pending``);
        whether any slot changed."""
        if self.snapshot is None or self._bakes_seen == bake.GENERATION[0]:
            return False
        self._bakes_seen = bake.GENERATION[0]
        changed = extract.apply_bakes(self.snapshot)
        self._say_bakes()
        return bool(changed)

    def draw(self, width: int, height: int, view_matrix, window_matrix, is_perspective: bool,
             background=(0.0, 0.0, 0.0, 1.0)) -> gpu.types.GPUTexture | None:
        """Render the last snapshot as the region sees it; returns the texture to display: this
        frame's or, when it fails (``error`` says why), the last good frame's (None if none)."""
        self.take_bakes()
        snap = self.snapshot
        snap.camera = S.Camera.from_matrices(np.array(view_matrix), np.array(window_matrix), is_perspective)
        snap.width, snap.height = width, height
        self._view = snap.camera
        if self._unchosen:  # Auto waited for a view to choose for: this one
            extract.choose_terms(snap)
            self._unchosen = False
        pending = self.pending
        try:
            self.renderer.sync(snap, keep=lambda key: key not in pending)
            self.pending = set()  # kept on failure: the next frame uploads them
            views, comparison, shown, _ = frame_views(snap, lambda model: background, half_target=True,
                                                      keep_last=True)
            frame = self.renderer.run(views, comparison, adapt=self._adapter(snap))
            texture = frame.outputs[shown].texture_color
        except ShaderCompileError as exc:
            self._failed(str(exc))
            return self._last_good
        except Exception as exc:  # an error in one frame must not take the viewport down
            self._failed(f"Shading Lab failed to draw: {type(exc).__name__}: {exc}")
            return self._last_good
        self.error = ""
        self._last_good = texture
        return texture

    def _adapter(self, snap):
        """Automatic exposure's adaptation over the time since the last draw (none: converged)."""
        now = self.clock()
        dt = 0.0 if self._last_draw is None else now - self._last_draw
        self._last_draw = now
        self.adapting = False
        if snap.settings.auto_exposure is None:
            self._exposures.clear()
            return None

        def adapt(view, metered: float) -> float:
            key = (view.name, view.model or snap.settings.model)
            stops = exposure.adapt(self._exposures.get(key), metered, dt, view.auto_exposure)
            self._exposures[key] = stops
            self.adapting |= abs(stops - metered) > ADAPTED_STOPS
            return stops

        return adapt

    def _failed(self, message: str) -> None:
        if message != self.error:
            self.error, self.error_reported = message, False

    def free(self) -> None:
        self._last_good = None
        self.renderer.free()
