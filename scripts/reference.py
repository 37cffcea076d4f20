"""Ground truth and peers: the same scene rendered by Cycles (the reference), EEVEE and Workbench.

The reference is what Shading Lab computes, computed exactly: Cycles on the CPU with direct light
only (max bounces 0), the lights as the file has them (Cast Shadow, radius, soft falloff: the
engine casts shadows with penumbrae from the lights' sizes, but still shades a sphere or area light
as a point, which the reference does not), the world lighting the scene and occluded by the
objects, pixel-centre sampling (a Gaussian filter of width 0.01 px: Cycles' Box filter ignores its
width and averages the whole pixel), no denoising, and enough samples that noise is below the
differences measured. References are cached on disk by a hash of everything that decides them.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import bpy
import numpy as np
import OpenEXR

ROOT = Path(__file__).resolve().parent.parent
CACHE_DIR = ROOT / ".cache" / "references"
#: Bump when the reference settings below change: old cache entries then stop matching.
SETTINGS_VERSION = 4  # 2: the world lights the scene; 3: objects occlude the world's light; 4: lights
#                       cast shadows and keep their size, as the file has them
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
        h.update(repr((getattr(obj, "visible_shadow", True),)).encode())
        if obj.type == "MESH":
            mesh = obj.data
            co = np.empty(len(mesh.vertices) * 3, np.float32)
            mesh.vertices.foreach_get("co", co)
            h.update(co.tobytes())
            for slot in obj.material_slots:
                h.update(_id_key(slot.material).encode())
        elif obj.type == "LIGHT":
            light = obj.data
            h.update(repr((light.type, tuple(light.color), light.energy, getattr(light, "exposure", 0.0),
                           getattr(light, "spot_size", 0), getattr(light, "spot_blend", 0),
                           getattr(light, "size", 0), getattr(light, "size_y", 0),
                           getattr(light, "shape", ""), getattr(light, "angle", 0), light.use_shadow,
                           getattr(light, "shadow_soft_size", 0),
                           getattr(light, "use_soft_falloff", None))).encode())
        elif obj.type == "CAMERA":
            cam = obj.data
            h.update(repr((cam.type, cam.lens, cam.ortho_scale, cam.sensor_width, cam.shift_x,
                           cam.shift_y)).encode())
    h.update(_id_key(scene.world).encode())
    return h.hexdigest()[:24]


def _plain(value):
    try:
        return tuple(value)
    except TypeError:
        return value


#: Properties every shader node has (placement, labels, selection): they do not change a render.
_NODE_BASE = None


def _id_key(block) -> str:
    """A material's or world's node graph as text: every node's type, settings (images by their
    file and date, or their pixels), input values and links, node groups followed."""
    if block is None:
        return "none"
    return json.dumps([block.name, _tree_key(block.node_tree, set())] if block.node_tree else [block.name])


def _tree_key(tree, seen: set) -> list:
    global _NODE_BASE
    if _NODE_BASE is None:
        _NODE_BASE = {p.identifier for p in bpy.types.ShaderNode.bl_rna.properties}
    if tree.name in seen:
        return [tree.name]
    seen.add(tree.name)
    parts = []
    for node in sorted(tree.nodes, key=lambda n: n.name):
        parts.append([node.name, node.bl_idname])
        for prop in node.bl_rna.properties:
            if prop.identifier in _NODE_BASE:
                continue
            value = getattr(node, prop.identifier)
            if isinstance(value, bpy.types.Image):
                parts.append(_image_key(value))
            elif isinstance(value, bpy.types.NodeTree):
                parts.append(_tree_key(value, seen))
            elif prop.type in ("BOOLEAN", "INT", "FLOAT", "STRING", "ENUM"):
                parts.append(repr(_plain(value)))
        for socket in node.inputs:
            if hasattr(socket, "default_value"):
                parts.append(repr(_plain(socket.default_value)))
    parts.append(sorted(f"{link.from_node.name}.{link.from_socket.identifier}>"
                        f"{link.to_node.name}.{link.to_socket.identifier}" for link in tree.links))
    return parts


def _image_key(image) -> str:
    """An image by its file's path, size and date, or (packed, generated, edited) by its pixels."""
    path = Path(bpy.path.abspath(image.filepath_raw)) if image.filepath_raw else None
    on_disk = path is not None and path.is_file()
    if image.source == "FILE" and image.packed_file is None and not image.is_dirty and on_disk:
        stat = path.stat()
        return f"{image.name} {path} {stat.st_size} {stat.st_mtime_ns}"
    pixels = np.empty(len(image.pixels), np.float32)
    image.pixels.foreach_get(pixels)
    return f"{image.name} {tuple(image.size)} {hashlib.sha256(pixels.tobytes()).hexdigest()}"


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


def render_reference(scene, samples: int = 256,
                     cache_dir: Path | None = CACHE_DIR) -> tuple[np.ndarray, bool]:
    """(Cycles reference image, whether it came from the cache); ``cache_dir`` None: rendered,
    not cached (for scenes whose fingerprint misses what sets them apart, such as rays' visibility)."""
    if cache_dir is None:
        import tempfile

        with tempfile.TemporaryDirectory() as tmp:
            return _render_cycles(scene, samples, Path(tmp) / "reference.exr"), False
    cache_dir.mkdir(parents=True, exist_ok=True)
    key = f"{scene_fingerprint(scene)}-s{samples}"
    cached = cache_dir / f"{key}.exr"
    if cached.is_file():
        return read_exr_rgba(cached), True
    partial = cache_dir / f".{key}.partial.exr"
    image = _render_cycles(scene, samples, partial)
    partial.replace(cached)
    return image, False


def _render_cycles(scene, samples: int, path: Path) -> np.ndarray:
    engine = scene.render.engine
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
        return render_to_array(scene, path)
    finally:
        scene.render.engine = engine


def use_engine(scene, engine: str, samples: int = 1) -> None:
    """Render ``scene`` with ``engine`` as every comparison sets the peers up: EEVEE at ``samples``
    per pixel with its light threshold lowered so that weak lights are not culled (lights as the
    file has them, shadows included); Workbench as it is (its studio lighting)."""
    scene.render.engine = engine
    if engine == EEVEE:
        scene.eevee.taa_render_samples = samples
        scene.eevee.light_threshold = 1e-6

