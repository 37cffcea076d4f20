"""GPU objects shared by every renderer: compiled programs and precomputed tables.

Final renders (a render thread in the UI), material previews (job threads) and the viewport (the
main thread) all draw with the same programs, so they live here, once, behind one lock:

- ``program(key, ...)`` compiles a program the first time its key is asked for and returns the
  same object afterwards; ``table(key, build)`` does the same for lookup-table textures.
- ``clear()`` (unregister, exit) empties the library without freeing anything in use: a renderer
  holds its own references to the programs and tables of the frame it is drawing
  (``Renderer`` keeps them for its lifetime), and Blender frees a GPU object only when its last
  Python reference goes. A render running across an unregister finishes with the programs it
  has; the next request compiles anew.
- The message of the last failed compile is kept for the Render panel until a render compiles
  cleanly.
- ``take_spare(key)`` / ``keep_spare(key, ...)``: textures a finished renderer handed back (its
  shadow maps; its targets' textures, ``take_texture`` / ``keep_textures``) for the next one of
  the same shape, and the buffers a final render read its pixels into once it has handed them to
  Blender (``take_read_buffer`` / ``keep_read_buffers``), within ``SPARE_BYTES``, with what the
  renderer says of their content (the shadow maps' layers that hold nothing, and with Persistent
  Data what they hold).
- ``image_texture(image, build)``: each image's texture, uploaded once per read of its pixels,
  within ``IMAGE_BYTES``.

Blender shares programs and textures between its GPU contexts, so a program compiled on the
render thread serves the viewport too; framebuffers and vertex arrays are per context and are
never kept here (each ``Renderer`` owns its own).
"""

from __future__ import annotations

import atexit
import threading
import weakref
from collections.abc import Callable

import gpu
import numpy as np

from ..plan import programs
from ..reference import environment as env


class ShaderCompileError(RuntimeError):
    """A program failed to compile or link; the message carries the driver's log."""


#: Precomputed worlds kept (each ~13 MB of GPU memory): the viewport going back and forth
#: between two worlds, or a world edit and its undo, recomputes nothing.
ENVIRONMENTS_KEPT = 2
#: Programs kept, least recently used dropped first: per-material term sets (Auto), light counts
#: and shadow layouts multiply the variants an editing session meets; each holds driver memory.
PROGRAMS_KEPT = 96
#: Shadow-map textures kept between renders, in bytes of GPU memory (a bounded pool: the oldest
#: goes first). A final render makes a new renderer each time, and a fresh array of depth maps
#: costs more to allocate than to draw on the CPU rasteriser (a softbox scene's 12 layers of
#: 1024^2: ~40 ms of its ~90 ms shadow pass): the next render of the same shape takes the texture
#: back and draws every layer a caster reaches again; of the others it clears only those that do
#: not hold "nothing" already (the renderer that kept it says which, passes.ShadowPass.far), or,
#: with Persistent Data, draws nothing where the maps hold what it would draw
#: (passes.ShadowPass.content and .held). Textures larger than this are freed as before. The passes'
#: targets go the same way (``keep_textures``): a fresh 640 x 360 float texture cost 1-3 ms to
#: allocate, ~8 ms of a world-lit frame's targets.
SPARE_BYTES = 256 << 20
#: Bytes per texel of the formats passes' targets use (``keep_textures``' accounting).
TEXEL_BYTES = {"RGBA32F": 16, "RGBA16F": 8, "RG32F": 8, "R32F": 4, "R16F": 2, "RGBA8": 4,
               "DEPTH_COMPONENT32F": 4, "DEPTH_COMPONENT24": 4, "DEPTH24_STENCIL8": 4}
#: Image textures kept between renderers, in bytes of GPU memory (least recently used dropped
#: first). A final render makes a new renderer each time, and uploading an image costs it again:
#: 12 ms of the world preset's ~110 ms frame for its 1024 x 512 half-float world (the conversion
#: and the driver's copy). The pixels' identity keys them (``snapshot.ImageData``: the scene reader
#: keeps one object per image until the image changes), so an edited image is uploaded again and
#: its old texture dropped at once; an image larger than this is not kept.
IMAGE_BYTES = 512 << 20


