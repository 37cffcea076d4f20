"""The GPU renderer: draws a ``Snapshot`` with the scene-specialised GLSL programs.

Host-agnostic: it needs a GPU context (Blender's ``gpu`` module, inside
``RenderEngine.render()`` or ``view_draw()``) but reads no Blender data. The final render and the
viewport share it; the viewport passes its own view-projection matrix.
"""

from __future__ import annotations

import atexit
from collections.abc import Callable
from dataclasses import replace

import gpu
import numpy as np

from . import programs
from .snapshot import MaterialParams, MeshGeometry, Snapshot


class ShaderCompileError(RuntimeError):
    """A program failed to compile or link; the message carries the driver's log."""


_PROGRAMS: dict[tuple[tuple[str, str], ...], gpu.types.GPUShader] = {}
_LAST_COMPILE_ERROR = [""]  # shown in the Render panel until a render compiles cleanly


def compile_error() -> str:
    """The message of the last program that failed to compile ("" when the last render was clean)."""
    return _LAST_COMPILE_ERROR[0]


def clear_compile_error() -> None:
    _LAST_COMPILE_ERROR[0] = ""


def compiled_program_count() -> int:
    return len(_PROGRAMS)


def _compile(info, label: str, key) -> gpu.types.GPUShader:
    try:
        return gpu.shader.create_from_info(info)
    except Exception as exc:  # Blender raises a bare Exception with the driver log on stderr
        message = (f"Shading Lab could not compile its {label} program "
                   f"({', '.join(f'{n}={v}' for n, v in key)}): {exc} (the driver's log is on the console)")
        _LAST_COMPILE_ERROR[0] = message
        raise ShaderCompileError(message) from exc


def _cached_program(key, label: str, src: programs.ProgramSource, declare) -> gpu.types.GPUShader:
    """Compile ``src`` once per ``key``: defines, then ``declare(info)`` adds the interface."""
    shader = _PROGRAMS.get(key)
    if shader is not None:
        return shader
    info = gpu.types.GPUShaderCreateInfo()
    for name, value in src.defines:
        info.define(name, value)
    declare(info)
    info.fragment_out(0, "VEC4", "frag_color")
    info.vertex_source(src.vertex)
    info.fragment_source(src.fragment)
    shader = _PROGRAMS[key] = _compile(info, label, src.defines)
    return shader


def _declare_shading(info, typedefs: str, features: programs.Features) -> None:
    info.typedef_source(typedefs)
    if features.uses_albedo_table:
        info.sampler(0, "FLOAT_2D", "ms_table")
    if features.uses_s_table:
        info.sampler(1, "FLOAT_2D", "s_table")
    info.uniform_buf(0, "FrameData", "frame")
    info.uniform_buf(1, "LightBlock", "lights")
    info.uniform_buf(2, "MaterialData", "material")
    info.uniform_buf(3, "ObjectData", "object")
    for slot, name in enumerate(("base_color", "metallic", "roughness", "normal"), start=2):
        if features.has_map(name.upper()):
            info.sampler(slot, "FLOAT_2D", name + "_map")
    if features.peel:
        info.sampler(6, "FLOAT_2D", "opaque_depth")
        info.sampler(7, "FLOAT_2D", "peel_depth")
    info.vertex_in(0, "VEC3", "pos")
    info.vertex_in(1, "VEC3", "nor")
    info.vertex_in(2, "VEC2", "uv")
    info.vertex_in(3, "VEC4", "tangent")
    iface = gpu.types.GPUStageInterfaceInfo("shading_lab_iface")
    iface.smooth("VEC3", "world_position")
    iface.smooth("VEC3", "world_normal")
    iface.smooth("VEC2", "world_uv")
    iface.smooth("VEC4", "world_tangent")
    info.vertex_out(iface)


def _declare_post(info) -> None:
    info.vertex_in(0, "VEC2", "pos")
    info.sampler(0, "FLOAT_2D", "hdr_image")
    info.push_constant("FLOAT", "exposure_scale")


def get_program(features: programs.Features) -> gpu.types.GPUShader:
    """The shading program for ``features``, compiled once and cached by its sorted defines."""
    src = programs.program_source(features)
    return _cached_program(features.defines(), features.model, src,
                           lambda info: _declare_shading(info, src.typedefs, features))


_MS_TEXTURES: dict[tuple[str, str], gpu.types.GPUTexture] = {}


