"""The ``SHADING_LAB`` render engine: final renders (F12, ``blender -b``, ``bpy``).

Thin by design: ``extract`` reads the scene, ``renderer`` draws it; this class moves pixels into
the render result and reports progress and errors through Blender.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import threading
import time

import bpy
import gpu
import numpy as np
from bpy.app.handlers import persistent

from ..frame.gpu_library import LIBRARY, ShaderCompileError
from ..frame.passes import View
from ..frame.renderer import Renderer, frame_views
from ..plan import auto_terms
from ..scene import exposure
from . import bake, extract

ENGINE_ID = "SHADING_LAB"
RADIANCE_PASS = "Radiance"  # raw HDR radiance when the engine's own tone mapper fills Combined
#: Light passes, named as EEVEE and Cycles name theirs, switched by the same view-layer toggles:
#: pass name -> (view-layer property, lobe weights (diffuse, specular, ambient, final clamp)).
#: Blender 5 spells the names out; 4.x used the short forms.
_LONG_NAMES = bpy.app.version >= (5, 0, 0)
LIGHT_PASSES = {
    ("Diffuse Direct" if _LONG_NAMES else "DiffDir"): ("use_pass_diffuse_direct", (1.0, 0.0, 0.0, 0.0)),
    ("Glossy Direct" if _LONG_NAMES else "GlossDir"): ("use_pass_glossy_direct", (0.0, 1.0, 0.0, 0.0)),
}


def aov_passes(view_layer) -> list[tuple[str, str]]:
    """The view layer's AOVs: (name, "COLOR" or "VALUE"), each name once."""
    aovs = getattr(view_layer, "aovs", None) or ()
    return list({aov.name: (aov.name, aov.type) for aov in aovs if aov.name}.values())


def light_passes(view_layer) -> list[str]:
    return [name for name, (toggle, _) in LIGHT_PASSES.items() if getattr(view_layer, toggle, False)]

#: Phase times of the last render (final or preview) in milliseconds, read by the benchmarks.
#: Renders and previews run on their own threads in the UI: each replaces it whole, under a lock.
last_timings: dict[str, float] = {}
#: What the last final render said of the scene (``Snapshot.warnings``): the CLI lists it.
last_warnings: list[str] = []
#: The last final render's automatic exposure: view name -> (stops used, stops metered).
last_exposures: dict[str, tuple[float, float]] = {}
#: The Auto term set's choices in the last final render or viewport update: material name ->
#: auto_terms.Choice (the Material panel and the CLI show them).
last_term_choices: dict = {}
#: The last verification of the Auto term set (``request_verification``): material name ->
#: auto_terms.Verification, the measured error of Auto against the Principled set.
last_verification: dict = {}
_VERIFY_NEXT = threading.Event()


def request_verification() -> None:
    """Have the next final render also measure the Auto term set against the Principled set, per
    material (three more draws of the frame: Principled, material ids; ``last_verification``)."""
    _VERIFY_NEXT.set()
_TIMINGS_LOCK = threading.Lock()


def _set_timings(timings: dict[str, float]) -> None:
    with _TIMINGS_LOCK:
        last_timings.clear()
        last_timings.update(timings)


def _set_term_choices(choices: dict) -> None:
    with _TIMINGS_LOCK:
        last_term_choices.clear()
        last_term_choices.update(choices)


def target_too_big(width: int, height: int, samples: int) -> str:
    """Why a width x height frame at ``samples`` x ``samples`` anti-aliasing cannot be drawn (its
    targets exceed the GPU's largest texture), with what would fit; "" when it can."""
    limit = gpu.capabilities.max_texture_size_get()
    if max(width, height) * samples <= limit:
        return ""
    fits = limit // max(width, height)
    advice = (f"set Anti-Aliasing to {fits} or less" if fits >= 1
              else f"the frame itself is larger than {limit} pixels")
    return (f"Shading Lab cannot draw {width} x {height} at Anti-Aliasing {samples}: it needs a "
            f"{width * samples} x {height * samples} target and this GPU's largest is {limit} x {limit}; "
            f"{advice}")