class _Library:
    def __init__(self):
        self._lock = threading.RLock()  # re-entrant: a table's builder may ask for another table
        self._programs: dict = {}
        self._tables: dict = {}
        self._environments: dict = {}
        self._spares: list = []  # (key, texture, bytes, state), oldest first
        self._images: dict = {}  # image key -> (weakref to its ImageData, texture, bytes), by use
        self.image_uploads = 0  # image textures made since start (tests count them)
        self._compile_error = ""
        self._failed: dict = {}  # key -> why it did not compile (not tried again on every redraw)
        self.compiles = 0  # programs compiled since start (for tests and benchmarks)

    def program(self, key, label: str, src: programs.ProgramSource,
                declare: Callable[[gpu.types.GPUShaderCreateInfo], None]) -> gpu.types.GPUShader:
        """The program for ``key``: ``src``'s defines, then ``declare(info)`` adds the interface."""
        with self._lock:
            shader = self._programs.pop(key, None)
            if shader is not None:
                self._programs[key] = shader  # most recently used last
                return shader
            if key in self._failed:
                self._compile_error = self._failed[key]
                raise ShaderCompileError(self._failed[key])
            info = gpu.types.GPUShaderCreateInfo()
            for name, value in src.defines:
                info.define(name, value)
            declare(info)
            info.fragment_out(0, "VEC4", "frag_color")
            info.vertex_source(src.vertex)
            info.fragment_source(src.fragment)
            try:
                shader = gpu.shader.create_from_info(info)
            except Exception as exc:  # Blender raises a bare Exception with the driver log on stderr
                message = (f"Shading Lab could not compile its {label} program "
                           f"({', '.join(f'{n}={v}' for n, v in src.defines)}): {exc} "
                           f"(the driver's log is on the console)")
                self._compile_error = self._failed[key] = message
                raise ShaderCompileError(message) from exc
            self.compiles += 1
            self._programs[key] = shader
            while len(self._programs) > PROGRAMS_KEPT:
                del self._programs[next(iter(self._programs))]
            return shader

    def table(self, key, build: Callable[[], gpu.types.GPUTexture]) -> gpu.types.GPUTexture:
        """The lookup-table texture ``key``, built by ``build()`` once."""
        with self._lock:
            texture = self._tables.get(key)
            if texture is None:
                texture = self._tables[key] = build()
            return texture

    def environment(self, key, build: Callable[[], object]):
        """The precomputed world light for ``key`` (its content), built by ``build()`` when it is
        not one of the last ``ENVIRONMENTS_KEPT`` asked for."""
        with self._lock:
            held = self._environments.pop(key, None)
            if held is None:
                held = build()
            self._environments[key] = held  # most recently used last
            while len(self._environments) > ENVIRONMENTS_KEPT:
                del self._environments[next(iter(self._environments))]
            return held

    def image_texture(self, image, build: Callable[[object], gpu.types.GPUTexture]) -> tuple:
        """(the texture of ``image``, whether it was uploaded now): ``build(image)`` makes it
        unless this very ``snapshot.ImageData`` was uploaded before and kept (``IMAGE_BYTES``).
        Shared and read-only: every renderer samples it, none draws into it."""
        with self._lock:
            held = self._images.pop(image.key, None)
            if held is not None and held[0]() is image:
                self._images[image.key] = held  # most recently used last
                return held[1], False
            texture = build(image)
            self.image_uploads += 1
            # an image the scene reader let go of (its cache's budget, a file load) goes too
            for key in [key for key, entry in self._images.items() if entry[0]() is None]:
                del self._images[key]
            size = image.pixels.nbytes  # the texture's too: each storage keeps its texels' format
            if size <= IMAGE_BYTES:
                self._images[image.key] = (weakref.ref(image), texture, size)
                while sum(entry[2] for entry in self._images.values()) > IMAGE_BYTES:
                    del self._images[next(iter(self._images))]
            return texture, True

    def image_bytes(self) -> int:
        with self._lock:
            return sum(entry[2] for entry in self._images.values())

    def take_spare(self, key) -> tuple | None:
        """(a texture a finished renderer left for ``key`` (its kind and shape), what that renderer
        said of its content), or None. Taken, not shared: two renderers never draw into one
        texture."""
        with self._lock:
            for i, (held_key, texture, _size, state) in enumerate(self._spares):
                if held_key == key:
                    del self._spares[i]
                    return texture, state
            return None

    def keep_spare(self, key, texture, size: int, state=None, first_out: bool = False) -> None:
        """Keep a renderer's ``texture`` (``size`` bytes) and ``state`` (what its content is, for
        the next user) for the next renderer asking for ``key``, within ``SPARE_BYTES`` (the
        oldest dropped first; ``first_out``: dropped before everything kept so far)."""
        if size > SPARE_BYTES:
            return
        with self._lock:
            if first_out:
                self._spares.insert(0, (key, texture, size, state))
            else:
                self._spares.append((key, texture, size, state))
            while sum(entry[2] for entry in self._spares) > SPARE_BYTES:
                del self._spares[0]

    def take_texture(self, width: int, height: int, format: str) -> gpu.types.GPUTexture | None:
        """A 2D texture of this size and format a finished renderer handed back, or None."""
        spare = self.take_spare(("texture", width, height, format))
        return None if spare is None else spare[0]

    def keep_textures(self, textures) -> None:
        """Keep a finished renderer's 2D ``textures`` for the next renderers' targets of their size
        and format (their content is not kept: a target is drawn before it is read)."""
        for texture in textures:
            size = texture.width * texture.height * TEXEL_BYTES.get(texture.format, 16)
            self.keep_spare(("texture", texture.width, texture.height, texture.format), texture, size)

    def take_read_buffer(self, floats: int) -> gpu.types.Buffer:
        """A float buffer of ``floats`` values to read pixels back into: one a caller handed back
        (``keep_read_buffers``), else a new one. Reading 640x360 pixels into a new buffer took
        2.2 ms, into a kept one 0.35 ms: the new memory's pages are faulted in and zeroed as the
        driver writes them."""
        spare = self.take_spare(("read buffer", floats))
        if spare is not None:
            return spare[0]
        return gpu.types.Buffer("FLOAT", floats)

    def keep_read_buffers(self, images) -> None:
        """Keep the buffers under ``images`` (arrays ``Target.read`` returned) for the next reads
        of their size. The arrays must not be used afterwards: the next read overwrites them."""
        buffers = {}
        for image in images:
            owner = image  # its views' bases lead to a memoryview of the buffer
            while owner is not None and not isinstance(owner, gpu.types.Buffer):
                owner = owner.obj if isinstance(owner, memoryview) else getattr(owner, "base", None)
            if owner is not None:
                buffers[id(owner)] = owner  # once each, though two images share it
        for buffer in buffers.values():  # the first to go: a texture saves more per byte
            self.keep_spare(("read buffer", len(buffer)), buffer, 4 * len(buffer), first_out=True)

    def spare_bytes(self, kind: str | None = None) -> int:
        """Bytes of the textures kept (of ``kind`` alone: "shadow maps", "texture")."""
        with self._lock:
            return sum(entry[2] for entry in self._spares if kind is None or entry[0][0] == kind)

    def drop_spares(self) -> None:
        with self._lock:
            self._spares = []

    def program_count(self) -> int:
        return len(self._programs)

    def table_count(self) -> int:
        return len(self._tables)

    def held(self) -> list:
        """Every program and table the library holds (tests check that nothing else holds them)."""
        with self._lock:
            return [*self._programs.values(), *self._tables.values(), *self._environments.values(),
                    *(entry[1] for entry in self._spares), *(entry[1] for entry in self._images.values())]

    @property
    def compile_error(self) -> str:
        return self._compile_error

    def clear_compile_error(self) -> None:
        """Forget the last error and which programs failed: the next use compiles them again (a
        final render tries again; the viewport does not, redraw after redraw)."""
        with self._lock:
            self._compile_error = ""
            self._failed = {}

    def clear(self) -> None:
        """Forget every program and table; renderers still drawing keep theirs until they finish."""
        with self._lock:
            self._programs = {}
            self._failed = {}
            self._tables = {}
            self._environments = {}
            self._spares = []
            self._images = {}
        programs.clear_source_caches()