def _r32f(table: np.ndarray) -> gpu.types.GPUTexture:
    h, w = table.shape
    data = gpu.types.Buffer("FLOAT", w * h, np.ascontiguousarray(table, np.float32).ravel())
    return gpu.types.GPUTexture((w, h), format="R32F", data=data)


def rgba32f_texture(image: np.ndarray) -> gpu.types.GPUTexture:
    """An (h, w, 4) float image (bottom row first) as a texture."""
    h, w = image.shape[:2]
    data = gpu.types.Buffer("FLOAT", w * h * 4, np.ascontiguousarray(image, np.float32).ravel())
    return gpu.types.GPUTexture((w, h), format="RGBA32F", data=data)


def multiscatter_texture(terms) -> gpu.types.GPUTexture:
    """The directional-albedo table of ``terms``' D and V as an R32F texture (built once); for the
    Principled set, GGX + Smith's table with Eavg(r) as an extra row."""
    from . import multiscatter

    key = ("PRINCIPLED",) if terms.principled else (terms.ndf, terms.visibility)
    texture = _MS_TEXTURES.get(key)
    if texture is None:
        if terms.principled:
            table = np.vstack([multiscatter.albedo_table("GGX", "SMITH_CORRELATED"),
                               multiscatter.average_albedo()[None, :]])
        else:
            table = multiscatter.albedo_table(*key)
        texture = _MS_TEXTURES[key] = _r32f(table)
    return texture


def principled_s_texture() -> gpu.types.GPUTexture:
    """The Principled set's S(r, mu, z) table as a 16 x 256 R32F atlas (rows: mu + 16 z)."""
    from . import multiscatter

    texture = _MS_TEXTURES.get(("S",))
    if texture is None:
        table = multiscatter.principled_s_table()
        n = table.shape[0]
        texture = _MS_TEXTURES[("S",)] = _r32f(table.reshape(n * n, n))
    return texture


def _declare_compare(info) -> None:
    info.vertex_in(0, "VEC2", "pos")
    info.sampler(0, "FLOAT_2D", "image_a")
    info.sampler(1, "FLOAT_2D", "image_b")
    info.push_constant("FLOAT", "split")
    info.push_constant("FLOAT", "range")


def get_compare_program(features: programs.CompareFeatures) -> gpu.types.GPUShader:
    return _cached_program(("compare",) + features.defines(), "compare", programs.compare_source(features),
                           _declare_compare)


def _declare_occupancy(info) -> None:
    info.vertex_in(0, "VEC2", "pos")
    info.sampler(0, "FLOAT_2D", "layer_depth")


def get_occupancy_program() -> gpu.types.GPUShader:
    src = programs.occupancy_source()
    return _cached_program(("occupancy",) + src.defines, "occupancy", src, _declare_occupancy)


def _declare_under(info) -> None:
    info.vertex_in(0, "VEC2", "pos")
    info.sampler(0, "FLOAT_2D", "accumulated")
    info.sampler(1, "FLOAT_2D", "peeled")


def get_under_program() -> gpu.types.GPUShader:
    src = programs.under_source()
    return _cached_program(("under",), "transparency composite", src, _declare_under)


def get_post_program(features: programs.PostFeatures) -> gpu.types.GPUShader:
    """The resolve/display pass for ``features``, cached like the shading programs."""
    return _cached_program(("post",) + features.defines(), "display", programs.post_source(features),
                           _declare_post)


def clear_program_cache() -> None:
    _PROGRAMS.clear()
    _MS_TEXTURES.clear()
    programs.program_source.cache_clear()
    programs.post_source.cache_clear()
    programs.occupancy_source.cache_clear()
    programs.under_source.cache_clear()


# Compiled programs outlive renders; free them before Blender tears its GPU module down, or it
# reports them as leaked blocks at exit.
atexit.register(clear_program_cache)


def _vertex_format() -> gpu.types.GPUVertFormat:
    fmt = gpu.types.GPUVertFormat()
    fmt.attr_add(id="pos", comp_type="F32", len=3, fetch_mode="FLOAT")
    fmt.attr_add(id="nor", comp_type="F32", len=3, fetch_mode="FLOAT")
    fmt.attr_add(id="uv", comp_type="F32", len=2, fetch_mode="FLOAT")
    fmt.attr_add(id="tangent", comp_type="F32", len=4, fetch_mode="FLOAT")
    return fmt