def render_region(scene, snap) -> tuple[int, int, int, int]:
    """(x, y, width, height) in pixels, from the bottom left, of what the render result holds: the
    render region (Output > Render Region) if set, as Blender rounds it, else the whole frame.
    The frame is drawn whole and the region cut from it; with *Crop to Render Region* the result
    is the region's size, without it the rest of the frame stays empty, as in Cycles."""
    r = scene.render
    if not r.use_border:
        return 0, 0, snap.width, snap.height
    x0, x1 = (min(max(round(v * snap.width), 0), snap.width) for v in (r.border_min_x, r.border_max_x))
    y0, y1 = (min(max(round(v * snap.height), 0), snap.height) for v in (r.border_min_y, r.border_max_y))
    if x1 <= x0 or y1 <= y0:
        return 0, 0, snap.width, snap.height
    return x0, y0, x1 - x0, y1 - y0


class _Activity:
    """Renders in progress. Blender runs final renders and previews on threads of their own, and
    an add-on can be disabled meanwhile: ``unregister()`` waits here until none is running before
    it takes the engine (and the programs it draws with) away. A render counts from Blender's
    ``render_init`` to its ``render_complete``/``render_cancel`` (the whole job, Blender's own
    use of the engine type included) and, for previews, which have no such events, for the
    duration of ``render()``."""

    def __init__(self):
        self._changed = threading.Condition()
        self._threads: dict[int, int] = {}  # thread id -> renders it is in

    def begin(self) -> None:
        me = threading.get_ident()
        with self._changed:
            self._threads[me] = self._threads.get(me, 0) + 1

    def end(self) -> None:
        me = threading.get_ident()
        with self._changed:
            if me not in self._threads:  # began before the handlers were installed
                return
            self._threads[me] -= 1
            if not self._threads[me]:
                del self._threads[me]
            self._changed.notify_all()

    @contextlib.contextmanager
    def running(self):
        self.begin()
        try:
            yield
        finally:
            self.end()

    def count(self) -> int:
        with self._changed:
            return sum(self._threads.values())

    def wait_idle(self, timeout: float) -> bool:
        """Wait until no other thread renders (a render on this thread cannot end while it
        waits); False if some still did after ``timeout`` seconds."""
        me = threading.get_ident()
        with self._changed:
            return self._changed.wait_for(lambda: not (set(self._threads) - {me}), timeout)


ACTIVITY = _Activity()


@dataclasses.dataclass
class Preparation:
    """A render that only bakes: F12's first step (``operators.SHADINGLAB_OT_render``). Run on the
    main thread (``bpy.ops.render.render()`` inside ``preparing``), it reads the scene as the
    render after it will -- Blender's render evaluation: modifiers at their render settings,
    objects hidden in the viewport but rendered -- so the bakes it makes have the keys that render
    looks for; it bakes what the frame lacks and draws nothing. No bake starts once ``budget``
    seconds were spent baking (one at least), so the interface can show the progress between such
    renders. What it found accumulates over the view layers Blender renders."""

    budget: float = math.inf
    #: the keys of the bakes the frame lacked when read
    wanted: set[str] = dataclasses.field(default_factory=set)
    #: what each bake started stands for ("Material > Node > Output"), in order
    started: list[str] = dataclasses.field(default_factory=list)
    #: what could not be baked (its readers take their socket values)
    problems: list[str] = dataclasses.field(default_factory=list)
    #: seconds spent baking
    seconds: float = 0.0
    _since: float | None = None

    def begin(self, label: str) -> None:
        """A bake starts."""
        if self._since is None:
            self._since = time.perf_counter()
        self.started.append(label)

    def should_stop(self) -> bool:
        return self._since is not None and time.perf_counter() - self._since >= self.budget

    def left(self) -> set[str]:
        """The keys of the wanted bakes still missing."""
        return {k for k in self.wanted if bake.CACHE.get(k) is None}


#: The preparation the renders on the main thread serve meanwhile (``preparing``).
_PREPARING: list[Preparation | None] = [None]