LIBRARY = _Library()


# --- the programs -----------------------------------------------------------------------------


def _depth_write(info) -> None:
    """The program writes gl_FragDepth. Blender 4.2 and 4.5 have no ``depth_write`` on a create
    info; their OpenGL programs write gl_FragDepth without the declaration."""
    if hasattr(info, "depth_write"):
        info.depth_write("ANY")


def layer_framebuffer(texture, layer: int):
    """A framebuffer whose depth attachment is one layer of a 2D-array depth texture. Blender 4.2
    and 4.5 read the slot's {"texture", "layer"} dict with its two values swapped ("'GPUTexture'
    object cannot be interpreted as an integer"; a (texture, layer) tuple binds every layer
    there): that reading is what the error says, so it gets the values it reads."""
    try:
        return gpu.types.GPUFrameBuffer(depth_slot={"texture": texture, "layer": layer})
    except TypeError:
        return gpu.types.GPUFrameBuffer(depth_slot={"texture": layer, "layer": texture})

def bind_sampler(shader, name: str, texture) -> None:
    """``shader.uniform_sampler(name, texture)``, unless the compiler removed the sampler (unused
    in this variant of the program): Blender binds a sampler it cannot find to texture unit -1,
    writing before the start of its own array of bound textures -- memory corruption that
    crashed Blender a few renders later (seen here with a Blinn-Phong program that declared the
    world's table it did not read)."""
    try:
        shader.uniform_from_name(name)
    except ValueError:
        return
    shader.uniform_sampler(name, texture)


#: The shading programs' interface (glsl/uniforms.glsl, mesh.vert.glsl): uniform blocks by
#: binding, push constants, vertex attributes by location, and what the vertex stage hands on.
_BLOCKS = (("FrameData", "frame"), None, ("MaterialData", "material"),  # 1: was the lights' block
           ("ObjectBlock", "objects"))
_PUSH_CONSTANTS = (("INT", "object_index"), ("VEC4", "lobes"))
def graph_push_constants(graph) -> tuple[str, ...]:
    """The per-draw vec4s a node graph's program reads (its object's texture space, colour and
    Object Info, its object, instancer and view-layer attributes), beside ``_PUSH_CONSTANTS``' 20
    bytes: at most 20 + 6 x 16 = 116 of 128."""
    names = ()
    if graph.uses & {"object", "generated"}:
        names += ("graph_texspace", "graph_texspace_size")
    if graph.uses & {"object_color", "object_info"}:
        names += ("graph_object_color", "graph_object_info")
    names += tuple(f"graph_uniform_attribute{k}" for k in range(graph.uniform_attributes))
    return names


#: The texture unit of a node graph's first image (``graph_image_0``; the programs' own end at 20).
GRAPH_IMAGE_SLOT = 21
_ATTRIBUTES = (("VEC3", "pos"), ("VEC3", "nor"), ("VEC2", "uv"), ("VEC4", "tangent"))
_VARYINGS = (("VEC3", "world_position"), ("VEC3", "world_normal"), ("VEC2", "world_uv"),
             ("VEC4", "world_tangent"))


#: The texture unit of the triangle texture of a graph reading the fragment's triangle (after its images').
GRAPH_TRIANGLE_SLOT = GRAPH_IMAGE_SLOT + programs.codegen.MAX_IMAGES