def upload_geometry(geometry: MeshGeometry) -> list[tuple[int, gpu.types.GPUBatch]]:
    """One batch per material range: ``[(slot, batch), ...]``."""
    fmt = _vertex_format()
    batches = []
    for slot, first, count in geometry.ranges:
        if count == 0:
            continue
        vbo = gpu.types.GPUVertBuf(fmt, count)
        part = slice(first, first + count)
        vbo.attr_fill("pos", np.ascontiguousarray(geometry.positions[part], np.float32))
        vbo.attr_fill("nor", np.ascontiguousarray(geometry.normals[part], np.float32))
        uvs = geometry.uvs[part] if geometry.uvs is not None else np.zeros((count, 2), np.float32)
        tangents = (geometry.tangents[part] if geometry.tangents is not None
                    else np.zeros((count, 4), np.float32))
        vbo.attr_fill("uv", np.ascontiguousarray(uvs, np.float32))
        vbo.attr_fill("tangent", np.ascontiguousarray(tangents, np.float32))
        batches.append((slot, gpu.types.GPUBatch(type="TRIS", buf=vbo)))
    return batches


def _read(fb, w: int, h: int) -> np.ndarray:
    buffer = fb.read_color(0, 0, w, h, 4, 0, "FLOAT")
    buffer.dimensions = w * h * 4
    return np.array(buffer, np.float32).reshape(h, w, 4)  # a copy: a view would pin the GPU buffer


_FULL_SCREEN = ((-1.0, -1.0), (3.0, -1.0), (-1.0, 3.0))


def _full_screen_batch() -> gpu.types.GPUBatch:
    fmt = gpu.types.GPUVertFormat()
    fmt.attr_add(id="pos", comp_type="F32", len=2, fetch_mode="FLOAT")
    vbo = gpu.types.GPUVertBuf(fmt, 3)
    vbo.attr_fill("pos", _FULL_SCREEN)
    return gpu.types.GPUBatch(type="TRIS", buf=vbo)


def _full_screen_pass(shader, bind: Callable[[gpu.types.GPUShader], None], w: int, h: int,
                      target=None, read: bool = False) -> np.ndarray | None:
    """Draw ``shader`` over a w x h float target (``bind`` sets its inputs) and read it back, or
    into ``target`` (one the caller owns, e.g. the viewport's), read back only if ``read``."""
    batch = _full_screen_batch()
    own = target is None
    if own:
        target = SceneTarget(w, h, depth=False)
    try:
        with target.bind():
            fb = gpu.state.active_framebuffer_get()
            fb.clear(color=(0.0, 0.0, 0.0, 0.0))
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set("NONE")
            shader.bind()
            bind(shader)
            batch.draw(shader)
            return _read(fb, w, h) if own or read else None
    finally:
        if own:
            target.free()


def compare_pass(texture_a, texture_b, w: int, h: int, features: programs.CompareFeatures,
                 split: float = 0.5, value_range: float = 1.0, target=None) -> np.ndarray | None:
    """Composite two same-size renders: a split view or a difference heat map."""

    def bind(shader):
        shader.uniform_sampler("image_a", texture_a)
        shader.uniform_sampler("image_b", texture_b)
        if features.mode == "SPLIT":
            shader.uniform_float("split", float(split))
        else:
            shader.uniform_float("range", float(value_range))

    return _full_screen_pass(get_compare_program(features), bind, w, h, target)


def post_pass(texture, w: int, h: int, features: programs.PostFeatures, exposure_ev: float = 0.0,
              target=None) -> np.ndarray | None:
    """The resolve/display pass over ``texture``: supersampling average, then the tone curve."""

    def bind(shader):
        shader.uniform_sampler("hdr_image", texture)
        if features.tone_mapper is not None:  # the resolve-only pass has no such uniform
            shader.uniform_float("exposure_scale", 2.0 ** exposure_ev)

    return _full_screen_pass(get_post_program(features), bind, w, h, target)