@contextlib.contextmanager
def preparing(job: Preparation):
    """Final renders on the main thread only bake meanwhile, for ``job`` (``Preparation``)."""
    _PREPARING[0] = job
    try:
        yield job
    finally:
        _PREPARING[0] = None


#: Held while the add-on registers or unregisters: a render job starting meanwhile waits for it.
REGISTRATION = threading.RLock()


@persistent
def _job_started(*_args) -> None:
    with REGISTRATION:
        ACTIVITY.begin()
    exposure.TRACK.job_started()  # an animation adapts from its own first frame only


@persistent
def _job_ended(*_args) -> None:
    ACTIVITY.end()


def _job_handlers():
    h = bpy.app.handlers
    return ((h.render_init, _job_started), (h.render_complete, _job_ended), (h.render_cancel, _job_ended))


def register() -> None:
    for handlers, function in _job_handlers():
        if function not in handlers:
            handlers.append(function)


def unregister() -> None:
    for handlers, function in _job_handlers():
        if function in handlers:
            handlers.remove(function)


def exposure_text(exposures: dict[str, tuple[float, float]]) -> str:
    """The automatic exposure of a frame's views, as the stats line and the EXR header say it:
    "+2.350 EV (auto)", or per view for A|B ("a +1.200 EV, b +0.800 EV (auto)")."""
    if not exposures:
        return ""
    if len(exposures) == 1:
        return f"{next(iter(exposures.values()))[0]:+.3f} EV (auto)"
    return ", ".join(f"{name} {stops:+.3f} EV" for name, (stops, _) in exposures.items()) + " (auto)"


def viewport_border(context, scene) -> tuple[int, int, int, int] | None:
    """(x, y, width, height) in region pixels of the viewport's render region, None without one:
    in camera view the scene's render region (Output > Render Region) over the camera frame, else
    the viewport's own (View > Render Region), as Blender's engines read them."""
    from bpy_extras.view3d_utils import location_3d_to_region_2d

    region, rv3d, space = context.region, context.region_data, context.space_data
    if rv3d.view_perspective == "CAMERA":
        r = scene.render
        camera = space.camera if getattr(space, "use_local_camera", False) and space.camera else scene.camera
        if not r.use_border or camera is None:
            return None
        corners = [location_3d_to_region_2d(region, rv3d, camera.matrix_world @ v, default=None)
                   for v in camera.data.view_frame(scene=scene)]
        if any(c is None for c in corners):
            return None
        xs, ys = [c.x for c in corners], [c.y for c in corners]
        x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
        box = (x0 + r.border_min_x * (x1 - x0), y0 + r.border_min_y * (y1 - y0),
               x0 + r.border_max_x * (x1 - x0), y0 + r.border_max_y * (y1 - y0))
    elif getattr(space, "use_render_border", False):
        w, h = region.width, region.height
        box = (space.render_border_min_x * w, space.render_border_min_y * h,
               space.render_border_max_x * w, space.render_border_max_y * h)
    else:
        return None
    x0, x1 = (min(max(round(v), 0), region.width) for v in (box[0], box[2]))
    y0, y1 = (min(max(round(v), 0), region.height) for v in (box[1], box[3]))
    return x0, y0, max(x1 - x0, 0), max(y1 - y0, 0)


#: The colour of what the viewport says that is not an error (bakes in progress).
NOTICE_COLOR = (0.9, 0.85, 0.5, 1.0)


def draw_error(message: str, width: int, height: int, color=(1.0, 0.35, 0.3, 1.0)) -> None:
    """``message`` in the region's top left, wrapped to its width (as Blender's engines show
    theirs), over whatever image is there, in ``color`` (an error's red by default)."""
    import blf

    prefs = bpy.context.preferences
    size = 12.0 * ((prefs.system.ui_scale if prefs else 0.0) or 1.0)  # 0 in background mode
    font, margin = 0, 1.5 * size
    blf.size(font, size)
    lines = [""]
    for word in message.split():
        line = f"{lines[-1]} {word}".strip()
        if lines[-1] and blf.dimensions(font, line)[0] > width - 2 * margin:
            lines.append(word)
        else:
            lines[-1] = line
    blf.enable(font, blf.SHADOW)
    blf.shadow(font, 3, 0.0, 0.0, 0.0, 1.0)
    blf.color(font, *color)
    y = height - 3.0 * size
    for line in lines[:8]:
        blf.position(font, margin, y, 0.0)
        blf.draw(font, line)
        y -= 1.4 * size
    blf.disable(font, blf.SHADOW)