def _declare_graph_images(info, graph) -> None:
    """A node graph's samplers (``graph_image_<k>``): a 2D array where it holds a UDIM image's tiles;
    and the mesh's triangles (``graph_triangles``) where it reads the fragment's triangle."""
    for k in range(graph.images):
        kind = "FLOAT_2D_ARRAY" if k in graph.arrays else "FLOAT_2D"
        info.sampler(GRAPH_IMAGE_SLOT + k, kind, f"graph_image_{k}")
    if "triangle" in graph.uses:
        info.sampler(GRAPH_TRIANGLE_SLOT, "FLOAT_2D", "graph_triangles")


def _declare_shading(info, typedefs: str, features: programs.Features) -> None:
    info.typedef_source(typedefs)
    samplers = {0: "ms_table" if features.uses_albedo_table else None,
                1: "s_table" if features.uses_s_table else None,
                2: "sheen_table" if features.uses_sheen_table else None,
                3: "thin_film_table" if features.uses_thin_film_table else None}
    if features.peel:
        samplers.update({6: "opaque_depth", 7: "peel_depth"})
        # the layer's Holdout share (0 but for a graph's Holdout), where the pass keeps one
        info.fragment_out(1, "VEC4", "frag_holdout")
    if "TRANSMISSION" in features.lobes:  # what is behind the glass (passes.RefractionPass); a glass is
        # never shaded deferred (Features), so it takes the G-buffer's units
        samplers.update({17: "refraction_behind", 18: "refraction_back", 19: "refraction_back_depth"})
    if features.uses_subsurface_table:  # never shaded deferred either (Features): the G-buffer's last unit
        samplers[20] = "subsurface_table"
    samplers[8] = "env_atlas" if features.environment == "MAP" else None  # irradiance, levels
    samplers[9] = "split_table" if features.uses_split_table else None
    samplers[10] = "env_chain" if features.uses_env_chain else None
    samplers[11] = "env_chain_clamped" if features.uses_env_chain else None
    samplers[12] = "env_occlusion_map" if features.occlusion else None
    for slot, name in samplers.items():
        if name is not None:
            info.sampler(slot, "FLOAT_2D", name)
    if features.shadow_layers:
        info.sampler(13, "FLOAT_2D_ARRAY", "shadow_maps")
        info.uniform_buf(len(_BLOCKS) + 2, "ShadowBlock", "shadow")
    if features.light_block:
        info.uniform_buf(len(_BLOCKS) + 3, "LightBlock", "light_block")
    else:
        info.sampler(14, "FLOAT_2D", "light_data")
    if features.light_tiles:
        info.sampler(15, "FLOAT_2D", "light_tiles")
    if features.uses_ltc:
        info.sampler(16, "FLOAT_2D", "ltc_table")
    for binding, block in enumerate(_BLOCKS):
        if block is not None and not (features.deferred and block[1] in ("material", "objects")):
            info.uniform_buf(binding, *block)
    if features.environment:
        info.uniform_buf(len(_BLOCKS), "EnvironmentData", "env")
    if features.uses_env_chain:
        info.uniform_buf(len(_BLOCKS) + 1, "ChainData", "chain")
    if "TRANSMISSION" in features.lobes:
        info.uniform_buf(len(_BLOCKS) + 5, "RefractionData", "refraction")
    if features.graph is not None:  # the material's node graph: its constants, images, the object's data
        info.uniform_buf(len(_BLOCKS) + 4, "GraphBlock", "graph")
        _declare_graph_images(info, features.graph)
        for name in graph_push_constants(features.graph):
            info.push_constant("VEC4", name)
    if features.deferred:  # a full-screen pass over the G-buffer (glsl/gbuffer.frag.glsl)
        for slot, name in enumerate(("material_table", "gbuffer_position", "gbuffer_normal"), start=17):
            info.sampler(slot, "FLOAT_2D", name)
        if features.shadow_layers:
            info.sampler(20, "FLOAT_2D", "gbuffer_face")
        info.push_constant("INT", "deferred_group")
    for kind, name in _PUSH_CONSTANTS:
        if not (features.deferred and name == "object_index"):  # the G-buffer knew the object
            info.push_constant(kind, name)
    if features.deferred:
        info.vertex_in(0, "VEC2", "pos")  # post.vert.glsl's full-screen triangle
    else:
        _declare_mesh_stage(info, "shading_lab_iface", features.graph)


def _declare_mesh_stage(info, interface: str, graph=None) -> None:
    """mesh.vert.glsl's vertex attributes and what it hands the fragment stage; with a node
    graph, its attributes (``attr<k>``, the draw's second vertex buffer) and the object-space
    position where it reads one."""
    for location, (kind, name) in enumerate(_ATTRIBUTES):
        info.vertex_in(location, kind, name)
    iface = gpu.types.GPUStageInterfaceInfo(interface)
    for kind, name in _VARYINGS:
        iface.smooth(kind, name)
    if graph is not None:
        kinds = graph.attribute_kinds
        for k in range(graph.attributes):
            info.vertex_in(len(_ATTRIBUTES) + k, "VEC4", f"attr{k}")
            # an island's value is its triangles' (Cycles' face attribute, safe to hash): not interpolated
            flat = k < len(kinds) and kinds[k] == "RANDOM_PER_ISLAND"
            (iface.flat if flat else iface.smooth)("VEC4", f"graph_attribute{k}")
        if graph.uses & {"object", "generated"}:
            iface.smooth("VEC3", "object_position")
    info.vertex_out(iface)