class SceneTarget:
    """A float colour texture and (unless ``depth`` is False) a depth texture drawn into
    together, both readable by shaders (depth peeling samples the opaque depth); with the
    ``bind``/``texture_color`` interface of a ``GPUOffScreen``. The peeling buffers are made on
    first use and kept with the target: their number does not depend on the layer count."""

    def __init__(self, width: int, height: int, format: str = "RGBA32F", depth: bool = True):
        self.width, self.height, self.format = width, height, format
        self.texture_color = gpu.types.GPUTexture((width, height), format=format)
        self.texture_depth = (gpu.types.GPUTexture((width, height), format="DEPTH_COMPONENT32F")
                              if depth else None)
        if depth:
            self.framebuffer = gpu.types.GPUFrameBuffer(color_slots=self.texture_color,
                                                        depth_slot=self.texture_depth)
        else:
            self.framebuffer = gpu.types.GPUFrameBuffer(color_slots=self.texture_color)
        self._peel: _PeelBuffers | None = None

    def bind(self):
        return self.framebuffer.bind()

    def peel_buffers(self) -> _PeelBuffers:
        if self._peel is None:
            self._peel = _PeelBuffers(self.width, self.height, self.format)
        return self._peel

    def drop_peel_buffers(self) -> None:
        self._peel = None

    def free(self) -> None:
        """Drop every texture and framebuffer (Blender frees them with their last reference)."""
        self._peel = None
        self.framebuffer = self.texture_color = self.texture_depth = None


