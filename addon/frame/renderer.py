"""The GPU renderer: draws a ``Snapshot`` as a frame of passes (``passes.py``).

Host-agnostic: it needs a GPU context (Blender's ``gpu`` module, inside ``RenderEngine.render()``
or ``view_draw()``) but reads no Blender data: images arrive in the snapshot as pixels. Final
renders, light passes, A|B comparisons, previews and the viewport all draw through ``run``: a
list of views (each drawn by the same passes) and optionally their comparison. A light pass is
the same view with other lobe weights.

A ``Renderer`` keeps the GPU copy of its scene (``gpu_scene.SceneResources``) and its passes'
targets between frames; ``sync`` brings the scene up to date (uploading only what changed),
``run`` draws a frame, ``render_views`` does both and reads images back, ``free`` releases all.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import gpu
import numpy as np

from ..plan import programs
from ..scene.snapshot import Snapshot
from . import gpu_library
from .gpu_environment import EnvironmentPass
from .gpu_scene import SceneResources
from .passes import (
    VIEW_PASSES,
    ComparePass,
    Comparison,
    Frame,
    Pass,
    ShadowPass,
    Target,
    View,
    full_screen_batch,
)


def frame_views(snapshot: Snapshot, background: Callable[[str | None], tuple], samples: int = 1,
                half_target: bool = False, keep_last: bool = False
                ) -> tuple[list[View], Comparison | None, str, str | None]:
    """The views of a frame as the scene's settings ask for them (one view, or A and B and their
    comparison), the output to show and the raw radiance output when it differs from the one
    shown (under an engine tone mapper, without A|B). ``background(model)`` is what the camera
    sees where there is no surface. ``keep_last``: the output shown is written by the frame's
    last pass only, into a target of its own (a frame that fails leaves the last good image)."""
    settings = snapshot.settings
    display = None
    if settings.tone_mapper != "BLENDER" or settings.auto_exposure is not None:
        display = programs.PostFeatures(samples, settings.tone_mapper, settings.transfer)

    def view(name, model=None, tone_map=True):
        return View(snapshot.width, snapshot.height, name=name, model=model, samples=samples,
                    background=background(model), half_target=half_target,
                    display=display if tone_map else None, exposure=settings.exposure,
                    auto_exposure=settings.auto_exposure if tone_map else None)

    if settings.compare_mode == "OFF":
        main = view("main")
        if display is None:  # the display and compare passes write targets of their own anyway
            main = replace(main, own_radiance=keep_last)
            return [main], None, main.output("radiance"), None
        return [main], None, main.output("display"), main.output("radiance")
    # a split composites what each model shows (display values under an engine tone mapper); a
    # difference map compares radiance
    features = programs.CompareFeatures(settings.compare_mode)
    tone_map = features.mode == "SPLIT"
    a, b = (view(name, model, tone_map) for name, model in zip("ab", settings.compare_models))
    shown = "display" if display is not None and tone_map else "radiance"
    comparison = Comparison(a.output(shown), b.output(shown), snapshot.width, snapshot.height, features,
                            settings.compare_split, settings.compare_range, half_target=half_target)
    return [a, b], comparison, "compare", None


class Renderer:
    def __init__(self):
        self.scene = SceneResources()
        self._passes: dict[tuple[type, str], Pass] = {}
        self._full_screen = None
        self.peeled_layers = 0  # transparency layers the last frame blended (for tests and stats)

    @property
    def uploads(self) -> dict[str, int]:
        """What the last sync and frame uploaded, by kind (geometry, objects, lights, materials,
        frame, textures): zero everywhere for an unchanged scene."""
        return {k: v for k, v in self.scene.uploads.items() if v}

    @property
    def uploaded_geometry(self) -> int:
        return self.scene.uploads["geometry"]

    @property
    def shadow_layers_drawn(self) -> int:
        """Shadow-map layers drawn since the renderer was made (a viewport keeps its maps while
        lights and casters hold still)."""
        step = self._passes.get((ShadowPass, "shadows"))
        return step.renders if step is not None else 0

    def sync(self, snapshot: Snapshot, keep: Callable[[str], bool] | None = None) -> None:
        self.scene.sync(snapshot, keep)

    def _pass(self, kind: type, name: str) -> Pass:
        step = self._passes.get((kind, name))
        if step is None:
            step = self._passes[kind, name] = kind()
        return step

    def steps(self, views: list[View], comparison: Comparison | None = None) -> list[tuple[Pass, object]]:
        """The frame: each view's passes in order, then the comparison if any."""
        steps = [(self._pass(EnvironmentPass, "world"), None),  # once per frame, for every view
                 (self._pass(ShadowPass, "shadows"), views)]  # the casters their views need
        steps += [(self._pass(kind, view.name), view) for view in views for kind in VIEW_PASSES]
        if comparison is not None:
            steps.append((self._pass(ComparePass, "compare"), comparison))
        return steps

    def run(self, views: list[View], comparison: Comparison | None = None, *,
            should_stop: Callable[[], bool] | None = None,
            adapt: Callable[[View, float], float] | None = None) -> Frame:
        """Draw one frame of the synced scene. Once ``should_stop()`` says so, no more geometry
        is drawn; the passes after it still make their images from what was drawn. ``adapt``:
        automatic exposure's adaptation from the previous frame (``Frame.adapt``)."""
        if self._full_screen is None:
            self._full_screen = full_screen_batch()
        frame = Frame(self.scene.snapshot, self.scene, self._full_screen, should_stop, adapt=adapt)
        for step, spec in self.steps(views, comparison):
            if frame.cancelled and step.draws_geometry:
                continue
            if not step.run(frame, spec):
                frame.cancelled = True
        self.peeled_layers = frame.peeled_layers
        self.exposures = dict(frame.exposures)
        return frame

    def render_views(self, snapshot: Snapshot, views: list[View], outputs: list[str],
                     comparison: Comparison | None = None,
                     should_stop: Callable[[], bool] | None = None,
                     adapt: Callable[[View, float], float] | None = None) -> dict[str, np.ndarray]:
        """Sync ``snapshot``, draw the frame and read ``outputs`` back: each (height, width, 4)
        float32, bottom row first."""
        self.sync(snapshot)
        frame = self.run(views, comparison, should_stop=should_stop, adapt=adapt)
        return {name: frame.outputs[name].read() for name in outputs}

    def render_aovs(self, snapshot: Snapshot) -> dict[str, np.ndarray]:
        """Each of the snapshot's AOVs after a frame of it (``render_views``): the value the
        nearest surface's material writes from its AOV Output (zeros where it has none, and
        where no surface is), one sample per pixel centre; (height, width, 4) float32, bottom
        row first: a Color AOV's RGB (alpha 1 on surfaces), a Value AOV's value in x."""
        if not snapshot.aovs:
            return {}
        self.scene.put_frame(None, snapshot.width, snapshot.height)
        target = Target(snapshot.width, snapshot.height, "RGBA32F", depth=True)
        out = {}
        try:
            for name, kind in snapshot.aovs:
                with target.bind():
                    target.clear((0.0, 0.0, 0.0, 0.0), depth=1.0)
                    gpu.state.depth_test_set("LESS_EQUAL")
                    gpu.state.depth_mask_set(True)
                    try:
                        self.scene.draw_aov(name, kind == "VALUE")
                    finally:
                        gpu.state.depth_test_set("NONE")
                        gpu.state.depth_mask_set(False)
                out[name] = np.array(target.read())  # a copy: the read buffer is the next one's
        finally:
            gpu_library.LIBRARY.keep_textures(target.owned())
            target.free()
        return out

    def render(self, snapshot: Snapshot, background: tuple[float, float, float, float] = (0, 0, 0, 1),
               should_stop: Callable[[], bool] | None = None, samples: int = 1,
               lobes: tuple[float, float, float, float] = programs.ALL_LOBES,
               view_projection: np.ndarray | None = None) -> np.ndarray:
        """The snapshot's radiance, (height, width, 4) float32, bottom row first."""
        view = View(snapshot.width, snapshot.height, samples=max(int(samples), 1), background=background,
                    lobes=lobes, view_projection=view_projection)
        return self.render_views(snapshot, [view], [view.output("radiance")], should_stop=should_stop)[
            view.output("radiance")]

    def free(self) -> None:
        """Drop every GPU object; the passes' target textures go to the library for the next
        renderer's (a final render makes a renderer per frame), then the shadow maps' (kept
        last, so the first to stay within the library's budget)."""
        steps = list(self._passes.values())
        textures = {id(t): t for step in steps for t in step.textures()}  # each once
        gpu_library.LIBRARY.keep_textures(textures.values())
        for step in steps:
            step.free()
        self._passes.clear()
        self.scene.free()
        self._full_screen = None