def prepass_program(back_faces: bool = False, depth_only: bool = False) -> gpu.types.GPUShader:
    """Depth and world normals of opaque surfaces, their depth alone (``depth_only``: a target
    without colour), or the depth of the faces turned away (for the occlusion pass)."""
    src = programs.prepass_source(back_faces, depth_only)

    def declare(info):
        info.typedef_source(src.typedefs)
        info.uniform_buf(0, "FrameData", "frame")
        info.uniform_buf(3, "ObjectBlock", "objects")
        info.push_constant("INT", "object_index")
        _declare_mesh_stage(info, "shading_lab_prepass_iface")

    return LIBRARY.program(("prepass", back_faces, depth_only), "depth and normal", src, declare)


def gbuffer_program() -> gpu.types.GPUShader:
    """The G-buffer of the opaque surfaces shaded deferred: position and material row, the normal
    facing the viewer and the program's group, the flat face's normal."""
    src = programs.gbuffer_source()

    def declare(info):
        info.typedef_source(src.typedefs)
        info.uniform_buf(0, "FrameData", "frame")
        info.uniform_buf(3, "ObjectBlock", "objects")
        info.push_constant("INT", "object_index")
        info.push_constant("IVEC2", "gbuffer")  # the material's row, the group
        info.fragment_out(1, "VEC4", "gbuffer_normal")
        info.fragment_out(2, "VEC4", "gbuffer_face")
        _declare_mesh_stage(info, "shading_lab_gbuffer_iface")

    return LIBRARY.program(("gbuffer",), "G-buffer", src, declare)


def shadow_program(orthographic: bool = False) -> gpu.types.GPUShader:
    """A shadow map's layer: the casters' distances from the light (``orthographic``: a sun's
    layer, the rasteriser's depth)."""
    src = programs.shadow_source(orthographic)

    def declare(info):
        _declare_shadow_layer(info, src, orthographic)
        _declare_position_only(info, "shading_lab_shadow_iface")
        if not orthographic:
            _depth_write(info)

    return LIBRARY.program(("shadow", orthographic), "shadow map", src, declare)


def _declare_shadow_layer(info, src, orthographic: bool) -> None:
    """What every shadow-map program reads: the objects' block, the layer's projection (and a
    perspective layer's light position), the draw's object."""
    info.typedef_source(src.typedefs)
    info.uniform_buf(3, "ObjectBlock", "objects")
    info.push_constant("MAT4", "shadow_view_projection")
    if not orthographic:
        info.push_constant("VEC4", "light_origin")
    info.push_constant("INT", "object_index")


def _declare_position_only(info, interface: str) -> None:
    """A vertex stage that reads the position alone and hands on the world position."""
    info.vertex_in(0, "VEC3", "pos")
    iface = gpu.types.GPUStageInterfaceInfo(interface)
    iface.smooth("VEC3", "world_position")
    info.vertex_out(iface)


#: The node graph's frame fields (the view's matrices, its window): read from the frame block.
_FRAME_FIELDS = frozenset({"world_to_view", "view_to_world", "window", "clip_start", "ray_footprint",
                           "subpixels"})


def shadow_frame_fields() -> frozenset[str]:
    """The optional GraphInputs fields for which a coverage program reads the frame block."""
    return _FRAME_FIELDS


def shadow_coverage_program(graph, orthographic: bool, dither: bool) -> gpu.types.GPUShader:
    """A shadow map's layer for casters whose coverage is tested (``programs.shadow_coverage_source``):
    one per compiled graph's structure (``graph``, a ``GraphProgram``; None: the material's Alpha,
    a push constant), layer kind and rule."""
    src = programs.shadow_coverage_source(graph, orthographic, dither)

    def declare(info):
        _declare_shadow_layer(info, src, orthographic)
        if graph is None:
            info.push_constant("FLOAT", "shadow_alpha")
            _declare_position_only(info, "shading_lab_shadow_alpha_iface")
        else:
            if graph.uses & _FRAME_FIELDS:  # the frame's view when the maps are drawn
                info.uniform_buf(0, "FrameData", "frame")
            info.uniform_buf(len(_BLOCKS) + 4, "GraphBlock", "graph")
            _declare_graph_images(info, graph)
            for name in graph_push_constants(graph):
                info.push_constant("VEC4", name)
            _declare_mesh_stage(info, "shading_lab_shadow_graph_iface", graph)
        if not orthographic:
            _depth_write(info)

    key = ("shadow coverage", graph.key if graph is not None else None, orthographic, dither)
    return LIBRARY.program(key, "shadow map", src, declare)


def occlusion_depths_program() -> gpu.types.GPUShader:
    def declare(info):
        info.typedef_source(programs.read_glsl("chain_data.glsl"))
        _declare_full_screen("depth_map", "back_depth_map", "facing_map")(info)
        info.uniform_buf(0, "OcclusionData", "occlusion")

    return LIBRARY.program(("occlusion depths",), "ambient occlusion", programs.occlusion_depths_source(),
                           declare)


def gtao_program(scale: int = 1) -> gpu.types.GPUShader:
    def declare(info):
        info.typedef_source(programs.read_glsl("chain_data.glsl"))
        _declare_full_screen("depths", "normal_map")(info)
        info.uniform_buf(0, "OcclusionData", "occlusion")
        info.fragment_out(1, "VEC4", "cell_data")  # the traced pixel's normal and depth

    return LIBRARY.program(("gtao", scale), "ambient occlusion", programs.gtao_source(scale), declare)