def background_color(snap, scene, model: str | None = None) -> tuple[float, float, float, float]:
    """What the camera sees where there is no surface, for ``model`` (the scene's by default)."""
    if scene.render.film_transparent:
        return (0.0, 0.0, 0.0, 0.0)
    r, g, b = snap.world_color
    if (model or snap.settings.model) != "PBR":  # the LDR models clamp everything they output
        r, g, b = (min(max(c, 0.0), 1.0) for c in (r, g, b))
    return (r, g, b, 1.0)


class ShadingLabRenderEngine(bpy.types.RenderEngine):
    bl_idname = ENGINE_ID
    bl_label = "Shading Lab"
    bl_use_gpu_context = True
    bl_use_preview = True  # material, world and light previews, with the artist's scene's model
    bl_use_shading_nodes_custom = False

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._viewport = None

    def __del__(self):
        viewport = getattr(self, "_viewport", None)
        if viewport is not None:
            viewport.free()
        parent_del = getattr(super(), "__del__", None)
        if parent_del is not None:
            parent_del()

    # --- interactive viewport -------------------------------------------------------------------

    def view_update(self, context, depsgraph):
        from .viewport import ViewportSession

        if self._viewport is None:
            self._viewport = ViewportSession()
        try:
            self._viewport.update(depsgraph)
        except Exception as exc:
            self.report({"ERROR"}, f"Shading Lab could not read the scene: {type(exc).__name__}: {exc}")

    def view_draw(self, context, depsgraph):
        """Draw the session's frame (the last good one if this one failed), clipped to the render
        region when one is set, and the error, if any, over it."""
        from gpu_extras.presets import draw_texture_2d

        session = self._viewport
        if session is None or session.snapshot is None:
            return
        scene = depsgraph.scene
        region, rv3d = context.region, context.region_data
        texture = session.draw(region.width, region.height, rv3d.view_matrix, rv3d.window_matrix,
                               rv3d.is_perspective, background_color(session.snapshot, scene))
        if session.snapshot.term_choices:
            _set_term_choices(session.snapshot.term_choices)
        if session.error and not session.error_reported:
            self.report({"ERROR"}, session.error)
            session.error_reported = True
        if texture is not None:
            border = viewport_border(context, scene)
            if border is not None:
                gpu.state.scissor_test_set(True)
                gpu.state.scissor_set(*border)
            gpu.state.blend_set("ALPHA_PREMULT")
            self.bind_display_space_shader(scene)
            draw_texture_2d(texture, (0, 0), region.width, region.height)
            self.unbind_display_space_shader()
            gpu.state.blend_set("NONE")
            if border is not None:
                gpu.state.scissor_test_set(False)
        if session.error:
            draw_error(session.error, region.width, region.height)
        elif session.notice:  # what is being baked shows its socket's value meanwhile
            draw_error(session.notice, region.width, region.height, color=NOTICE_COLOR)
        if session.adapting:  # automatic exposure still approaching its target
            self.tag_redraw()

    # --- final renders ------------------------------------------------------------------------

    def render(self, depsgraph):
        with ACTIVITY.running():
            self._render(depsgraph)

    def _render(self, depsgraph):
        job = _PREPARING[0] if threading.current_thread() is threading.main_thread() else None
        if job is not None and not self.is_preview:
            self._prepare(depsgraph, job)
            return
        _set_timings({})  # a render that fails leaves none, not the previous render's
        start = time.perf_counter()
        self.update_stats("", "Shading Lab | Reading scene")
        snap = self._read_scene(depsgraph)
        if snap is None or self.test_break():
            return
        extracted = time.perf_counter()
        self.update_progress(0.25)
        label = f"{snap.settings.model} | {snap.triangle_count:,} triangles | {len(snap.lights)} lights"
        if snap.settings.auto_error_bound is not None and not self.is_preview:
            _set_term_choices(snap.term_choices)
            label = f"{label} | {auto_terms.summary(snap.term_choices)}"
        settings = snap.settings
        if settings.compare_mode != "OFF":
            label = (f"{label} | {settings.compare_mode.title()} "
                     f"A {settings.compare_models[0]} / B {settings.compare_models[1]}")
        self.update_stats("", f"Shading Lab | {label} | Drawing")
        # previews fill Combined only; with A|B, Combined holds the composite and there is no
        # Radiance pass (it would hold one model only)
        extra_passes = settings.compare_mode == "OFF" and not self.is_preview
        too_big = target_too_big(snap.width, snap.height, settings.samples)
        if too_big:
            self._fail(too_big)
            return
        views, comparison, combined, raw = frame_views(
            snap, lambda model: background_color(snap, depsgraph.scene, model), samples=settings.samples)
        raw = raw if extra_passes else None
        lobe_passes = light_passes(depsgraph.view_layer) if extra_passes else []
        for name in ([RADIANCE_PASS] if raw else []) + lobe_passes:
            self.add_pass(name, 4, "RGBA", layer=depsgraph.view_layer.name)
        for name, kind in snap.aovs:
            self.add_pass(name, 1 if kind == "VALUE" else 4, "X" if kind == "VALUE" else "RGBA",
                          layer=depsgraph.view_layer.name)
        drawn_frame = self._draw(snap, views, comparison, [combined] + ([raw] if raw else []), lobe_passes,
                                 self._adapter(depsgraph, snap))
        if drawn_frame is None or self.test_break():
            return
        images, exposures = drawn_frame
        if _VERIFY_NEXT.is_set() and not self.is_preview:
            _VERIFY_NEXT.clear()
            self.update_stats("", f"Shading Lab | {label} | Verifying Auto against Principled")
            self._verify(snap)
        drawn = time.perf_counter()
        self.update_progress(0.9)
        whole = (0, 0, snap.width, snap.height)
        x0, y0, w, h = whole if self.is_preview else render_region(depsgraph.scene, snap)
        # Blender's result already is the region: its own coordinates start at the region's corner
        result = self.begin_result(0, 0, w, h, layer=depsgraph.view_layer.name)
        try:
            passes = result.layers[0].passes
            values = {name for name, kind in snap.aovs if kind == "VALUE"}
            for name, image in images.items():
                pass_name = "Combined" if name == combined else RADIANCE_PASS if name == raw else name
                region = image[y0:y0 + h, x0:x0 + w, :1] if name in values else image[y0:y0 + h, x0:x0 + w]
                passes[pass_name].rect.foreach_set(np.ascontiguousarray(region).reshape(-1))
        finally:
            self.end_result(result)
        # Blender holds its copy now: the next render reads into these buffers
        LIBRARY.keep_read_buffers(images.values())
        said_exposure = exposure_text(exposures)
        if said_exposure:  # into the EXR's header and the image editor's metadata, as Cycles does
            self.get_result().stamp_data_add_field("Shading Lab Exposure", said_exposure)
        self.update_progress(1.0)
        done = time.perf_counter()
        timings = dict(extract_ms=1e3 * (extracted - start), draw_ms=1e3 * (drawn - extracted),
                       result_ms=1e3 * (done - drawn), total_ms=1e3 * (done - start))
        _set_timings(timings)
        if not self.is_preview:
            with _TIMINGS_LOCK:
                last_exposures.clear()
                last_exposures.update(exposures)
        said = f" | {len(snap.warnings)} warning(s), see the Info editor" if snap.warnings else ""
        said_exposure = f" | exposure {said_exposure}" if said_exposure else ""
        self.update_stats("", f"Shading Lab | {label} | {timings['total_ms']:.0f} ms{said_exposure}{said}")

    def _adapter(self, depsgraph, snap):
        """Automatic exposure's adaptation for this render: from the frame before it in an
        animation (a render job, or a sequence the CLI holds), none for stills and previews."""
        if self.is_preview or snap.settings.auto_exposure is None:
            return None
        scene = depsgraph.scene
        animating = bool(self.is_animation) or exposure.TRACK.held
        fps = scene.render.fps / scene.render.fps_base
        frame = scene.frame_current + scene.frame_subframe
        layer = depsgraph.view_layer.name

        def adapt(view, metered: float) -> float:
            key = (scene.name, layer, view.name, view.model or snap.settings.model)
            return exposure.TRACK.step(key, frame, fps, metered, view.auto_exposure, animating)

        return adapt

    def _read_scene(self, depsgraph):
        """The snapshot to draw (None, with the error reported, when the scene cannot be read)."""
        scene = depsgraph.scene
        width, height = extract.render_size(scene)
        try:
            if self.is_preview:
                settings = extract.preview_settings(scene)
            else:
                settings = extract.final_render_settings(scene)
                extract.remember_settings(scene)  # the scene being rendered is the artist's
            snap = extract.snapshot(depsgraph, width, height, settings=settings, aovs=not self.is_preview)
            if snap.bake_requests:
                self._bake_fallbacks(depsgraph, snap)
        except extract.ExtractError as exc:
            self._fail(str(exc))
            return None
        except Exception as exc:  # never let a scene we did not foresee take Blender down
            self._fail(f"Shading Lab could not read the scene: {type(exc).__name__}: {exc}")
            return None
        for warning in snap.warnings:
            self.report({"WARNING"}, warning)
        if not self.is_preview:
            with _TIMINGS_LOCK:
                last_warnings[:] = snap.warnings
        return snap

    def _prepare(self, depsgraph, job: Preparation) -> None:
        """Read the scene as this render would and bake what it lacks, drawing nothing
        (``Preparation``). A scene that cannot be read is left to the render that follows, which
        says why."""
        scene = depsgraph.scene
        width, height = extract.render_size(scene)
        self.update_stats("", "Shading Lab | Finding fallback bakes")
        try:
            snap = extract.snapshot(depsgraph, width, height, settings=extract.final_render_settings(scene),
                                    aovs=True, auto_choice=False, bakes_only=True)
        except Exception:  # (no camera, say): the render that follows reports it
            return
        if snap.bake_requests:
            self._bake_fallbacks(depsgraph, snap, job)

    def _bake_fallbacks(self, depsgraph, snap, job: Preparation | None = None) -> None:
        """Bake what the snapshot's materials need that the compiler cannot compile (``bake``), before
        anything is drawn, where this render runs on the main thread (batch renders, scripts, F12's
        ``Preparation`` ``job``: within its budget); else say why their readers take their socket
        values. Progress in the stats line, the progress bar and, in background mode, on the console."""
        count = bake.count_missing(snap.bake_requests)
        why = bake.can_bake_here()
        if why or self.is_preview:
            said = f"{count} fallback bake(s) not made ({why}): what they stand for takes its socket's value"
            if not self.is_preview:
                snap.warnings.append(said)
            if job is not None:
                job.problems.append(said)
            return
        done = [0]
        resolution = snap.bake_requests[0].resolution
        if job is not None:
            job.wanted |= bake.missing_keys(snap.bake_requests)

        def progress(label: str) -> None:
            done[0] += 1
            text = f"Baking {done[0]}/{count}: {label} ({resolution} x {resolution})"
            self.update_stats("", f"Shading Lab | {text}")
            self.update_progress(0.2 * (done[0] - 1) / max(count, 1))
            if bpy.app.background:
                print(f"Shading Lab: {text}", flush=True)
            if job is not None:
                job.begin(label)

        def should_stop() -> bool:
            return self.test_break() or (job is not None and job.should_stop())

        start = time.perf_counter()
        problems = bake.bake_all(snap.bake_requests, depsgraph, progress, should_stop)
        snap.warnings.extend(problems)
        if job is not None:
            job.problems.extend(problems)
            job.seconds += time.perf_counter() - start
        extract.apply_bakes(snap)
        if bpy.app.background and done[0]:
            seconds = time.perf_counter() - start
            print(f"Shading Lab: baked {done[0]} fallback(s) in {seconds:.2f} s", flush=True)
        if snap.bake_requests:
            snap.warnings.append(f"{bake.count_missing(snap.bake_requests)} fallback bake(s) not made: what "
                                 f"they stand for takes its socket's value")

    def _draw(self, snap, views, comparison, outputs: list[str], lobe_passes: list[str], adapt=None):
        """The frame's ``outputs`` and each light pass (the same frame with one lobe's weights,
        black behind), read back, and the frame's automatic exposures; None, with the error
        reported, when drawing failed."""
        renderer = Renderer()
        LIBRARY.clear_compile_error()
        try:
            images = renderer.render_views(snap, views, outputs, comparison, should_stop=self.test_break,
                                           adapt=adapt)
            exposures = renderer.exposures
            for name in lobe_passes:
                if self.test_break():
                    break
                lobe = View(snap.width, snap.height, samples=snap.settings.samples,
                            background=(0.0, 0.0, 0.0, 0.0), lobes=LIGHT_PASSES[name][1])
                images[name] = renderer.render_views(snap, [lobe], [lobe.output("radiance")],
                                                     should_stop=self.test_break)[lobe.output("radiance")]
            if not self.test_break():
                images.update(renderer.render_aovs(snap))
            return images, exposures
        except ShaderCompileError as exc:
            self._fail(str(exc))
        except Exception as exc:
            self._fail(f"Shading Lab failed to draw: {type(exc).__name__}: {exc}")
        finally:
            renderer.free()
        return None

    def _verify(self, snap) -> None:
        """Measure the Auto term set's real error per material (``request_verification``)."""
        with _TIMINGS_LOCK:
            last_verification.clear()
        settings = snap.settings
        if settings.auto_error_bound is None:
            self.report({"WARNING"}, "Verify: the term set is not Auto; nothing to verify")
            return
        renderer = Renderer()
        try:
            auto = renderer.render(snap)
            reference = renderer.render(auto_terms.principled_snapshot(snap))
            ids, keys = auto_terms.material_id_snapshot(snap)
            id_image = renderer.render(ids)
        except Exception as exc:
            self.report({"ERROR"}, f"Verify failed to draw: {type(exc).__name__}: {exc}")
            return
        finally:
            renderer.free()
        measured = auto_terms.measure(auto, reference, id_image, keys, settings.auto_error_bound,
                                      settings.exposure, settings.auto_quantile)
        measured = {key: v for key, v in measured.items() if key in snap.term_choices}
        with _TIMINGS_LOCK:
            last_verification.update(measured)  # the Verify operator reports it

    def update_render_passes(self, scene=None, renderlayer=None):
        """Announce the passes to the compositor and multilayer EXR output."""
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        props = getattr(scene, "shading_lab", None)
        exposed = props is not None and (props.tone_mapper != "BLENDER" or props.exposure_mode == "AUTO")
        if exposed and props.compare_mode == "OFF":
            self.register_pass(scene, renderlayer, RADIANCE_PASS, 4, "RGBA", "COLOR")
        for name in light_passes(renderlayer):
            self.register_pass(scene, renderlayer, name, 4, "RGBA", "COLOR")
        for name, kind in aov_passes(renderlayer):  # as Cycles registers them
            if kind == "VALUE":
                self.register_pass(scene, renderlayer, name, 1, "X", "VALUE")
            else:
                self.register_pass(scene, renderlayer, name, 4, "RGBA", "COLOR")

    def _fail(self, message: str) -> None:
        self.report({"ERROR"}, message)
        self.error_set(message)
        print(f"Shading Lab: {message}")


classes = (ShadingLabRenderEngine,)
