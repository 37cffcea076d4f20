"""Ground truth and peers: the same scene rendered by Cycles (the reference), EEVEE and Workbench.

The reference is what Shading Lab computes, computed exactly: Cycles on the CPU with direct light
only (max bounces 0), every light's radius 0 and soft falloff off, the world lighting the scene,
**nothing occluded**: light shadows off and every object's shadow-ray visibility off, so that the
world's light is not occluded either (the engine has neither shadows nor ambient occlusion yet:
this switches a real feature off, and the world-lighting tests say so too), pixel-centre sampling
(a Gaussian filter of width 0.01 px: Cycles' Box filter ignores its width and averages the whole
pixel), no denoising, and enough samples that noise is below the differences measured. References
are cached on disk by a hash of everything that decides them.
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

import bpy
import numpy as np
import OpenEXR

ROOT = Path(__file__).resolve().parent.parent
CACHE_DIR = ROOT / ".cache" / "references"
#: Bump when the reference settings below change: old cache entries then stop matching.
SETTINGS_VERSION = 2  # 2: the world lights the scene, unoccluded
EEVEE = "BLENDER_EEVEE" if bpy.app.version >= (5, 0, 0) else "BLENDER_EEVEE_NEXT"


def scene_fingerprint(scene) -> str:
    """A hash of what the reference image depends on: geometry, transforms, materials, lights,
    camera, resolution and Blender's version (read from the evaluated scene, so a preset, a
    .blend or a scene built in code hash alike)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    h = hashlib.sha256()
    h.update(f"v{SETTINGS_VERSION} {bpy.app.version_string}".encode())
    r = scene.render
    h.update(f"{r.resolution_x}x{r.resolution_y}@{r.resolution_percentage}".encode())
    for inst in depsgraph.object_instances:
        obj = inst.object
        h.update(obj.name.encode())
        h.update(np.array(inst.matrix_world, np.float32).tobytes())
        if obj.type == "MESH":
            mesh = obj.data
            co = np.empty(len(mesh.vertices) * 3, np.float32)
            mesh.vertices.foreach_get("co", co)
            h.update(co.tobytes())
            for slot in obj.material_slots:
                h.update(_material_key(slot.material).encode())
        elif obj.type == "LIGHT":
            light = obj.data
            h.update(repr((light.type, tuple(light.color), light.energy, getattr(light, "exposure", 0.0),
                           getattr(light, "spot_size", 0), getattr(light, "spot_blend", 0),
                           getattr(light, "size", 0), getattr(light, "angle", 0))).encode())
        elif obj.type == "CAMERA":
            cam = obj.data
            h.update(repr((cam.type, cam.lens, cam.ortho_scale, cam.sensor_width, cam.shift_x,
                           cam.shift_y)).encode())
    if scene.world is not None and scene.world.node_tree is not None:
        for node in scene.world.node_tree.nodes:
            for socket in node.inputs:
                if hasattr(socket, "default_value"):
                    h.update(repr(_plain(socket.default_value)).encode())
    return h.hexdigest()[:24]


def _plain(value):
    try:
        return tuple(value)
    except TypeError:
        return value


def _material_key(mat) -> str:
    if mat is None:
        return "none"
    parts = [mat.name]
    if mat.node_tree is not None:
        for node in mat.node_tree.nodes:
            parts.append(node.bl_idname + str(getattr(node, "distribution", "")))
            for socket in node.inputs:
                if hasattr(socket, "default_value"):
                    parts.append(repr(_plain(socket.default_value)))
    return json.dumps(parts)


def _prepare_lights(scene):
    """Shadows off, radius 0, soft falloff off, objects casting no shadow (not even the world's
    light); returns a function that restores them."""
    saved = []
    for obj in scene.objects:
        if hasattr(obj, "visible_shadow") and obj.type != "LIGHT":
            saved.append((obj, {"visible_shadow": obj.visible_shadow}))
            obj.visible_shadow = False
    for obj in scene.objects:
        if obj.type == "LIGHT":
            light = obj.data
            state = {"use_shadow": light.use_shadow}
            if light.type != "SUN":
                state["shadow_soft_size"] = light.shadow_soft_size
                if hasattr(light, "use_soft_falloff"):
                    state["use_soft_falloff"] = light.use_soft_falloff
            saved.append((light, state))
            light.use_shadow = False
            if light.type != "SUN":
                light.shadow_soft_size = 0.0
                if hasattr(light, "use_soft_falloff"):
                    light.use_soft_falloff = False

    def restore():
        for light, state in saved:
            for key, value in state.items():
                setattr(light, key, value)

    return restore


def read_exr_rgba(path: Path) -> np.ndarray:
    with OpenEXR.File(str(path)) as f:
        channels = f.channels()
        if "RGBA" in channels:
            return np.asarray(channels["RGBA"].pixels, np.float32)
        return np.stack([np.asarray(channels[c].pixels, np.float32) for c in "RGBA"], axis=-1)


def render_to_array(scene, path: Path) -> np.ndarray:
    """Render with the scene's engine, save a 32-bit EXR at ``path`` and read it back (top row
    first)."""
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = "IMAGE"
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    bpy.ops.render.render()
    bpy.data.images["Render Result"].save_render(filepath=str(path), scene=scene)
    return read_exr_rgba(path)


def render_reference(scene, samples: int = 256, cache_dir: Path = CACHE_DIR) -> tuple[np.ndarray, bool]:
    """(Cycles reference image, whether it came from the cache)."""
    cache_dir.mkdir(parents=True, exist_ok=True)
    key = f"{scene_fingerprint(scene)}-s{samples}"
    cached = cache_dir / f"{key}.exr"
    if cached.is_file():
        return read_exr_rgba(cached), True
    engine = scene.render.engine
    restore = _prepare_lights(scene)
    try:
        scene.render.engine = "CYCLES"
        c = scene.cycles
        c.device = "CPU"
        c.samples = samples
        c.use_adaptive_sampling = False
        c.use_denoising = False
        c.max_bounces = 0
        c.pixel_filter_type = "GAUSSIAN"
        c.filter_width = 0.01
        c.seed = 0
        partial = cache_dir / f".{key}.partial.exr"
        image = render_to_array(scene, partial)
        partial.replace(cached)
    finally:
        scene.render.engine = engine
        restore()
    return image, False


def render_peer(scene, engine: str, samples: int, path: Path) -> tuple[np.ndarray, float]:
    """(image, seconds) of EEVEE (light threshold lowered so weak lights are not culled, shadows
    off) or Workbench on the same scene."""
    previous = scene.render.engine
    restore = _prepare_lights(scene)
    try:
        scene.render.engine = engine
        if engine == EEVEE:
            scene.eevee.taa_render_samples = samples
            scene.eevee.light_threshold = 1e-6
        start = time.perf_counter()
        image = render_to_array(scene, path)
        return image, time.perf_counter() - start
    finally:
        scene.render.engine = previous
        restore()