def occlusion_resolve_program(scale: int = 1) -> gpu.types.GPUShader:
    def declare(info):
        info.typedef_source(programs.read_glsl("chain_data.glsl"))
        _declare_full_screen("raw", "traced_cells", "depths", "normal_map")(info)
        info.uniform_buf(0, "OcclusionData", "occlusion")

    return LIBRARY.program(("occlusion resolve", scale), "ambient occlusion",
                           programs.occlusion_resolve_source(scale), declare)


def shading_program(features: programs.Features) -> gpu.types.GPUShader:
    """The shading program for ``features``, compiled once and cached by its sorted defines."""
    src = programs.program_source(features)
    return LIBRARY.program(features.defines(), features.model, src,
                           lambda info: _declare_shading(info, src.typedefs, features))


def aov_program(graph, value: bool) -> gpu.types.GPUShader:
    """The program writing an AOV from a material's compiled AOV Output (``programs.aov_source``)."""
    def declare(info):
        info.typedef_source(programs.read_glsl("uniforms.glsl"))
        info.uniform_buf(0, "FrameData", "frame")
        info.uniform_buf(3, "ObjectBlock", "objects")
        info.uniform_buf(len(_BLOCKS) + 4, "GraphBlock", "graph")
        _declare_graph_images(info, graph)
        info.push_constant("INT", "object_index")
        for name in graph_push_constants(graph):
            info.push_constant("VEC4", name)
        _declare_mesh_stage(info, "shading_lab_aov_iface", graph)

    return LIBRARY.program(("aov", graph.key, value), "AOV", programs.aov_source(graph, value), declare)


def _declare_full_screen(*samplers: str, floats: tuple[str, ...] = ()):
    def declare(info) -> None:
        info.vertex_in(0, "VEC2", "pos")
        for slot, name in enumerate(samplers):
            info.sampler(slot, "FLOAT_2D", name)
        for name in floats:
            info.push_constant("FLOAT", name)
    return declare


def post_program(features: programs.PostFeatures) -> gpu.types.GPUShader:
    """The resolve/display pass for ``features``."""
    return LIBRARY.program(("post",) + features.defines(), "display", programs.post_source(features),
                           _declare_full_screen("hdr_image", floats=("exposure_scale",)))


def exposure_program(stage: str) -> gpu.types.GPUShader:
    """A stage of automatic exposure's reduction (programs.EXPOSURE_STAGES)."""
    return LIBRARY.program(("exposure", stage), "exposure", programs.exposure_source(stage),
                           _declare_full_screen("source", floats=("block",)))


def compare_program(features: programs.CompareFeatures) -> gpu.types.GPUShader:
    return LIBRARY.program(("compare",) + features.defines(), "compare", programs.compare_source(features),
                           _declare_full_screen("image_a", "image_b", floats=("split", "range")))


def background_program(features: programs.BackgroundFeatures) -> gpu.types.GPUShader:
    def declare(info):
        info.typedef_source(programs.read_glsl("world_data.glsl"))
        _declare_full_screen(*(f"env_image_{i}" for i in range(features.images)))(info)
        info.uniform_buf(0, "WorldData", "world")
        info.push_constant("MAT4", "inverse_view_projection")
        info.push_constant("VEC4", "viewport")

    return LIBRARY.program(("background",) + features.defines(), "background",
                           programs.background_source(features), declare)


def env_bake_program(images: int, poles: bool = False) -> gpu.types.GPUShader:
    """Bake the world's lighting field into a level of the chain; or (``poles``) the means of its
    edge rows, which the bake's border rows read."""
    def declare(info):
        info.typedef_source(programs.read_glsl("world_data.glsl"))
        _declare_full_screen(*(f"env_image_{i}" for i in range(images)), *(() if poles else ("poles",)))(info)
        info.uniform_buf(0, "WorldData", "world")
        info.push_constant("VEC4", "rect")
        info.push_constant("VEC4", "params")

    return LIBRARY.program(("env_bake", images, poles), "environment bake",
                           programs.env_bake_source(images, poles), declare)


def env_downsample_program(copy: bool = False) -> gpu.types.GPUShader:
    """Halve an equirectangular level (in rectangle ``offset`` of its texture); or (``copy``) copy
    one into a rectangle (``offset``)."""
    def declare(info):
        _declare_full_screen("source")(info)
        info.push_constant("VEC4", "offset")

    return LIBRARY.program(("env_downsample", copy), "environment downsample",
                           programs.env_downsample_source(copy), declare)


def env_prefilter_program() -> gpu.types.GPUShader:
    def declare(info):
        info.typedef_source(programs.read_glsl("chain_data.glsl"))
        _declare_full_screen("source", "samples")(info)
        info.uniform_buf(0, "ChainData", "chain")
        info.push_constant("VEC4", "rect")
        info.push_constant("VEC4", "params")

    return LIBRARY.program(("env_prefilter",), "environment prefilter", programs.env_prefilter_source(),
                           declare)