class _PeelBuffers:
    """What depth peeling needs beside its target, the same for any number of layers: the layer
    being peeled (colour, and two depth textures taking turns as the depth written and the
    previous layer's depth read), two accumulators taking turns for the front-to-back composite,
    and the small occupancy map that tells whether a layer holds anything."""

    def __init__(self, width: int, height: int, format: str):
        size = (width, height)
        self.colour = gpu.types.GPUTexture(size, format=format)
        self.depths = [gpu.types.GPUTexture(size, format="DEPTH_COMPONENT32F") for _ in range(2)]
        # layer i writes depth (i + 1) % 2 and reads depth i % 2, the previous layer's
        self.layer_fbs = [gpu.types.GPUFrameBuffer(color_slots=self.colour, depth_slot=depth)
                          for depth in (self.depths[1], self.depths[0])]
        self.first = gpu.types.GPUFrameBuffer(depth_slot=self.depths[0])  # cleared to 0 for layer 0
        self.accumulators = [SceneTarget(width, height, format, depth=False) for _ in range(2)]
        block = programs.OCCUPANCY_BLOCK
        self.occupancy = SceneTarget(-(-width // block), -(-height // block), depth=False)

    def any_fragment(self, depth: gpu.types.GPUTexture) -> bool:
        """Whether a peeled layer's depth holds any fragment: reduced on the GPU to one texel per
        block of ``programs.OCCUPANCY_BLOCK`` texels a side, and only that read back."""
        occ = self.occupancy
        image = _full_screen_pass(get_occupancy_program(), lambda s: s.uniform_sampler("layer_depth", depth),
                                  occ.width, occ.height, target=occ, read=True)
        return bool(image[..., 0].max() > 0.0)


class Renderer:
    """Holds the GPU copies of one snapshot's geometry and draws it.

    ``sync`` uploads geometry it has not seen (by key) and drops what the snapshot no longer has;
    ``draw`` draws into the bound framebuffer; ``render`` draws into a float target and reads it
    back. ``free`` releases every GPU object the renderer owns.
    """

    def __init__(self, image_loader: Callable[[str, bool], gpu.types.GPUTexture] | None = None):
        self._batches: dict[str, list[tuple[int, gpu.types.GPUBatch]]] = {}
        self.uploaded_geometry = 0  # geometries uploaded by the last sync (for tests and stats)
        self.peeled_layers = 0  # transparency layers the last draw blended (for tests and stats)
        #: (image name, nearest filtering) -> texture; None draws materials without their maps
        self.image_loader = image_loader

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
             should_stop: Callable[[], bool] | None = None, half_target: bool = False,
             lobes: tuple[float, float, float, float] = programs.ALL_LOBES, *,
             target: SceneTarget) -> None:
        """Draw every item into ``target`` (bound by the caller), one program per shading model
        in use (the scene's, and any material's own override). Partly transparent surfaces come
        after the opaque ones, depth peeled and composited in depth order per pixel."""
        frame_ubo = gpu.types.GPUUniformBuf(programs.pack_frame(snapshot, view_projection, lobes))
        light_ubo = gpu.types.GPUUniformBuf(
            programs.pack_lights(snapshot, programs.light_slots(len(snapshot.lights))))
        material_ubos = {
            key: gpu.types.GPUUniformBuf(programs.pack_material(m))
            for key, m in snapshot.materials.items()
        }
        with_maps = self.image_loader is not None
        features = {key: programs.Features.from_snapshot(snapshot, material=m, half_target=half_target,
                                                         with_maps=with_maps)
                    for key, m in snapshot.materials.items()}
        textures = {}
        if with_maps:
            for m in snapshot.materials.values():
                for name in MaterialParams.MAPS:
                    ref = getattr(m, name)
                    if ref is not None and ref not in textures:
                        textures[ref] = self.image_loader(*ref)
        groups: dict[programs.Features, list] = {}
        blended: dict[programs.Features, list] = {}  # partly transparent, by peeling program
        for index, item in enumerate(snapshot.items):
            batches = self._batches.get(item.geometry)
            if not batches:
                continue
            object_ubo = gpu.types.GPUUniformBuf(programs.pack_object(item.matrix, item.normal_matrix))
            for slot, batch in batches:
                key = item.materials[slot] if slot < len(item.materials) else item.materials[-1]
                record = (index, object_ubo, key, batch)
                material = snapshot.materials[key]
                if material.alpha < 1.0 or features[key].alpha_from_base_map:
                    blended.setdefault(replace(features[key], peel=True), []).append(record)
                else:
                    groups.setdefault(features[key], []).append(record)
        shared = (snapshot, frame_ubo, light_ubo, material_ubos, textures, should_stop)
        self.peeled_layers = 0
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(True)
        gpu.state.face_culling_set("NONE")
        gpu.state.blend_set("NONE")
        try:
            for feature_set, draws in sorted(groups.items(), key=lambda kv: kv[0].defines()):
                if not self._draw_group(feature_set, draws, shared):
                    return
            if blended:
                self._draw_peeled(target, blended, snapshot.settings.transparency_layers, shared)
            else:
                target.drop_peel_buffers()  # a viewport target keeps none once nothing is transparent
        finally:
            gpu.state.depth_test_set("NONE")
            gpu.state.depth_mask_set(False)
            gpu.state.blend_set("NONE")

    @staticmethod
    def _draw_group(feature_set: programs.Features, draws: list, shared: tuple,
                    bind: Callable[[gpu.types.GPUShader], None] | None = None) -> bool:
        """Draw ``draws`` (records of one feature set) with its program; False if cancelled."""
        snapshot, frame_ubo, light_ubo, material_ubos, textures, should_stop = shared
        shader = get_program(feature_set)
        shader.bind()
        shader.uniform_block("frame", frame_ubo)
        shader.uniform_block("lights", light_ubo)
        if feature_set.uses_albedo_table:
            shader.uniform_sampler("ms_table", multiscatter_texture(feature_set.terms))
        if feature_set.uses_s_table:
            shader.uniform_sampler("s_table", principled_s_texture())
        if bind is not None:
            bind(shader)
        for index, object_ubo, key, batch in draws:
            if should_stop is not None and index % 64 == 0 and should_stop():
                return False
            shader.uniform_block("object", object_ubo)
            shader.uniform_block("material", material_ubos[key])
            for name in feature_set.maps:
                sampler = name.removesuffix("_CLOSEST").lower() + "_map"
                shader.uniform_sampler(sampler, textures[getattr(snapshot.materials[key], sampler)])
            batch.draw(shader)
        return True

    def _draw_peeled(self, target: SceneTarget, groups: dict, layers: int, shared: tuple) -> None:
        """Depth peeling: up to ``layers`` passes over the partly transparent surfaces, each keeping
        the nearest fragment behind the previous pass's (per pixel, exact order, also within one
        mesh), composited front to back as they come; then the result over ``target``. A pass
        whose predecessor peeled nothing is not drawn: the scene needs no more layers."""
        buffers = target.peel_buffers()
        with buffers.first.bind():
            gpu.state.active_framebuffer_get().clear(depth=0.0)
        ordered = sorted(groups.items(), key=lambda kv: kv[0].defines())
        under = get_under_program()
        current = 0
        with buffers.accumulators[current].bind():
            gpu.state.active_framebuffer_get().clear(color=(0.0, 0.0, 0.0, 0.0))
        used = 0
        for i in range(max(int(layers), 1)):
            previous = buffers.depths[i % 2]  # written by the last pass (cleared to 0 before the first)
            if used and not buffers.any_fragment(previous):
                used -= 1  # the last pass peeled nothing, so no surface is left behind it
                break
            framebuffer = buffers.layer_fbs[i % 2]
            with framebuffer.bind():
                framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
                gpu.state.depth_test_set("LESS")
                gpu.state.depth_mask_set(True)
                gpu.state.blend_set("NONE")

                def bind(shader, previous=previous):
                    shader.uniform_sampler("opaque_depth", target.texture_depth)
                    shader.uniform_sampler("peel_depth", previous)

                for feature_set, draws in ordered:
                    if not self._draw_group(feature_set, draws, shared, bind):
                        return
            accumulated = buffers.accumulators[current]
            current = 1 - current

            def bind_under(shader, accumulated=accumulated):
                shader.uniform_sampler("accumulated", accumulated.texture_color)
                shader.uniform_sampler("peeled", buffers.colour)

            _full_screen_pass(under, bind_under, target.width, target.height,
                              target=buffers.accumulators[current])
            used += 1
        self.peeled_layers = used
        gpu.state.depth_test_set("NONE")
        gpu.state.depth_mask_set(False)
        gpu.state.blend_set("ALPHA_PREMULT")  # C + (1 - A) L_behind
        copy = get_post_program(programs.PostFeatures(samples=1))
        copy.bind()
        copy.uniform_sampler("hdr_image", buffers.accumulators[current].texture_color)
        _full_screen_batch().draw(copy)

    def render(self, snapshot: Snapshot, background: tuple[float, float, float, float] = (0, 0, 0, 1),
               should_stop: Callable[[], bool] | None = None) -> np.ndarray:
        """Draw into an RGBA32F target; returns (height, width, 4) float32, bottom row first.

        Shorthand for ``render_passes`` without supersampling or display output.
        """
        return self.render_passes(snapshot, background, should_stop)[0]

    def render_lobe(self, snapshot: Snapshot, lobes: tuple[float, float, float, float],
                    samples: int = 1) -> np.ndarray:
        """One lobe's radiance (e.g. (1, 0, 0, 0): diffuse light only, unclamped), black
        background, averaged over the same supersampling grid as Combined."""
        return self.render_passes(snapshot, (0.0, 0.0, 0.0, 0.0), samples=samples, lobes=lobes)[0]

    def render_passes(self, snapshot: Snapshot, background=(0, 0, 0, 1),
                      should_stop: Callable[[], bool] | None = None, samples: int = 1,
                      display: programs.PostFeatures | None = None, exposure_ev: float = 0.0,
                      lobes: tuple[float, float, float, float] = programs.ALL_LOBES):
        """Radiance (averaged over ``samples`` x ``samples`` sub-pixels) and, when ``display`` names
        a tone mapper, the display-linear image; each (height, width, 4) float32, bottom row first."""
        w, h = snapshot.width, snapshot.height
        samples = max(int(samples), 1)
        self.sync(snapshot)
        scene_target = SceneTarget(w * samples, h * samples)
        try:
            with scene_target.bind():
                fb = gpu.state.active_framebuffer_get()
                fb.clear(color=background, depth=1.0)
                self.draw(snapshot, should_stop=should_stop, lobes=lobes, target=scene_target)
                if samples == 1 and display is None:
                    return _read(fb, w, h), None
            texture = scene_target.texture_color
            radiance = post_pass(texture, w, h, programs.PostFeatures(samples=samples))
            shown = None
            if display is not None:
                shown = post_pass(texture, w, h, programs.PostFeatures(samples, display.tone_mapper,
                                                                       display.transfer), exposure_ev)
            return radiance, shown
        finally:
            scene_target.free()

    def render_compare(self, snapshot: Snapshot, models: tuple[str, str], compare: programs.CompareFeatures,
                       background: Callable[[Snapshot], tuple], split: float = 0.5, value_range: float = 1.0,
                       should_stop: Callable[[], bool] | None = None, samples: int = 1,
                       display: programs.PostFeatures | None = None, exposure_ev: float = 0.0) -> np.ndarray:
        """The frame rendered with two models and composited (split view or difference map).
        A split composites what Combined would hold (display values under an engine tone
        mapper); a difference map compares radiance."""
        images = []
        for model in models:
            snap = replace(snapshot, settings=replace(snapshot.settings, model=model))
            radiance, shown = self.render_passes(snap, background(snap), should_stop, samples, display,
                                                 exposure_ev)
            images.append(shown if shown is not None and compare.mode == "SPLIT" else radiance)
        textures = [rgba32f_texture(image) for image in images]
        return compare_pass(textures[0], textures[1], snapshot.width, snapshot.height, compare, split,
                            value_range)

    def free(self) -> None:
        self._batches.clear()
