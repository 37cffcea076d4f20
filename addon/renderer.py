"""The GPU renderer: draws a ``Snapshot`` with the scene-specialised GLSL programs.

Host-agnostic: it needs a GPU context (Blender's ``gpu`` module, inside
``RenderEngine.render()`` or ``view_draw()``) but reads no Blender data. The final render and the
viewport share it; the viewport passes its own view-projection matrix.
"""

from __future__ import annotations

import atexit
from collections.abc import Callable

import gpu
import numpy as np

from . import programs
from .snapshot import MeshGeometry, Snapshot


class ShaderCompileError(RuntimeError):
    """A program failed to compile or link; the message carries the driver's log."""


_PROGRAMS: dict[tuple[tuple[str, str], ...], gpu.types.GPUShader] = {}


def compiled_program_count() -> int:
    return len(_PROGRAMS)


def get_program(features: programs.Features) -> gpu.types.GPUShader:
    """The program for ``features``, compiled once and cached by its sorted defines."""
    key = features.defines()
    shader = _PROGRAMS.get(key)
    if shader is not None:
        return shader
    src = programs.program_source(features)
    info = gpu.types.GPUShaderCreateInfo()
    for name, value in src.defines:
        info.define(name, value)
    info.typedef_source(src.typedefs)
    info.uniform_buf(0, "FrameData", "frame")
    info.uniform_buf(1, "LightBlock", "lights")
    info.uniform_buf(2, "MaterialData", "material")
    info.uniform_buf(3, "ObjectData", "object")
    info.vertex_in(0, "VEC3", "pos")
    info.vertex_in(1, "VEC3", "nor")
    iface = gpu.types.GPUStageInterfaceInfo("shading_lab_iface")
    iface.smooth("VEC3", "world_position")
    iface.smooth("VEC3", "world_normal")
    info.vertex_out(iface)
    info.fragment_out(0, "VEC4", "frag_color")
    info.vertex_source(src.vertex)
    info.fragment_source(src.fragment)
    try:
        shader = gpu.shader.create_from_info(info)
    except Exception as exc:  # Blender raises a bare Exception with the driver log on stderr
        raise ShaderCompileError(
            f"Shading Lab could not compile its {features.model} program "
            f"({', '.join(f'{n}={v}' for n, v in key)}): {exc}"
        ) from exc
    _PROGRAMS[key] = shader
    return shader


def clear_program_cache() -> None:
    _PROGRAMS.clear()


# Compiled programs outlive renders; free them before Blender tears its GPU module down, or it
# reports them as leaked blocks at exit.
atexit.register(clear_program_cache)


def _vertex_format() -> gpu.types.GPUVertFormat:
    fmt = gpu.types.GPUVertFormat()
    fmt.attr_add(id="pos", comp_type="F32", len=3, fetch_mode="FLOAT")
    fmt.attr_add(id="nor", comp_type="F32", len=3, fetch_mode="FLOAT")
    return fmt


def upload_geometry(geometry: MeshGeometry) -> list[tuple[int, gpu.types.GPUBatch]]:
    """One batch per material range: ``[(slot, batch), ...]``."""
    fmt = _vertex_format()
    batches = []
    for slot, first, count in geometry.ranges:
        if count == 0:
            continue
        vbo = gpu.types.GPUVertBuf(fmt, count)
        vbo.attr_fill("pos", np.ascontiguousarray(geometry.positions[first:first + count], np.float32))
        vbo.attr_fill("nor", np.ascontiguousarray(geometry.normals[first:first + count], np.float32))
        batches.append((slot, gpu.types.GPUBatch(type="TRIS", buf=vbo)))
    return batches


class Renderer:
    """Holds the GPU copies of one snapshot's geometry and draws it.

    ``sync`` uploads geometry it has not seen (by key) and drops what the snapshot no longer has;
    ``draw`` draws into the bound framebuffer; ``render`` draws into a float target and reads it
    back. ``free`` releases every GPU object the renderer owns.
    """

    def __init__(self):
        self._batches: dict[str, list[tuple[int, gpu.types.GPUBatch]]] = {}
        self.uploaded_geometry = 0  # geometries uploaded by the last sync (for tests and stats)

    def sync(self, snapshot: Snapshot, keep: Callable[[str], bool] | None = None) -> None:
        self.uploaded_geometry = 0
        for key in list(self._batches):
            if key not in snapshot.geometries or (keep is not None and not keep(key)):
                del self._batches[key]
        for key, geometry in snapshot.geometries.items():
            if key not in self._batches:
                self._batches[key] = upload_geometry(geometry)
                self.uploaded_geometry += 1

    def draw(self, snapshot: Snapshot, view_projection: np.ndarray | None = None,
             should_stop: Callable[[], bool] | None = None) -> None:
        features = programs.Features.from_snapshot(snapshot)
        shader = get_program(features)
        frame_ubo = gpu.types.GPUUniformBuf(programs.pack_frame(snapshot, view_projection))
        light_ubo = gpu.types.GPUUniformBuf(programs.pack_lights(snapshot, features.max_lights))
        material_ubos = {
            key: gpu.types.GPUUniformBuf(programs.pack_material(m))
            for key, m in snapshot.materials.items()
        }
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(True)
        gpu.state.face_culling_set("NONE")
        gpu.state.blend_set("NONE")
        shader.bind()
        shader.uniform_block("frame", frame_ubo)
        shader.uniform_block("lights", light_ubo)
        for index, item in enumerate(snapshot.items):
            if should_stop is not None and index % 64 == 0 and should_stop():
                break
            object_ubo = gpu.types.GPUUniformBuf(programs.pack_object(item.matrix, item.normal_matrix))
            shader.uniform_block("object", object_ubo)
            for slot, batch in self._batches.get(item.geometry, ()):
                key = item.materials[slot] if slot < len(item.materials) else item.materials[-1]
                shader.uniform_block("material", material_ubos[key])
                batch.draw(shader)
        gpu.state.depth_test_set("NONE")
        gpu.state.depth_mask_set(False)

    def render(self, snapshot: Snapshot, background: tuple[float, float, float, float] = (0, 0, 0, 1),
               should_stop: Callable[[], bool] | None = None) -> np.ndarray:
        """Draw into an RGBA32F target; returns (height, width, 4) float32, bottom row first."""
        w, h = snapshot.width, snapshot.height
        self.sync(snapshot)
        offscreen = gpu.types.GPUOffScreen(w, h, format="RGBA32F")
        try:
            with offscreen.bind():
                fb = gpu.state.active_framebuffer_get()
                fb.clear(color=background, depth=1.0)
                self.draw(snapshot, should_stop=should_stop)
                buffer = fb.read_color(0, 0, w, h, 4, 0, "FLOAT")
        finally:
            offscreen.free()
        buffer.dimensions = w * h * 4
        return np.array(buffer, np.float32).reshape(h, w, 4)  # a copy: a view would pin the GPU buffer

    def free(self) -> None:
        self._batches.clear()