def prefilter_samples(alpha: float, samples: int, height: int, chain_width: int,
                      bias: float) -> gpu.types.GPUTexture:
    """One prefiltered level's lobe samples per row as the reads of the chain they make
    (``environment.prefilter_reads``), an RGBA32F texture, two texels a sample (built once per
    level size: every world shares it)."""
    def build():
        rows = env.prefilter_samples(alpha, samples, height, chain_width, bias)
        return rgba32f_texture(env.prefilter_reads(rows, chain_width))

    return LIBRARY.table(("PREFILTER", alpha, samples, height, chain_width, bias), build)


def env_irradiance_program() -> gpu.types.GPUShader:
    def declare(info):
        info.typedef_source(programs.read_glsl("chain_data.glsl"))
        _declare_full_screen("source")(info)
        info.uniform_buf(0, "ChainData", "chain")
        info.push_constant("VEC4", "rect")
        info.push_constant("VEC4", "params")

    return LIBRARY.program(("env_irradiance",), "irradiance map", programs.env_irradiance_source(), declare)


def split_table(terms) -> gpu.types.GPUTexture:
    """E(mu, r) and B(mu, r) of ``terms``' D and V (RGBA32F, E in red, B in green): the split
    sum's second factor (the Principled set: GGX with Smith)."""
    from ..reference import multiscatter

    ndf, visibility = terms.lobe

    def build():
        return rgba32f_texture(multiscatter.split_sum_table(ndf, visibility))

    return LIBRARY.table(("SPLIT", ndf, visibility), build)


def refraction_copy_program(stage: str) -> gpu.types.GPUShader:
    """A stage of the copy of what is behind the glass (programs.REFRACTION_COPY_STAGES)."""
    samplers = ("source", "source_depth") if stage == "COPY" else ("source",)

    def declare(info):
        _declare_full_screen(*samplers)(info)
        if stage == "PACK":
            info.push_constant("VEC4", "offset")

    return LIBRARY.program(("refraction", stage), "refraction copy", programs.refraction_copy_source(stage),
                           declare)


def occupancy_program() -> gpu.types.GPUShader:
    src = programs.occupancy_source()
    return LIBRARY.program(("occupancy",) + src.defines, "occupancy", src,
                           _declare_full_screen("layer_depth"))


def group_depth_program() -> gpu.types.GPUShader:
    """Each pixel's deferred group as a depth (glsl/group_depth.frag.glsl)."""
    def declare(info):
        _declare_full_screen("gbuffer_normal")(info)
        _depth_write(info)

    return LIBRARY.program(("group depth",), "deferred groups' depth", programs.group_depth_source(), declare)


def under_program(holdout: bool = False) -> gpu.types.GPUShader:
    """The transparency composite's step (glsl/under.frag.glsl); ``holdout``: the layers' Holdout
    share too, read and written as a second colour."""
    variant = "UNDER_HOLDOUT" if holdout else "UNDER"
    samplers = ("accumulated", "peeled") + (("accumulated_holdout", "peeled_holdout") if holdout else ())

    def declare(info):
        _declare_full_screen(*samplers)(info)
        if holdout:
            info.fragment_out(1, "VEC4", "frag_holdout")

    return LIBRARY.program(("under", variant), "transparency composite", programs.under_source(variant),
                           declare)


# --- the tables -------------------------------------------------------------------------------

def rgba32f_texture(table: np.ndarray) -> gpu.types.GPUTexture:
    """An RGBA32F texture of ``table`` (h, w, 4), bottom row first."""
    h, w = table.shape[:2]
    data = gpu.types.Buffer("FLOAT", w * h * 4, np.ascontiguousarray(table, np.float32).ravel())
    return gpu.types.GPUTexture((w, h), format="RGBA32F", data=data)


def r32f_texture(table: np.ndarray) -> gpu.types.GPUTexture:
    h, w = table.shape
    data = gpu.types.Buffer("FLOAT", w * h, np.ascontiguousarray(table, np.float32).ravel())
    return gpu.types.GPUTexture((w, h), format="R32F", data=data)


def albedo_table(terms, glossy: bool = False) -> gpu.types.GPUTexture:
    """The directional-albedo table of ``terms``' D and V as an R32F texture (built once); for the
    Principled set, GGX + Smith's table; with Eavg(r) (GGX + Smith's) as an extra row where the
    layering estimate reads it (the Principled set, the LAYERED diffuse); ``glossy`` (a program
    drawing the Glossy BSDFs' lobe, SL_GLOSSY: always layered) adds, after that row, the albedo
    tables of Beckmann + Smith and of Ashikhmin-Shirley (glsl/closures.glsl's glossy_albedo)."""
    from ..reference import closures, multiscatter

    ndf, visibility = terms.lobe
    glossy = glossy and terms.layered

    def build():
        table = multiscatter.albedo_table(ndf, visibility)
        if terms.layered:
            table = np.vstack([table, multiscatter.average_albedo()[None, :]])
        if glossy:
            table = np.vstack([table, multiscatter.albedo_table("BECKMANN", "SMITH_CORRELATED"),
                               closures.ashikhmin_shirley_albedo_table(table.shape[1])])
        return r32f_texture(table)

    key = (ndf, visibility, "EAVG" if terms.layered else "", "GLOSSY" if glossy else "")
    return LIBRARY.table(key, build)


