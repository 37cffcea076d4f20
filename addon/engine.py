"""The ``SHADING_LAB`` render engine: final renders (F12, ``blender -b``, ``bpy``).

Thin by design: ``extract`` reads the scene, ``renderer`` draws it; this class moves pixels into
the render result and reports progress and errors through Blender.
"""

from __future__ import annotations

import time

import bpy
import gpu

from . import extract
from .gpu_library import LIBRARY, ShaderCompileError
from .passes import View
from .renderer import Renderer, frame_views

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


def light_passes(view_layer) -> list[str]:
    return [name for name, (toggle, _) in LIGHT_PASSES.items() if getattr(view_layer, toggle, False)]

#: Phase times of the last final render in milliseconds (read by scripts/frame_time.py).
last_timings: dict[str, float] = {}


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
        from gpu_extras.presets import draw_texture_2d

        session = self._viewport
        if session is None or session.snapshot is None:
            return
        scene = depsgraph.scene
        region, rv3d = context.region, context.region_data
        try:
            texture = session.draw(region.width, region.height, rv3d.view_matrix, rv3d.window_matrix,
                                   rv3d.is_perspective, background_color(session.snapshot, scene))
        except Exception as exc:
            self.report({"ERROR"}, f"Shading Lab failed to draw: {type(exc).__name__}: {exc}")
            return
        gpu.state.blend_set("ALPHA_PREMULT")
        self.bind_display_space_shader(scene)
        draw_texture_2d(texture, (0, 0), region.width, region.height)
        self.unbind_display_space_shader()
        gpu.state.blend_set("NONE")

    # --- final renders ------------------------------------------------------------------------

    def render(self, depsgraph):
        scene = depsgraph.scene
        width, height = extract.render_size(scene)
        last_timings.clear()  # a render that fails leaves none, not the previous render's
        start = time.perf_counter()
        preview = self.is_preview
        self.update_stats("", "Shading Lab | Reading scene")
        try:
            if preview:
                settings = extract.preview_settings(scene)
            else:
                settings = None
                extract.remember_settings(scene)  # the scene being rendered is the artist's
            snap = extract.snapshot(depsgraph, width, height, settings=settings)
        except extract.ExtractError as exc:
            self._fail(str(exc))
            return
        except Exception as exc:  # never let a scene we did not foresee take Blender down
            self._fail(f"Shading Lab could not read the scene: {type(exc).__name__}: {exc}")
            return
        for warning in snap.warnings:
            self.report({"WARNING"}, warning)
        if self.test_break():
            return
        extracted = time.perf_counter()
        self.update_progress(0.25)
        label = f"{snap.settings.model} | {snap.triangle_count:,} triangles | {len(snap.lights)} lights"
        self.update_stats("", f"Shading Lab | {label} | Drawing")
        settings = snap.settings
        extra_passes = settings.compare_mode == "OFF" and not preview  # previews fill Combined only
        views, comparison, combined, raw = frame_views(
            snap, lambda model: background_color(snap, scene, model), samples=settings.samples)
        if comparison is not None:  # Combined holds the composite; no Radiance pass (one model only)
            label = (f"{label} | {settings.compare_mode.title()} "
                     f"A {settings.compare_models[0]} / B {settings.compare_models[1]}")
        raw = raw if extra_passes else None
        if raw is not None:
            self.add_pass(RADIANCE_PASS, 4, "RGBA", layer=depsgraph.view_layer.name)
        lobe_passes = light_passes(depsgraph.view_layer) if extra_passes else []
        for name in lobe_passes:
            self.add_pass(name, 4, "RGBA", layer=depsgraph.view_layer.name)
        renderer = Renderer()
        LIBRARY.clear_compile_error()
        try:
            images = renderer.render_views(snap, views, [combined] + ([raw] if raw else []), comparison,
                                           should_stop=self.test_break)
            for name in lobe_passes:  # the same frame with one lobe's weights, black behind
                if self.test_break():
                    break
                lobe = View(snap.width, snap.height, samples=settings.samples,
                            background=(0.0, 0.0, 0.0, 0.0), lobes=LIGHT_PASSES[name][1])
                images[name] = renderer.render_views(snap, [lobe], [lobe.output("radiance")],
                                                     should_stop=self.test_break)[lobe.output("radiance")]
        except ShaderCompileError as exc:
            self._fail(str(exc))
            return
        except Exception as exc:
            self._fail(f"Shading Lab failed to draw: {type(exc).__name__}: {exc}")
            return
        finally:
            renderer.free()
        if self.test_break():
            return
        drawn = time.perf_counter()
        self.update_progress(0.9)
        result = self.begin_result(0, 0, width, height, layer=depsgraph.view_layer.name)
        try:
            passes = result.layers[0].passes
            passes["Combined"].rect.foreach_set(images[combined].reshape(-1))
            if raw is not None:
                passes[RADIANCE_PASS].rect.foreach_set(images[raw].reshape(-1))
            for name in lobe_passes:
                passes[name].rect.foreach_set(images[name].reshape(-1))
        finally:
            self.end_result(result)
        self.update_progress(1.0)
        done = time.perf_counter()
        last_timings.update(extract_ms=1e3 * (extracted - start), draw_ms=1e3 * (drawn - extracted),
                            result_ms=1e3 * (done - drawn), total_ms=1e3 * (done - start))
        self.update_stats("", f"Shading Lab | {label} | {last_timings['total_ms']:.0f} ms")

    def update_render_passes(self, scene=None, renderlayer=None):
        """Announce the passes to the compositor and multilayer EXR output."""
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        props = getattr(scene, "shading_lab", None)
        if props is not None and props.tone_mapper != "BLENDER" and props.compare_mode == "OFF":
            self.register_pass(scene, renderlayer, RADIANCE_PASS, 4, "RGBA", "COLOR")
        for name in light_passes(renderlayer):
            self.register_pass(scene, renderlayer, name, 4, "RGBA", "COLOR")

    def _fail(self, message: str) -> None:
        self.report({"ERROR"}, message)
        self.error_set(message)
        print(f"Shading Lab: {message}")


classes = (ShadingLabRenderEngine,)