def ltc_table(terms) -> gpu.types.GPUTexture:
    """Area lights' linearly transformed cosines for ``terms``' distribution (the Principled set:
    GGX) with the horizon-clipping sphere table below them, as one RGBA32F texture
    (glsl/ltc.glsl)."""
    from ..reference import ltc

    ndf = terms.lobe[0]

    def build():
        table = ltc.ltc_table(ndf)
        sphere = ltc.sphere_table()
        rows = np.zeros((sphere.shape[0], table.shape[1], 4), np.float32)
        rows[:, :sphere.shape[1], 0] = sphere
        return rgba32f_texture(np.concatenate([table, rows]))

    return LIBRARY.table(("LTC", ndf), build)


def s_table() -> gpu.types.GPUTexture:
    """The Principled set's S(r, mu, z) table as a 16 x 1312 R32F atlas (rows: mu + 16 z), and after
    it rough glass's albedo tables (addon/reference/transmission.py's glass_albedo_tables, the
    roughness along x): E entering glass at rows 256 + mu + 16 z, leaving it at 512 + mu + 16 z, their
    averages at rows 768 + z and 784 + z, the transmitted part T at rows 800 + mu + 16 z and
    1056 + mu + 16 z (glsl/transmission.glsl's glass_albedo, glass_transmitted)."""
    from ..reference import multiscatter, transmission

    def build():
        table = multiscatter.principled_s_table()
        n = table.shape[0]
        glass = transmission.glass_albedo_tables()
        if glass["E"].shape[0] != n:
            raise ValueError(f"the glass tables' side {glass['E'].shape[0]} is not the S table's {n}")
        names = ("E", "E_inv", "Eavg", "Eavg_inv", "T", "T_inv")
        rows = [table.reshape(n * n, n)] + [glass[name].reshape(-1, n) for name in names]
        return r32f_texture(np.concatenate(rows))

    return LIBRARY.table(("S",), build)

def sheen_table() -> gpu.types.GPUTexture:
    """The Principled BSDF's sheen LTC table (addon/reference/sheen.py) as an RGBA32F texture: texel
    (n.v index, roughness index) = (a, b, albedo, 0) (glsl/principled.glsl's sheen_lookup)."""
    from ..reference import sheen

    def build():
        table = sheen.table()
        return rgba32f_texture(np.concatenate([table, np.zeros(table.shape[:2] + (1,), np.float32)], axis=-1))

    return LIBRARY.table(("SHEEN",), build)


def thin_film_table() -> gpu.types.GPUTexture:
    """The Thin Film's sensitivity (addon/reference/thin_film.py's sensitivity_table in Blender 5.0's
    scene linear Rec. 709, materials/convert.py's XYZ_TO_RGB) as a 512 x 2 RGBA32F texture: row 0 its
    real part, row 1 its imaginary part (glsl/thin_film.glsl's thin_film_sensitivity)."""
    from ..materials import convert
    from ..reference import thin_film

    def build():
        table = thin_film.sensitivity_table(convert.XYZ_TO_RGB).transpose(1, 0, 2)
        return rgba32f_texture(np.concatenate([table, np.zeros(table.shape[:2] + (1,), np.float32)], axis=-1))

    return LIBRARY.table(("THIN_FILM",), build)

def subsurface_table() -> gpu.types.GPUTexture:
    """The subsurface's random walk tables (addon/reference/subsurface.py's walk_table,
    walk_drift_table, walk_gain_table) as an RGBA32F texture: per albedo node i and Anisotropy node j,
    texels (6 i, j) and (6 i + 1, j) R / albedo at entry nodes 0-3 and 4-7, (6 i + 2, j) and
    (6 i + 3, j) the drift's moments at nodes 0-6 and a 0, (6 i + 4, j) and (6 i + 5, j) the convex
    gain at nodes 0-7 (glsl/subsurface.glsl's subsurface_walk_node)."""
    from ..reference import subsurface

    def build():
        reflectance = subsurface.walk_table()  # (albedo, g, 8)
        drift = subsurface.walk_drift_table()  # (albedo, g, 7)
        gain = subsurface.walk_gain_table()  # (albedo, g, 8)
        pad = np.zeros(drift.shape[:2] + (1,), np.float32)
        table = np.concatenate([reflectance, drift, pad, gain], axis=-1)
        texels = table.transpose(1, 0, 2).reshape(table.shape[1], 6 * table.shape[0], 4)
        return rgba32f_texture(np.ascontiguousarray(texels))

    return LIBRARY.table(("SUBSURFACE",), build)

# Compiled programs outlive renders; free them before Blender tears its GPU module down, or it
# reports them as leaked blocks at exit.
atexit.register(LIBRARY.clear)


#: What an image a node graph samples gives where its pixels could not be read: Blender's and
#: Cycles' colour of a missing image.
MISSING_IMAGE = (1.0, 0.0, 1.0, 1.0)


def missing_texture() -> gpu.types.GPUTexture:
    """A 1 x 1 texture of ``MISSING_IMAGE`` (built once)."""
    return LIBRARY.table(("missing image",), lambda: rgba32f_texture(np.array([[MISSING_IMAGE]], np.float32)))


def missing_array_texture() -> gpu.types.GPUTexture:
    """A 1 x 1 x 1 2D array of ``MISSING_IMAGE``: a UDIM image of no readable tile (built once)."""
    def build():
        data = gpu.types.Buffer("FLOAT", 4, np.array(MISSING_IMAGE, np.float32))
        return gpu.types.GPUTexture((1, 1), layers=1, format="RGBA32F", data=data)

    return LIBRARY.table(("missing image array",), build)
