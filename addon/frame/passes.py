"""The passes a frame is made of, and what they share.

A frame is a list of steps, each a pass and its input, run in order (``Renderer.run``):

    per frame: EnvironmentPass (the world's light), ShadowPass (the lights' shadow maps)
    per view:  OcclusionPass ─► OpaquePass ─► BackgroundPass ─► RefractionPass ─► TransparencyPass
               ─► ResolvePass ─► ExposurePass ─► DisplayPass
    then:      ComparePass (A|B: two views composited)

Lifetimes:
- per scene (``SceneResources``, in ``gpu_scene``): geometry, uniform blocks, textures;
- per frame (``Frame``): the snapshot being drawn, cancellation, and the named outputs passes
  hand on (``"main.scene"``, ``"main.radiance"``, ``"main.display"``, ``"compare"``);
- per pass: its own render targets, kept while their size and format stay the same (the
  viewport redraws into the same ones), freed with the renderer.

A pass with nothing to do does nothing: no transparency layers without transparent surfaces, no
copy of the scene without transmitting ones, no
resolve without supersampling, no metering under manual exposure, no display pass under
Blender's view transform (unless automatic exposure scales Combined), no shadow maps without a
light that casts. The per-frame passes run ahead of the views, reading the same
``Frame``.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import gpu
import numpy as np

from ..plan import light_tiles, programs, shadows
from ..scene import exposure
from ..scene.matrices import invert
from ..scene.snapshot import MAX_ENVIRONMENT_IMAGES, Snapshot, World
from . import gpu_library
from .gpu_scene import Draw, SceneResources


def new_texture(width: int, height: int, format: str) -> gpu.types.GPUTexture:
    """A 2D texture for a target: one a finished renderer handed back (``Renderer.free``), else a
    new one. Its content is undefined either way: every target is drawn (or cleared) before it
    is read."""
    texture = gpu_library.LIBRARY.take_texture(width, height, format)
    return texture if texture is not None else gpu.types.GPUTexture((width, height), format=format)


class Target:
    """A float colour texture and (unless ``depth`` is False) a depth texture drawn into
    together, both readable by shaders (depth peeling samples the opaque depth)."""

    def __init__(self, width: int, height: int, format: str = "RGBA32F", depth: bool = True,
                 depth_texture: gpu.types.GPUTexture | None = None, colors: int = 1):
        """``depth_texture``: another target's depth (of this size) to draw against instead of a
        depth texture of its own; ``colors``: colour textures drawn into at once (a program's
        outputs 0, 1, ...: ``texture_color`` and then ``more_colors``), or 0: the depth alone
        (nothing to write but depth: on the CPU rasteriser ~3x faster than a colour beside it)."""
        self.width, self.height, self.format, self.depth = width, height, format, depth
        self.colors = colors
        self.texture_color = new_texture(width, height, format) if colors else None
        self.more_colors = tuple(new_texture(width, height, format) for _ in range(colors - 1))
        self.shares_depth = depth and depth_texture is not None
        if depth and depth_texture is None:
            depth_texture = new_texture(width, height, "DEPTH_COMPONENT32F")
        self.texture_depth = depth_texture if depth else None
        slots = (self.texture_color, *self.more_colors) if self.more_colors else self.texture_color
        if not colors:
            self.framebuffer = gpu.types.GPUFrameBuffer(depth_slot=self.texture_depth)
        elif depth:
            self.framebuffer = gpu.types.GPUFrameBuffer(color_slots=slots, depth_slot=self.texture_depth)
        else:
            self.framebuffer = gpu.types.GPUFrameBuffer(color_slots=slots)

    def bind(self):
        return self.framebuffer.bind()

    def fits(self, width: int, height: int, format: str, depth: bool, colors: int = 1) -> bool:
        return (self.width, self.height, self.format, self.depth, self.colors) == \
            (width, height, format, depth, colors)

    def clear(self, color=(0.0, 0.0, 0.0, 0.0), depth: float | None = None) -> None:
        """Clear the bound target: its colours to ``color`` (where it has any) and, if given,
        its depth."""
        if self.colors and depth is not None:
            self.framebuffer.clear(color=color, depth=depth)
        elif self.colors:
            self.framebuffer.clear(color=color)
        elif depth is not None:
            self.framebuffer.clear(depth=depth)

    def read(self, region: tuple[int, int, int, int] | None = None) -> np.ndarray:
        """(height, width, 4) float32, bottom row first, of the whole texture or of ``region``
        (x, y, width, height): a view of the buffer the texels were read into (main memory, kept
        alive by the array), not a copy of it (a 1280 x 720 copy took 3-30 ms, most of it the
        fresh memory's first touch); a buffer a final render handed back once Blender had the
        pixels (``gpu_library.LIBRARY.keep_read_buffers``) where one of this size is kept."""
        x, y, w, h = (0, 0, self.width, self.height) if region is None else region
        buffer = gpu_library.LIBRARY.take_read_buffer(w * h * 4)
        with self.bind():
            self.framebuffer.read_color(x, y, w, h, 4, 0, "FLOAT", data=buffer)
        return np.frombuffer(buffer, np.float32).reshape(h, w, 4)

    def fence(self) -> None:
        """Wait until everything drawn into the target is done (one texel read back)."""
        with self.bind():
            if self.colors:
                self.framebuffer.read_color(0, 0, 1, 1, 4, 0, "FLOAT")
            else:
                self.framebuffer.read_depth(0, 0, 1, 1)

    def owned(self) -> list:
        """The textures this target made (not a depth it shares)."""
        if self.framebuffer is None:
            return []
        colors = [self.texture_color, *self.more_colors] if self.colors else []
        return colors + ([self.texture_depth] if self.depth and not self.shares_depth else [])

    def free(self) -> None:
        """Drop the textures and framebuffer (Blender frees them with their last reference)."""
        self.framebuffer = self.texture_color = self.texture_depth = None
        self.more_colors = ()


def _fitted(target: Target | None, width: int, height: int, format: str = "RGBA32F",
            depth: bool = False, colors: int = 1) -> Target:
    """``target`` if it has this size and format, else a new one (the old one freed)."""
    if target is not None and target.fits(width, height, format, depth, colors):
        return target
    if target is not None:
        target.free()
    return Target(width, height, format, depth, colors=colors)


@dataclass(frozen=True)
class View:
    """One image of a frame and how it is drawn. ``name`` picks the passes (and their targets)
    that draw it: views drawn one after the other may share a name; views needed together (A
    and B of a comparison) may not."""

    width: int
    height: int
    name: str = "main"
    model: str | None = None  # None: the scene's; a material's own model wins either way
    samples: int = 1  # supersampling grid per axis
    background: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    lobes: tuple[float, float, float, float] = programs.ALL_LOBES
    half_target: bool = False  # RGBA16F targets (the viewport)
    display: programs.PostFeatures | None = None  # also tone map (an engine tone mapper)
    exposure: float = 0.0  # stops (manual)
    auto_exposure: exposure.AutoExposure | None = None  # metered by ExposurePass instead
    view_projection: np.ndarray | None = field(default=None, compare=False)  # None: the camera's
    # the radiance in a target of its own, written only once the frame is complete (the viewport
    # shows it: a frame that fails half-way leaves the last good image there)
    own_radiance: bool = False

    @property
    def format(self) -> str:
        return "RGBA16F" if self.half_target else "RGBA32F"

    def output(self, kind: str) -> str:
        return f"{self.name}.{kind}"


@dataclass(frozen=True)
class Comparison:
    """The A|B composite of two views' images: a split view or a difference heat map."""

    a: str  # output names
    b: str
    width: int
    height: int
    features: programs.CompareFeatures
    split: float = 0.5
    value_range: float = 1.0
    half_target: bool = False


@dataclass
class Frame:
    """What the passes of one frame share."""

    snapshot: Snapshot
    scene: SceneResources
    full_screen: gpu.types.GPUBatch
    should_stop: Callable[[], bool] | None = None
    outputs: dict[str, Target] = field(default_factory=dict)
    cancelled: bool = False  # should_stop() said so: no more geometry is drawn
    peeled_layers: int = 0  # transparency layers the last view blended
    # automatic exposure: (view, metered stops) -> the stops to use (eye adaptation between
    # frames); None: the metered value
    adapt: Callable[[View, float], float] | None = None
    exposures: dict[str, tuple[float, float]] = field(default_factory=dict)  # view -> (stops, metered)
    # view output -> the G-buffer the occlusion pass drew for it ahead of the opaque pass
    gbuffers: dict[str, GBuffer] = field(default_factory=dict)
    # view name -> the faces culled per opaque draw (``view_culling``), worked out once a frame
    cullings: dict[str, Callable[[Draw], str] | None] = field(default_factory=dict)

    def view_projection(self, view: View):
        """The view's world -> clip matrix: its own, else the camera's."""
        return self.snapshot.camera.view_projection if view.view_projection is None else view.view_projection

    def exposure(self, view: View) -> float:
        """The view's exposure in stops: metered (and adapted) when automatic, else its own."""
        return self.exposures[view.name][0] if view.name in self.exposures else view.exposure

    def draw_full_screen(self, shader, bind: Callable[[gpu.types.GPUShader], None], target: Target,
                         clear: bool = True) -> None:
        """Draw ``shader`` over all of ``target`` (``bind`` sets its inputs)."""
        with target.bind():
            if clear:
                target.framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0))
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set("NONE")
            shader.bind()
            bind(shader)
            self.full_screen.draw(shader)


_FULL_SCREEN = ((-1.0, -1.0), (3.0, -1.0), (-1.0, 3.0))


def full_screen_batch() -> gpu.types.GPUBatch:
    """A triangle covering clip space: every full-screen pass of a renderer draws this one."""
    fmt = gpu.types.GPUVertFormat()
    fmt.attr_add(id="pos", comp_type="F32", len=2, fetch_mode="FLOAT")
    vbo = gpu.types.GPUVertBuf(fmt, 3)
    vbo.attr_fill("pos", _FULL_SCREEN)
    return gpu.types.GPUBatch(type="TRIS", buf=vbo)


class Pass:
    """A step of a frame. ``run`` returns False when the frame was cancelled; a cancelled frame
    skips the passes that draw geometry and still runs those that make images of it."""

    draws_geometry = False

    def run(self, frame: Frame, spec) -> bool:
        raise NotImplementedError

    def free(self) -> None:
        """Drop the pass's own GPU objects."""

    def textures(self) -> list:
        """The 2D textures the pass made for its targets (``Renderer.free`` hands them back)."""
        return []


class TargetPass(Pass):
    """A pass drawing into one target of its own, kept while its size and format hold."""

    def __init__(self):
        self.target: Target | None = None

    def fit(self, width: int, height: int, format: str, depth: bool = False) -> Target:
        self.target = _fitted(self.target, width, height, format, depth)
        return self.target

    def free(self) -> None:
        if self.target is not None:
            self.target.free()
            self.target = None

    def textures(self) -> list:
        return self.target.owned() if self.target is not None else []


#: Draw only the light-facing faces of closed casters into the shadow maps (the same depths as
#: every face; tests turn it off to compare).
CULL_CLOSED_CASTERS = True
#: Leave out of a layer the flat casters that can shadow nothing in it (a ground under the scene
#: and its light: ``shadows.shadowless_casters``; tests turn it off to compare).
SKIP_SHADOWLESS = True
#: Leave out of a layer the casters whose shadow falls where no view of the frame looks
#: (``shadows.receiving_casters``: the same image; tests turn it off to compare).
VIEW_CULLED_CASTERS = True
#: Leave out of a sun's coarser cascades the casters its finer ones hold for every lookup that
#: could read them (``shadows.finer_cascades_hold``: the same image; tests turn it off to compare).
CASCADE_CULLED_CASTERS = True
#: How a partly covering caster (``SceneResources.covering``: a material's Alpha under 1, a node
#: graph's coverage) shadows (glsl/shadow_coverage.glsl): "DITHER" a share of its map's texels per
#: coverage (4 x 4 ordered dither, which the receivers' filter averages towards Cycles' partial
#: shadow), "THRESHOLD" where its coverage is 1/2 or more, None not at all (tests compare them).
PARTIAL_COVERAGE = "DITHER"
#: The faces culled for a caster's facing (``SceneResources.caster_facing``): open, out, in.
CULLING = {0: "NONE", 1: "BACK", -1: "FRONT"}
#: Cull the faces of closed surfaces that a view sees wholly from outside where they turn away
#: from it: each is hidden behind a nearer face of its own (``SceneResources.view_facing``; the
#: prepass, the G-buffer and forward shading; tests turn it off to compare).
CULL_CLOSED_SURFACES = True


def view_culling(frame: Frame, view: View, opaque) -> Callable[[Draw], str] | None:
    """The faces culled per draw of ``opaque`` ((features, draws) groups: all of the view's
    opaque surfaces) as ``view`` sees them, or None where none is."""
    if not CULL_CLOSED_SURFACES:
        return None
    if view.name in frame.cullings:
        return frame.cullings[view.name]
    frame.cullings[view.name] = None
    draws = [draw for _features, group in opaque for draw in group]
    facing = frame.scene.view_facing(draws, frame.view_projection(view))
    if not facing.any():
        return None
    modes = {id(draw): CULLING[int(f)] for draw, f in zip(draws, facing)}
    frame.cullings[view.name] = culling = lambda draw: modes.get(id(draw), "NONE")  # noqa: E731
    return culling


class ShadowPass(Pass):
    """The frame's shadow maps (``gpu_scene.SceneResources.shadow_plan``): one layer of a 2D-array
    depth texture per map, each holding the casters' distances from its light
    (glsl/shadow.frag.glsl). A layer holds the casters that reach its volume and whose shadow can
    fall where the frame's views look (``VIEW_CULLED_CASTERS``: a caster behind the camera, whose
    shadow falls behind it too, is left out). Drawn again only when the plan (lights, map size,
    the scene's bounds) or a caster (its matrix or geometry) changed, or when a view looks where a
    layer lacks a caster (drawn then with the casters it held as well: a camera orbiting a still
    scene re-renders a layer at most until it holds every caster that reaches it); a material
    edit re-renders nothing unless it changes how surfaces cast (a slot made partly transparent
    casts by its coverage, ``PARTIAL_COVERAGE``: an edit of a partly covering caster's graph or
    Alpha draws the maps again, ``SceneResources.coverage_key``). With Persistent Data
    (``Settings.persistent_data``, final renders) a final render that takes the last one's
    texture keeps its maps where they hold the same content
    (``SceneResources.shadow_content_key``) and every caster its views need: re-rendering a still
    scene, or one where only materials change, draws no map. Sets ``SceneResources.shadow_maps``;
    nothing when no light casts. ``views``: the frame's views (None: every caster that reaches a
    layer)."""

    draws_geometry = True

    def __init__(self):
        self.texture = None
        self.framebuffers: list = []
        self.key = None
        self._shape = None
        self.renders = 0  # layers drawn since the pass was made (tests count them)
        self.drawn_casters = 0  # (layer, caster) pairs the last drawing of the maps drew
        self.cleared = 0  # layers the last drawing of the maps cleared
        self.far: set[int] = set()  # layers that hold "nothing" alone: cleared, nothing drawn since
        #: the maps' content key (SceneResources.shadow_content_key) once every layer is drawn with
        #: Persistent Data on; None: not known
        self.content: bytes | None = None
        self.kept = 0  # renders that kept the maps a finished renderer left (Persistent Data)
        #: (layers, casters): which casters each layer holds, where ``key`` (or ``content``) says
        #: what they are; None: not known
        self.held: np.ndarray | None = None
        self._held_casters: tuple | None = None  # held's columns: (item, material) per caster
        self._casters = None  # ((key, the casters), the casters' spheres, which reach each layer)
        #: the coverage programs the maps were drawn with, (graph key or None, orthographic)
        self.coverage_programs: set = set()

    def _reach(self, frame: Frame, key) -> tuple[list, np.ndarray, np.ndarray, tuple]:
        """The casters, their spheres and which of them reach each layer (shadows.layer_casters,
        less the flat casters that can shadow nothing there and the casters a sun's finer cascade
        holds for every lookup that could read them); the last two worked out once per
        ``key`` and casters (a viewport redrawing a still scene does not again); last, the casters
        by item and material (what ``held``'s columns are)."""
        scene = frame.scene
        casters = scene.shadow_casters(covering=PARTIAL_COVERAGE is not None)
        which = (key, tuple((draw.order, draw.material) for draw in casters))
        if self._casters is None or self._casters[0] != which:
            spheres = scene.caster_spheres(casters)
            reach = shadows.layer_casters(scene.shadow_plan.matrices, spheres)
            if SKIP_SHADOWLESS:
                reach &= ~scene.shadowless_casters(casters)
            if CASCADE_CULLED_CASTERS:
                reach &= ~shadows.finer_cascades_hold(scene.shadow_plan, spheres)
            self._casters = (which, spheres, reach)
        return casters, self._casters[1], self._casters[2], which[1]

    def run(self, frame: Frame, views: list[View] | None = None) -> bool:
        scene = frame.scene
        plan = scene.shadow_plan
        if plan is None or plan.layers == 0:
            self.free()
            scene.shadow_maps = None
            return True
        # the lights' extents decide which flat casters a layer leaves out (shadowless_casters)
        extents = tuple(shadows.light_extent(light) for light in frame.snapshot.lights)
        # partly covering casters: their coverage (graphs' constants, images, Alphas) and the rule
        coverage = (PARTIAL_COVERAGE, scene.coverage_key(scene.shadow_casters())
                    if PARTIAL_COVERAGE is not None else b"")
        key = (plan.key(), scene.caster_key, extents, coverage)
        shape = (plan.size, plan.layers)
        if self.texture is None or self._shape != shape:
            self.free()
            spare = gpu_library.LIBRARY.take_spare(("shadow maps", shape))
            if spare is not None:
                self.texture, (far, self.content, self.held, self._held_casters) = spare
                self.far = set(far)
            else:
                self.texture = gpu.types.GPUTexture((plan.size, plan.size), layers=plan.layers,
                                                    format="DEPTH_COMPONENT32F")
                self.far = set()
                self.content = self.held = self._held_casters = None
            self._shape = shape
            self.framebuffers = [gpu_library.layer_framebuffer(self.texture, i) for i in range(plan.layers)]
        scene.shadow_maps = self.texture
        casters, spheres, reach, which = self._reach(frame, key)
        needed = reach
        if VIEW_CULLED_CASTERS and views and plan.box is not None:
            regions = [shadows.visible_region(frame.view_projection(view), *plan.box) for view in views]
            needed = reach & shadows.receiving_casters(plan.matrices, plan.size, spheres, regions)
        same = key == self.key
        content = self.content if same else None
        if not same and frame.snapshot.settings.persistent_data:
            drawing = (SKIP_SHADOWLESS, CULL_CLOSED_CASTERS, extents, coverage)
            content = scene.shadow_content_key(casters, drawing)
            same = content == self.content  # the maps the last final render of this content drew
        held = self.held if same and self.held is not None and self._held_casters == which else None
        if held is not None:
            redraw = (needed & ~held).any(axis=1)  # layers lacking a caster a view needs
            if not redraw.any():
                if self.key != key:
                    self.kept += 1
                self.key = key
                return True
            want = needed | held
        else:
            redraw = np.ones(plan.layers, bool)
            want = needed
            held = np.zeros_like(want)
        self.key = None  # until every layer is drawn
        self.held = None
        self.drawn_casters = int(want[redraw].sum())
        self.cleared = 0
        facing = scene.caster_facing(casters) if CULL_CLOSED_CASTERS else np.zeros(len(casters), np.int8)
        covers = [scene.covering(draw) for draw in casters]
        for layer, framebuffer in enumerate(self.framebuffers):
            if not redraw[layer]:
                continue
            if frame.should_stop is not None and frame.should_stop():
                return False
            held[layer] = want[layer]
            if not want[layer].any():
                # a layer no caster reaches holds "nothing": cleared unless it already does (a
                # cube face turned away from every caster; clearing a 1024^2 layer costs ~0.5 ms)
                if layer not in self.far or not SKIP_FAR_LAYERS:
                    with framebuffer.bind():
                        framebuffer.clear(depth=1.0)
                    self.cleared += 1
                    self.far.add(layer)
                continue
            self.far.discard(layer)
            origin = plan.origins[layer]
            orthographic = origin[3] == shadows.KIND_ORTHOGRAPHIC
            inverse_far = 0.0 if orthographic else 1.0 / float(plan.info[layer][0])
            layer_facing = facing
            if not orthographic and facing.any():  # a light inside a closed caster (a bulb) sees
                # its inside: every face drawn (the near plane, <= 1e-4 far + 1 mm, counted in)
                margin = 1e-4 * float(plan.info[layer][0]) + 1e-3
                around = np.linalg.norm(spheres[:, :3] - origin[:3], axis=1) <= spheres[:, 3] + margin
                layer_facing = np.where(around, 0, facing)
            shader = gpu_library.shadow_program(orthographic)
            light_origin = (*(float(x) for x in origin[:3]), inverse_far)
            with framebuffer.bind():
                framebuffer.clear(depth=1.0)
                self.cleared += 1
                gpu.state.depth_test_set("LESS")
                gpu.state.depth_mask_set(True)
                gpu.state.face_culling_set("NONE")
                gpu.state.blend_set("NONE")
                try:
                    shader.bind()
                    shader.uniform_float("shadow_view_projection", plan.matrices[layer].T.ravel().tolist())
                    if not orthographic:  # (an orthographic layer's program has no use for it)
                        shader.uniform_float("light_origin", light_origin)
                    # a closed caster's nearest face to the light faces it: its other faces are
                    # culled (counter-clockwise faces the light; mirrored or inward-facing ones
                    # wind the other way)
                    drawn = np.flatnonzero(want[layer]).tolist()  # (indices: no per-element numpy)
                    covering = [i for i in drawn if covers[i]]
                    if covering:
                        drawn = [i for i in drawn if not covers[i]]
                    facing_drawn = layer_facing[drawn].tolist()
                    scene.draw_positions([casters[i] for i in drawn], shader, frame_block=False,
                                         culling=[CULLING[f] for f in facing_drawn])
                    if covering:
                        self._draw_covering(scene, [casters[i] for i in covering], orthographic,
                                            plan.matrices[layer], light_origin)
                finally:
                    gpu.state.depth_test_set("NONE")
                    gpu.state.depth_mask_set(False)
                    gpu.state.face_culling_set("NONE")
            self.renders += 1
        self.key = key
        self.held, self._held_casters = held, which
        self.content = content
        return True

    def _draw_covering(self, scene, draws: list, orthographic: bool, matrix, light_origin) -> None:
        """Partly covering casters into the bound layer by their coverage (every face: one seen
        through another's holes), a program per compiled graph's structure
        (``gpu_library.shadow_coverage_program``, compiled where a layer holds such a caster;
        counted in ``coverage_programs``)."""
        gpu.state.face_culling_set("NONE")
        groups: dict = {}
        for draw in draws:
            graph = scene.snapshot.materials[draw.material].graph
            groups.setdefault(graph.program if graph is not None else None, []).append(draw)
        for graph, group in groups.items():
            shader = gpu_library.shadow_coverage_program(graph, orthographic, PARTIAL_COVERAGE == "DITHER")
            self.coverage_programs.add((graph.key if graph is not None else None, orthographic))
            shader.bind()
            shader.uniform_float("shadow_view_projection", matrix.T.ravel().tolist())
            if not orthographic:
                shader.uniform_float("light_origin", light_origin)
            scene.draw_coverage(group, shader, graph)

    def free(self) -> None:
        """Hand the maps' texture to the library for the next renderer of its shape (a final
        render's successor draws every layer a caster reaches again, and clears the others unless
        they hold nothing already: ``far``; with Persistent Data it keeps them all where
        ``content`` is its own); the framebuffers belong to this context."""
        if self.texture is not None and self._shape is not None:
            size, layers = self._shape
            state = (frozenset(self.far), self.content, self.held, self._held_casters)
            gpu_library.LIBRARY.keep_spare(("shadow maps", self._shape), self.texture,
                                           4 * size * size * layers, state)
        self.texture = None
        self.far = set()
        self.content = self.held = self._held_casters = None
        self.framebuffers = []
        self.key = None
        self._shape = None


#: Leave a shadow layer that no caster reaches as it is when it already holds nothing (tests turn
#: it off to compare).
SKIP_FAR_LAYERS = True

#: Where a view's surfaces are shaded deferred, the occlusion pass draws their G-buffer in place
#: of its prepass (the same depth and normals: one drawing of the geometry fewer; tests turn it
#: off to compare).
GBUFFER_AHEAD = True

#: Draw the occlusion's back-face prepass with the faces towards the viewer culled (the same
#: depths as discarding them in the program; tests turn it off to compare).
CULL_BACK_PREPASS = True


class OcclusionPass(Pass):
    """Screen-space ambient occlusion of the world's light (glsl/gtao.frag.glsl), for the views
    whose programs use it: the opaque surfaces' depth and normals drawn first (a prepass), then
    the visible fraction of the hemisphere per sub-pixel. Writes ``<view>.occlusion`` and
    ``<view>.prepass`` (its depth, the opaque pass's) -- or, where the view's surfaces are shaded
    deferred (``GBUFFER_AHEAD``), draws their G-buffer instead of the prepass, for the opaque
    pass to shade (``Frame.gbuffers``). Nothing when the world sends no light or occlusion is off."""

    draws_geometry = True

    def __init__(self):
        self.prepass: Target | None = None
        self.back: Target | None = None
        self.depths: Target | None = None
        self.raw: Target | None = None  # the interleaved trace, before its resolve
        self.target: Target | None = None
        self.gbuffer: GBuffer | None = None  # drawn in place of the prepass (GBUFFER_AHEAD)
        self.depth: gpu.types.GPUTexture | None = None  # that G-buffer's depth

    def run(self, frame: Frame, view: View) -> bool:
        lists = view_lists(frame, view)
        s = view.samples
        w, h = view.width * s, view.height * s
        if not any(features.occlusion for features, _ in lists.opaque):
            groups = opaque_groups(frame, view)
            if not (SHADE_ONCE and depth_prepass_pays(groups, frame.snapshot.triangle_count, w * h,
                                                      pixel_lights(frame, view))):
                self.free()
                return True
            # no occlusion, but shading costly enough that the opaque surfaces' depth is worth
            # drawing first: the prepass alone
            for target in (self.back, self.depths, self.raw, self.target):
                if target is not None:
                    target.free()
            self.back = self.depths = self.raw = self.target = None
            self._free_gbuffer()
            # its depth alone is read: no colour (a plane at 1280 x 720: 7.4 -> 1.2 ms)
            self.prepass = _fitted(self.prepass, w, h, "", depth=True, colors=0)
            frame.scene.put_frame(view.view_projection, view.width, view.height, view.samples)
            self._draw_prepass(frame, view, lists, self.prepass, back_faces=False)
            frame.outputs[view.output("prepass")] = self.prepass
            return True
        opaque = opaque_groups(frame, view)
        ahead = GBUFFER_AHEAD and any(features.deferred for features, _ in opaque)
        if ahead:
            if self.prepass is not None:
                self.prepass.free()
                self.prepass = None
            if self.depth is None or (self.depth.width, self.depth.height) != (w, h):
                self.depth = new_texture(w, h, "DEPTH_COMPONENT32F")
            if self.gbuffer is None or not self.gbuffer.fits(w, h, self.depth, True):
                self.gbuffer = GBuffer(w, h, self.depth, True)
        else:
            self._free_gbuffer()
            # float32 normals, as the G-buffer's: the same occlusion forward and deferred
            self.prepass = _fitted(self.prepass, w, h, "RGBA32F", depth=True)
        self.back = _fitted(self.back, w, h, "", depth=True, colors=0)  # its depth alone is read
        self.depths = _fitted(self.depths, w, h, "RG32F")
        scale = programs.OCCLUSION_SCALES[frame.snapshot.settings.occlusion_resolution]
        # the trace, and each cell's traced normal and depth for the resolve (colors 2)
        self.raw = _fitted(self.raw, -(-w // scale), -(-h // scale), "RGBA32F", colors=2)
        self.target = _fitted(self.target, w, h, "RGBA16F")
        frame.scene.put_frame(view.view_projection, view.width, view.height, view.samples)
        if ahead:
            # the G-buffer's depth and normals are the prepass's (the same vertex program and
            # normal), its face texture's w the prepass's alpha
            if not draw_gbuffer(frame, view, opaque, self.gbuffer, write_depth=True):
                return False
            frame.gbuffers[view.output("gbuffer")] = self.gbuffer
            depth_map, normal_map, facing_map = self.depth, self.gbuffer.textures[1], self.gbuffer.textures[2]
        else:
            self._draw_prepass(frame, view, lists, self.prepass, back_faces=False)
            depth_map = self.prepass.texture_depth
            normal_map = facing_map = self.prepass.texture_color
        self._draw_prepass(frame, view, lists, self.back, back_faces=True)
        camera = frame.snapshot.camera
        projection = (np.asarray(frame.view_projection(view), np.float64)
                      @ invert(np.asarray(camera.view, np.float64)))
        rows = np.zeros((3 * 16 + 12,), np.float32)
        inverse = invert(projection)
        rows[0:16] = inverse.T.ravel()
        rows[16:32] = projection.T.ravel()
        rows[32:48] = np.asarray(camera.view, np.float64).T.ravel()
        perspective = 1.0 if camera.is_perspective else 0.0
        rows[48:52] = (frame.snapshot.settings.occlusion_distance, perspective, w, h)
        # a view position's x and y at device coordinates (x, y) on the near plane: over its z
        # (perspective, times the depth) or alone (orthographic), affine in x and y
        near = inverse @ np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]])
        lateral = near[:2] / near[2 if camera.is_perspective else 3]
        rows[52:56] = np.concatenate([lateral[:, 1] - lateral[:, 0], lateral[:, 2] - lateral[:, 0]])
        rows[56:58] = lateral[:, 0]
        block = gpu.types.GPUUniformBuf(rows.tobytes())
        back, depths, raw = self.back, self.depths, self.raw

        def bind_depths(shader):
            gpu_library.bind_sampler(shader, "depth_map", depth_map)
            gpu_library.bind_sampler(shader, "back_depth_map", back.texture_depth)
            gpu_library.bind_sampler(shader, "facing_map", facing_map)
            shader.uniform_block("occlusion", block)

        def bind(shader):
            gpu_library.bind_sampler(shader, "depths", depths.texture_color)
            gpu_library.bind_sampler(shader, "normal_map", normal_map)
            shader.uniform_block("occlusion", block)

        frame.draw_full_screen(gpu_library.occlusion_depths_program(), bind_depths, self.depths)

        def bind_resolve(shader):
            gpu_library.bind_sampler(shader, "raw", raw.texture_color)
            gpu_library.bind_sampler(shader, "traced_cells", raw.more_colors[0])
            bind(shader)

        frame.draw_full_screen(gpu_library.gtao_program(scale), bind, self.raw)
        frame.draw_full_screen(gpu_library.occlusion_resolve_program(scale), bind_resolve, self.target)
        frame.outputs[view.output("occlusion")] = self.target
        if not ahead:
            frame.outputs[view.output("prepass")] = self.prepass
        return True

    @staticmethod
    def _draw_prepass(frame: Frame, view: View, lists, target: Target, back_faces: bool,
                      groups=None) -> None:
        """The opaque surfaces' nearest depth and normals into ``target`` (its depth alone where
        it has no colour; ``back_faces``: the nearest faces turned away, depth alone). ``groups``:
        the refraction pass's transmitting surfaces in place of ``lists``' opaque ones, their
        nearest faces turned away with their normals facing the viewer (where rays leave them)."""
        normals = groups is not None
        groups = lists.opaque if groups is None else groups
        front_culling = None if back_faces else view_culling(frame, view, groups)
        with target.bind():
            target.clear(color=(0.0, 0.0, 1.0, 0.0), depth=1.0)
            gpu.state.depth_test_set("LESS_EQUAL")
            gpu.state.depth_mask_set(True)
            gpu.state.blend_set("NONE")
            # (the faces turned away keep their program: it leaves out those towards the viewer;
            # their normals' program draws whatever the culling leaves it)
            shader = gpu_library.prepass_program(back_faces and not normals,
                                                 depth_only=not (target.colors or back_faces))
            try:
                for _features, draws in groups:
                    culling = None
                    if back_faces and (CULL_BACK_PREPASS or normals):
                        # the faces turned away alone: the others culled before they rasterise
                        # (the program discards them too); a mirrored object's outward faces
                        # wind the other way (turning the winding with front_facing_set would
                        # turn the program's gl_FrontFacing too)
                        culling = ["BACK" if h < 0 else "FRONT" for h in frame.scene.handedness(draws)]
                    elif front_culling is not None:
                        culling = [front_culling(draw) for draw in draws]
                    frame.scene.draw_positions(draws, shader, culling=culling)
            finally:
                gpu.state.depth_test_set("NONE")
                gpu.state.depth_mask_set(False)
                gpu.state.face_culling_set("NONE")

    def _free_gbuffer(self) -> None:
        if self.gbuffer is not None:
            self.gbuffer.free()
        self.gbuffer = self.depth = None

    def textures(self) -> list:
        out = [t for target in (self.prepass, self.back, self.depths, self.raw, self.target)
               if target is not None for t in target.owned()]
        if self.gbuffer is not None:
            out += list(self.gbuffer.textures)
        return out + ([self.depth] if self.depth is not None else [])

    def free(self) -> None:
        for target in (self.prepass, self.back, self.depths, self.raw, self.target):
            if target is not None:
                target.free()
        self.prepass = self.back = self.depths = self.raw = self.target = None
        self._free_gbuffer()


#: Draw the opaque surfaces against the occlusion prepass's depth where there is one, so that
#: each pixel is shaded once (tests turn it off to compare).
SHADE_ONCE = True


#: Shade opaque surfaces deferred where that pays (``deferred_pays``; tests turn it off to compare).
DEFERRED = True


#: The lights a pixel evaluates from which its shading counts as costly (``costly_shading``).
MANY_LIGHTS = 5


def costly_shading(features: programs.Features, lights: float | None = None) -> bool:
    """A program costly per pixel: penumbrae searched in shadow maps, area lights, the world's
    light (its maps and occlusion), the world sampled per pixel, many lights: ``lights``, those
    a pixel evaluates (``pixel_lights``: with light culling its tile's, on average), by default
    every light the program holds."""
    return (features.soft_shadows or "AREA" in features.light_kinds or bool(features.environment)
            or features.env_samples > 0 or _many_lights(features, lights))


def heaviest_shading(features: programs.Features, lights: float | None = None) -> bool:
    """Among the costly programs (``costly_shading``), those whose every pixel costs the most:
    area lights (their polygons, and their penumbrae in six maps), or many lights."""
    return "AREA" in features.light_kinds or _many_lights(features, lights)


def _many_lights(features: programs.Features, lights: float | None) -> bool:
    return (features.max_lights if lights is None else lights) >= MANY_LIGHTS


def view_lists(frame: Frame, view: View):
    """``view``'s draws grouped by program (``SceneResources.draw_lists``), shading through light
    culling's tile lists where they pay for the view (``SceneResources.culls``)."""
    scene = frame.scene
    return scene.draw_lists(view.model, view.half_target,
                            scene.culls(view.view_projection, view.width, view.height, view.samples))


def pixel_lights(frame: Frame, view: View) -> float:
    """How many lights a pixel of ``view`` evaluates, on average (light culling lists a screen
    tile's: 64 lights that each reach a sixteenth of the view are ~4 a pixel)."""
    return frame.scene.lights_per_pixel(view.view_projection, view.width, view.height, view.samples)


#: The most pixels per triangle, on average over the view, at which deferred shading pays: for a
#: costly program, and for one of the heaviest (``heaviest_shading``). A forward program shades
#: the partly covered blocks of pixels along each triangle's edges whole, so the smaller the
#: triangles the more it shades twice; the G-buffer's writes cost the same whatever their size.
DEFERRED_PIXELS_PER_TRIANGLE = 32
DEFERRED_PIXELS_PER_TRIANGLE_HEAVIEST = 64


def deferred_pays(features: programs.Features, triangles: int, pixels: int,
                  lights: float | None = None) -> bool:
    """Whether ``features``' surfaces are shaded deferred (passes.OpaquePass): where their shading
    is costly and the triangles small against what a pixel costs (DEFERRED_PIXELS_PER_TRIANGLE);
    not for image-mapped surfaces (Features), nor beyond DEFERRED_PIXELS (the G-buffer's memory).
    Measured (Principled set, in-process alternating medians of min-of-3, forward -> deferred):
    640 x 360: furnace 490 -> 318 ms, softbox 195 -> 165, roughness_sweep 141 -> 123,
    material_grid (22 px a triangle) 125 -> 112; 1280 x 720 (35 px a triangle): furnace 834 ->
    503, softbox 465 -> 368, roughness_sweep 379 -> 370; softbox at 1920 x 1080 (78 px) 869 ->
    817 (within this machine's noise: left forward, beyond the 64 px); material_grid at 960 x 720
    (65 px) 274 -> 288, world at 640 x 360 (48 px) 84 -> 86 (those stay forward). Shading all
    surfaces deferred lost 4-16 % on the presets of one or two lights without penumbrae (fresnel,
    hdr, long_tail: the G-buffer's writes). ``lights``: as ``costly_shading``'s."""
    if not (DEFERRED and not features.peel and features.graph is None and pixels <= DEFERRED_PIXELS
            and costly_shading(features, lights)):
        return False
    heaviest = heaviest_shading(features, lights)
    most = DEFERRED_PIXELS_PER_TRIANGLE_HEAVIEST if heaviest else DEFERRED_PIXELS_PER_TRIANGLE
    return most * triangles >= pixels


def opaque_groups(frame: Frame, view: View) -> list:
    """The view's opaque (features, draws) groups, each marked deferred where that pays."""
    pixels = view.width * view.height * view.samples ** 2
    triangles = frame.snapshot.triangle_count
    lights = pixel_lights(frame, view)
    return [(replace(features, deferred=deferred_pays(features, triangles, pixels, lights)), draws)
            for features, draws in view_lists(frame, view).opaque]


def depth_prepass_pays(opaque, triangles: int, pixels: int, lights: float | None = None) -> bool:
    """Whether drawing the opaque surfaces' depth ahead of their shading (the prepass alone, where
    no occlusion asks for it) saves more than it costs: where some surface shaded forward has a
    program costly per pixel (``costly_shading``), each pixel hidden behind another surface then
    costs no shading; the geometry drawn
    twice costs its vertices and rasterising again, which a scene of many more triangles than
    pixels does not win back. Measured (docs/bench/peers.md's presets, 640 x 360): softbox
    and furnace gain, scenes of a light or two without penumbrae lose a few ms; so do 64 lights over
    a plane with light culling, ~4 a pixel (1280 x 720: 53.8 ms a frame with the prepass, 49.7 without).
    ``lights``: as ``costly_shading``'s."""
    if triangles > pixels:
        return False
    # a G-buffer is a prepass already
    return any(costly_shading(f, lights) for f, _ in opaque if not f.deferred)


#: The most pixels (supersampled) a view shades deferred: its G-buffer holds 48 bytes a pixel
#: (400 MB at this size, a 3840 x 2160 view); larger views are shaded forward.
DEFERRED_PIXELS = 3840 * 2160


class GBuffer:
    """The G-buffer of the opaque surfaces shaded deferred (glsl/gbuffer.frag.glsl), float32:
    position and material row, the normal facing the viewer and the group shading it, and (where
    some program looks shadows up: ``face``) the flat face's normal; drawn against ``depth`` (the
    prepass's, or the opaque pass's own)."""

    def __init__(self, width: int, height: int, depth: gpu.types.GPUTexture, face: bool):
        self.width, self.height, self.depth, self.face = width, height, depth, face
        self.textures = tuple(new_texture(width, height, "RGBA32F") for _ in range(3 if face else 2))
        self.framebuffer = gpu.types.GPUFrameBuffer(color_slots=self.textures, depth_slot=depth)
        # the groups alone are cleared (to -1: no surface): a pixel's other texels are read only
        # where a surface wrote them this frame
        self.groups = gpu.types.GPUFrameBuffer(color_slots=self.textures[1])
        # each pixel's group as a depth (write_groups, made at its first use), which the groups'
        # passes test against
        self.group_depth: gpu.types.GPUTexture | None = None
        self.group_framebuffer: gpu.types.GPUFrameBuffer | None = None
        self._shading: tuple | None = None  # (colour texture, its framebuffer with group_depth)

    def write_groups(self, frame: Frame) -> None:
        """Each pixel's deferred group as a depth (glsl/group_depth.frag.glsl), the far plane where
        none: a group's pass then shades its own pixels alone (``shading_framebuffer``)."""
        if self.group_depth is None:
            self.group_depth = new_texture(self.width, self.height, "DEPTH_COMPONENT32F")
            self.group_framebuffer = gpu.types.GPUFrameBuffer(depth_slot=self.group_depth)
        shader = gpu_library.group_depth_program()
        with self.group_framebuffer.bind():
            gpu.state.depth_test_set("ALWAYS")
            gpu.state.depth_mask_set(True)
            try:
                shader.bind()
                gpu_library.bind_sampler(shader, "gbuffer_normal", self.textures[1])
                frame.full_screen.draw(shader)
            finally:
                gpu.state.depth_test_set("NONE")
                gpu.state.depth_mask_set(False)

    def shading_framebuffer(self, color: gpu.types.GPUTexture) -> gpu.types.GPUFrameBuffer:
        """``color`` drawn into with the groups' depth (``write_groups``, drawn first) to test
        against."""
        if self._shading is None or self._shading[0] is not color:
            self._shading = (color, gpu.types.GPUFrameBuffer(color_slots=color, depth_slot=self.group_depth))
        return self._shading[1]

    def fits(self, width: int, height: int, depth: gpu.types.GPUTexture, face: bool) -> bool:
        return (self.width, self.height, self.face) == (width, height, face) and self.depth is depth

    def clear(self, depth: bool) -> None:
        with self.groups.bind():
            self.groups.clear(color=(0.0, 0.0, 0.0, -1.0))
        if depth:
            with self.framebuffer.bind():
                self.framebuffer.clear(depth=1.0)

    def free(self) -> None:
        self.framebuffer = self.groups = self.textures = self.depth = None
        self.group_depth = self.group_framebuffer = self._shading = None


#: Shade each deferred group over its surfaces' rectangle on screen alone (tests turn it off to
#: compare).
DEFERRED_SCISSOR = True
#: Shade each deferred group's pixels alone, by the depth test against the groups' depth
#: (GBuffer.write_groups; tests turn it off to compare).
DEFERRED_DEPTH_TEST = True
#: The groups a depth stands for (glsl/deferred_depth.glsl); a view of more shades each group's
#: pass over its rectangle and leaves the rest to the program's discard.
GATED_GROUPS = 255


def depth_gated(opaque) -> bool:
    """Whether the deferred groups of ``opaque`` (``opaque_groups``) are shaded behind the depth
    test against their pixels' groups (GBuffer.write_groups): where there are two or more. A pass
    over pixels it discards costs most of their shading on the CPU rasteriser (softbox, 640 x 360:
    24 ms against 0.6 behind a failing depth test; Auto's three materials on the default terms
    beside ten on the Principled set, the two passes 35 + 18 -> 30 + 8 ms); one group saves about
    what writing the groups' depth costs (the frames 0.98-1.02x)."""
    groups = [group for group, (features, _draws) in enumerate(opaque) if features.deferred]
    return DEFERRED_DEPTH_TEST and len(groups) > 1 and groups[-1] < GATED_GROUPS


def deferred_rectangle(frame: Frame, view: View, draws: list[Draw], width: int,
                       height: int) -> tuple[int, int, int, int] | None:
    """The pixels (x, y, width, height) of a ``width`` x ``height`` target where ``draws`` can
    cover a pixel: the rectangle around their items' bounding spheres on screen (the whole target
    where one reaches behind the camera, or without DEFERRED_SCISSOR); None where they cover none.
    A deferred group's pass is a full-screen triangle whose every pixel reads the G-buffer to find
    its group: outside the rectangle none is the group's (furnace with Auto's two programs,
    640 x 360: the deferred passes 68 -> 61 ms, the one program's 60; one group over the whole
    target 0.94-0.99x)."""
    if not DEFERRED_SCISSOR:
        return 0, 0, width, height
    spheres = frame.scene.caster_spheres(draws)
    if not len(spheres):
        return None
    boxes = light_tiles.screen_boxes(spheres[:, :3], spheres[:, 3],
                                     np.asarray(frame.view_projection(view), np.float64), width, height)
    if not np.all(np.isfinite(boxes)):
        return 0, 0, width, height
    x0, y0 = max(int(np.floor(boxes[:, 0].min())), 0), max(int(np.floor(boxes[:, 1].min())), 0)
    x1, y1 = min(int(np.ceil(boxes[:, 2].max())), width), min(int(np.ceil(boxes[:, 3].max())), height)
    if x1 <= x0 or y1 <= y0:
        return None
    return x0, y0, x1 - x0, y1 - y0


def draw_gbuffer(frame: Frame, view: View, opaque, gbuffer: GBuffer, write_depth: bool) -> bool:
    """Every opaque surface of ``opaque`` (``opaque_groups``) into ``gbuffer``, each with its
    group's number (-1 where shaded forward), against the G-buffer's depth -- written where
    ``write_depth`` (no prepass drew it). False if cancelled."""
    culling = view_culling(frame, view, opaque)
    gbuffer.clear(depth=write_depth)
    with gbuffer.framebuffer.bind():
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(write_depth)
        gpu.state.face_culling_set("NONE")
        gpu.state.blend_set("NONE")
        try:
            groups = [(group if features.deferred else -1, draws)
                      for group, (features, draws) in enumerate(opaque)]
            drawn = frame.scene.draw_gbuffer(groups, frame.should_stop, culling)
        finally:
            gpu.state.depth_test_set("NONE")
            gpu.state.depth_mask_set(False)
            gpu.state.face_culling_set("NONE")
    if depth_gated(opaque):
        gbuffer.write_groups(frame)
    return drawn


class OpaquePass(TargetPass):
    """The view's scene target (colour and depth, supersampled size), cleared to the background
    colour, and every opaque surface drawn into it. Where the occlusion pass drew its prepass
    (``<view>.prepass``), the target takes that depth and draws against it without writing it:
    hidden surfaces cost no shading. Where shading is costly and the triangles small
    (``deferred_pays``), surfaces are shaded deferred: their G-buffer drawn first (by the occlusion
    pass, in its prepass's place, where there is occlusion; it writes the depth where no prepass
    did), then each program once over its own pixels, in whole quads of
    pixels (small triangles shaded forward pay for the partly covered blocks of pixels they
    touch); the others are drawn forward against the finished depth. Writes ``<view>.scene``."""

    draws_geometry = True

    def __init__(self):
        super().__init__()
        self.gbuffer: GBuffer | None = None
        self.depth: gpu.types.GPUTexture | None = None  # the G-buffer's own depth (no prepass)

    def run(self, frame: Frame, view: View) -> bool:
        s = view.samples
        w, h = view.width * s, view.height * s
        opaque = opaque_groups(frame, view)
        deferred = any(features.deferred for features, _ in opaque)
        prepass = frame.outputs.get(view.output("prepass")) if SHADE_ONCE else None
        if prepass is not None and not prepass.fits(w, h, prepass.format, True, prepass.colors):
            prepass = None
        ahead = frame.gbuffers.get(view.output("gbuffer")) if deferred else None
        # the depth drawn against: the prepass's (the nearest opaque surface's, by the same vertex
        # program: each pixel is shaded once) or that of the G-buffer the occlusion pass drew,
        # else the G-buffer's own, else the target's own
        shared = prepass.texture_depth if prepass is not None else ahead.depth if ahead is not None else None
        if deferred and shared is None:
            if self.depth is None or (self.depth.width, self.depth.height) != (w, h):
                self.depth = new_texture(w, h, "DEPTH_COMPONENT32F")
            shared = self.depth
        elif self.depth is not None and shared is not self.depth:
            self.depth = None
        if shared is not None:
            if self.target is None or not self.target.fits(w, h, view.format, True) or \
                    self.target.texture_depth is not shared:
                TargetPass.free(self)
                self.target = Target(w, h, view.format, depth_texture=shared)
        else:
            if self.target is not None and self.target.shares_depth:
                TargetPass.free(self)
            self.fit(w, h, view.format, depth=True)
        target = self.target
        frame.outputs[view.output("scene")] = target
        frame.scene.put_frame(view.view_projection, view.width, view.height, view.samples)
        occlusion = frame.outputs.get(view.output("occlusion"))

        def bind(shader):
            gpu_library.bind_sampler(shader, "env_occlusion_map", occlusion.texture_color)

        drawn = True  # every G-buffer draw done (a cancel shades what was drawn, no more)
        gbuffer = ahead
        if deferred and ahead is None:
            face = any(features.deferred and features.shadow_layers for features, _ in opaque)
            if self.gbuffer is None or not self.gbuffer.fits(w, h, shared, face):
                self.gbuffer = GBuffer(w, h, shared, face)
            gbuffer = self.gbuffer
            drawn = draw_gbuffer(frame, view, opaque, gbuffer, write_depth=prepass is None)
        elif self.gbuffer is not None:
            self.gbuffer.free()
            self.gbuffer = None
        with target.bind():
            if shared is None:
                target.framebuffer.clear(color=view.background, depth=1.0)
            else:
                target.framebuffer.clear(color=view.background)
            gpu.state.face_culling_set("NONE")
            gpu.state.blend_set("NONE")
            try:
                deferred = [(group, features, group_draws)
                            for group, (features, group_draws) in enumerate(opaque) if features.deferred]
                gated = depth_gated(opaque)
                if deferred:
                    # with several groups, each one's pass tested against the groups' depth
                    # (GBuffer.write_groups)
                    with (gbuffer.shading_framebuffer(target.texture_color).bind() if gated
                          else contextlib.nullcontext()):
                        gpu.state.depth_test_set("EQUAL" if gated else "NONE")
                        gpu.state.depth_mask_set(False)
                        for group, features, group_draws in deferred:
                            rectangle = deferred_rectangle(frame, view, group_draws, w, h)
                            if rectangle is None:
                                continue
                            gpu.state.scissor_test_set(True)
                            gpu.state.scissor_set(*rectangle)
                            try:
                                frame.scene.shade_deferred(features, group, view.lobes, gbuffer.textures,
                                                           frame.full_screen,
                                                           bind if features.occlusion else None)
                            finally:
                                gpu.state.scissor_test_set(False)
                        gpu.state.depth_test_set("NONE")
                if not drawn:
                    return False
                gpu.state.depth_test_set("LESS_EQUAL")
                gpu.state.depth_mask_set(shared is None)
                culling = view_culling(frame, view, opaque)
                for features, draws in opaque:
                    if features.deferred:
                        continue
                    if not frame.scene.draw_group(features, draws, view.lobes, frame.should_stop,
                                                  bind if features.occlusion else None, culling):
                        return False
            finally:
                gpu.state.depth_test_set("NONE")
                gpu.state.depth_mask_set(False)
                gpu.state.face_culling_set("NONE")
        return True

    def free(self) -> None:
        super().free()
        if self.gbuffer is not None:
            self.gbuffer.free()
        self.gbuffer = self.depth = None

    def textures(self) -> list:
        out = super().textures() + ([self.depth] if self.depth is not None else [])
        return out + (list(self.gbuffer.textures) if self.gbuffer is not None else [])


class BackgroundPass(Pass):
    """Where the camera sees no opaque surface (depth still at the far plane) and environment
    images (the film not transparent): the world along each sub-pixel's ray, into
    ``<view>.scene`` -- after the opaque surfaces, so that covered pixels cost nothing, and before
    the transparent ones, which blend over it."""

    def run(self, frame: Frame, view: View) -> bool:
        target = frame.outputs[view.output("scene")]
        terms = frame.snapshot.world.camera
        images = min(len(World.images(terms)), MAX_ENVIRONMENT_IMAGES)
        if not images or view.background[3] <= 0.0:
            return True  # the clear colour is the background
        model = view.model or frame.snapshot.settings.model
        features = programs.BackgroundFeatures(images, clamp=model != "PBR", half_target=view.half_target)
        shader = gpu_library.background_program(features)
        vp = frame.view_projection(view)
        inverse = invert(np.asarray(vp, np.float64)).astype(np.float32)
        with target.bind():
            gpu.state.depth_test_set("LESS_EQUAL")  # the triangle lies at the far plane
            gpu.state.depth_mask_set(False)
            gpu.state.blend_set("NONE")
            shader.bind()
            frame.scene.bind_world(shader, terms)
            shader.uniform_float("inverse_view_projection", inverse.T.ravel().tolist())
            shader.uniform_float("viewport", (float(target.width), float(target.height), 0.0, 0.0))
            frame.full_screen.draw(shader)
            gpu.state.depth_test_set("NONE")
        return True


def draw_nearest(frame: Frame, view: View, groups, test: str, bind) -> bool:
    """Draw ``groups`` ((features, draws)) into the bound framebuffer, each pixel keeping the
    fragment nearest by the depth ``test`` and writing its depth, unblended; False if cancelled."""
    gpu.state.depth_test_set(test)
    gpu.state.depth_mask_set(True)
    gpu.state.blend_set("NONE")
    try:
        for features, draws in groups:
            if not frame.scene.draw_group(features, draws, view.lobes, frame.should_stop, bind):
                return False
    finally:
        gpu.state.depth_test_set("NONE")
        gpu.state.depth_mask_set(False)
    return True


class RefractionPass(Pass):
    """The transmitting surfaces (a Transmission Weight, Glass and Refraction BSDFs: glsl/transmission.glsl),
    drawn over ``<view>.scene`` once the opaque surfaces and the world are in it -- what they refract,
    in screen space (EEVEE's refraction): a copy of its colour with its depth (level 0), halved and
    blurred into levels for rough glass, packed into one texture; and the nearest faces of the
    transmitting surfaces turned away from the viewer (depth and normals: where a ray through a
    closed object leaves it). Then each transmitting surface's nearest fragment is shaded, its
    transmitted part read from the copy where its refracted ray meets the opaque scene, and written
    with its depth (the partly transparent surfaces after it are drawn over it where in front, and
    hidden behind it). Nothing where no surface transmits."""

    draws_geometry = True

    def __init__(self):
        self._size: tuple | None = None
        self.levels: list[Target] = []
        self.atlas: Target | None = None
        self.back: Target | None = None
        self.block = None

    def _buffers(self, width: int, height: int, levels: int) -> None:
        if self._size == (width, height, levels):
            return
        self.free()
        sizes, self.rects, atlas = programs.refraction_layout(width, height, levels)
        self.levels = [Target(w, h, "RGBA32F", depth=False) for w, h in sizes]
        # one level is the copy alone (read where it is); more are packed into one texture
        self.atlas = Target(*atlas, "RGBA32F", depth=False) if len(sizes) > 1 else None
        self.back = Target(width, height, "RGBA32F", depth=True)
        self._size = (width, height, levels)

    @staticmethod
    def levels_needed(frame: Frame, groups) -> int:
        """The blurred levels the transmitting surfaces ``groups`` read: the copy alone where each
        is smooth (its material's Roughness at most ``programs.REFRACTION_SMOOTH`` and no node graph
        that could make it rougher: glsl/transmission.glsl reads such glass unblurred), else every
        level."""
        materials = frame.snapshot.materials
        rough = any(materials[draw.material].graph is not None
                    or materials[draw.material].roughness > programs.REFRACTION_SMOOTH
                    for _features, draws in groups for draw in draws)
        return programs.REFRACTION_LEVELS if rough else 1

    def run(self, frame: Frame, view: View) -> bool:
        groups = view_lists(frame, view).refracted
        if not groups:
            self.free()  # a viewport keeps no copy once nothing transmits
            return True
        target = frame.outputs[view.output("scene")]
        self._buffers(target.width, target.height, self.levels_needed(frame, groups))
        self._copy(frame, target)
        # the transmitting surfaces' nearest faces turned away from the viewer: depth and normals
        OcclusionPass._draw_prepass(frame, view, None, self.back, back_faces=True, groups=groups)
        inverse = invert(np.asarray(frame.view_projection(view), np.float64))
        behind = self.atlas or self.levels[0]
        self.block = gpu.types.GPUUniformBuf(programs.pack_refraction(
            inverse, self.rects, (behind.width, behind.height), float(view.background[3])))

        def bind(shader):
            gpu_library.bind_sampler(shader, "refraction_behind", behind.texture_color)
            gpu_library.bind_sampler(shader, "refraction_back", self.back.texture_color)
            gpu_library.bind_sampler(shader, "refraction_back_depth", self.back.texture_depth)
            shader.uniform_block("refraction", self.block)

        with target.bind():
            gpu.state.face_culling_set("NONE")
            return draw_nearest(frame, view, groups, "LESS_EQUAL", bind)

    def _copy(self, frame: Frame, target: Target) -> None:
        """The scene target's colour and depth into level 0, each next level from the last, and
        every level into its rectangle of the atlas."""
        def bind_copy(shader):
            gpu_library.bind_sampler(shader, "source", target.texture_color)
            gpu_library.bind_sampler(shader, "source_depth", target.texture_depth)

        frame.draw_full_screen(gpu_library.refraction_copy_program("COPY"), bind_copy, self.levels[0])
        if self.atlas is None:
            return  # the copy alone
        down = gpu_library.refraction_copy_program("DOWN")
        for source, level in zip(self.levels, self.levels[1:]):
            frame.draw_full_screen(down, lambda s, source=source: gpu_library.bind_sampler(
                s, "source", source.texture_color), level)
        pack = gpu_library.refraction_copy_program("PACK")
        atlas = self.atlas
        with atlas.bind():
            atlas.framebuffer.clear(color=(0.0, 0.0, 0.0, 1.0))
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set("NONE")
            pack.bind()
            try:
                for level, (x, y, w, h) in zip(self.levels, self.rects):
                    gpu.state.viewport_set(x, y, w, h)
                    gpu_library.bind_sampler(pack, "source", level.texture_color)
                    pack.uniform_float("offset", (float(x), float(y), 0.0, 0.0))
                    frame.full_screen.draw(pack)
            finally:
                gpu.state.viewport_set(0, 0, atlas.width, atlas.height)

    def free(self) -> None:
        for target in (*self.levels, self.atlas, self.back):
            if target is not None:
                target.free()
        self.levels, self.atlas, self.back, self.block = [], None, None, None
        self._size = None

    def textures(self) -> list:
        targets = (*self.levels, self.atlas, self.back)
        return [t for target in targets if target is not None for t in target.owned()]


class TransparencyPass(Pass):
    """Depth peeling (Everitt 2001) over the partly transparent surfaces: up to the scene's
    Transparency Layers passes, each keeping per pixel the nearest fragment behind the previous
    pass's (exact order, also within one mesh), composited front to back as they come, then the
    result over ``<view>.scene``. A pass whose predecessor peeled nothing is not drawn.

    Owns what peeling needs, the same for any number of layers: the layer being peeled (colour,
    and two depths taking turns as the one written and the previous layer's, read), two
    accumulators taking turns, and a small occupancy map that tells whether a layer holds
    anything. Dropped when a frame has nothing transparent.

    Where a peeled material holds a Holdout (``Features.holdout``), the layer and the accumulators
    have a second colour, the Holdout's share of the coverage (glsl/under.frag.glsl), and the share
    accumulated is subtracted from the alpha of the result (Cycles' alpha: a Holdout of 0.4 mixed
    with a Transparent BSDF over the world leaves 0.6 with the film opaque, 0 with it transparent);
    those colours exist only while such a material is drawn."""

    draws_geometry = True

    def __init__(self):
        self._size: tuple | None = None
        self.holdout = None  # the layer's Holdout share (a texture), while a peeled Holdout is drawn

    def _buffers(self, width: int, height: int, format: str, holdout: bool) -> None:
        if self._size == (width, height, format, holdout):
            return
        self.colour = new_texture(width, height, format)
        # the layer's Holdout share (its alpha), where a peeled material has a Holdout
        self.holdout = new_texture(width, height, format) if holdout else None
        self.depths = [new_texture(width, height, "DEPTH_COMPONENT32F") for _ in range(2)]
        colours = (self.colour, self.holdout) if holdout else self.colour
        # layer i writes depth (i + 1) % 2 and reads depth i % 2, the previous layer's
        self.layer_fbs = [gpu.types.GPUFrameBuffer(color_slots=colours, depth_slot=depth)
                          for depth in (self.depths[1], self.depths[0])]
        self.first = gpu.types.GPUFrameBuffer(depth_slot=self.depths[0])  # cleared to 0 for layer 0
        self.accumulators = [Target(width, height, format, depth=False, colors=2 if holdout else 1)
                             for _ in range(2)]
        block = programs.OCCUPANCY_BLOCK
        self.occupancy = Target(-(-width // block), -(-height // block), depth=False)
        self._size = (width, height, format, holdout)

    def _any_fragment(self, frame: Frame, depth: gpu.types.GPUTexture) -> bool:
        """Whether a peeled layer's depth holds any fragment: reduced on the GPU to one texel per
        block of ``programs.OCCUPANCY_BLOCK`` texels a side, and only that read back."""
        frame.draw_full_screen(gpu_library.occupancy_program(),
                               lambda s: gpu_library.bind_sampler(s, "layer_depth", depth), self.occupancy)
        return bool(self.occupancy.read()[..., 0].max() > 0.0)

    def run(self, frame: Frame, view: View) -> bool:
        groups = view_lists(frame, view).blended
        frame.peeled_layers = 0
        if not groups:
            self.free()  # a viewport keeps no peeling buffers once nothing is transparent
            return True
        target = frame.outputs[view.output("scene")]
        holdout = any(features.holdout for features, _ in groups)
        self._buffers(target.width, target.height, target.format, holdout)
        with self.first.bind():
            self.first.clear(depth=0.0)
        current = 0
        with self.accumulators[current].bind():
            self.accumulators[current].framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0))
        used = 0
        under = gpu_library.under_program(holdout)
        for i in range(max(int(frame.snapshot.settings.transparency_layers), 1)):
            previous = self.depths[i % 2]  # written by the last pass (cleared to 0 before the first)
            if used and not self._any_fragment(frame, previous):
                used -= 1  # the last pass peeled nothing, so no surface is left behind it
                break
            if not self._peel(frame, view, groups, self.layer_fbs[i % 2], target, previous):
                return False
            accumulated = self.accumulators[current]
            current = 1 - current

            def bind_under(shader, accumulated=accumulated):
                gpu_library.bind_sampler(shader, "accumulated", accumulated.texture_color)
                gpu_library.bind_sampler(shader, "peeled", self.colour)
                if holdout:
                    gpu_library.bind_sampler(shader, "accumulated_holdout", accumulated.more_colors[0])
                    gpu_library.bind_sampler(shader, "peeled_holdout", self.holdout)

            frame.draw_full_screen(under, bind_under, self.accumulators[current])
            used += 1
        frame.peeled_layers = used
        with target.bind():  # the layers over what is behind them: C + (1 - A) L_behind
            gpu.state.depth_test_set("NONE")
            gpu.state.depth_mask_set(False)
            gpu.state.blend_set("ALPHA_PREMULT")
            copy = gpu_library.post_program(programs.PostFeatures(samples=1))
            copy.bind()
            gpu_library.bind_sampler(copy, "hdr_image", self.accumulators[current].texture_color)
            frame.full_screen.draw(copy)
            if holdout:  # and the Holdout's share out of the alpha: (0, 0, 0, H) subtracted
                gpu.state.blend_set("SUBTRACT")
                gpu_library.bind_sampler(copy, "hdr_image", self.accumulators[current].more_colors[0])
                frame.full_screen.draw(copy)
            gpu.state.blend_set("NONE")
        return True

    @staticmethod
    def _peel(frame: Frame, view: View, groups, framebuffer, target: Target, previous) -> bool:
        """One layer: the nearest transparent fragment behind ``previous``, in front of the opaque."""

        def bind(shader):
            gpu_library.bind_sampler(shader, "opaque_depth", target.texture_depth)
            gpu_library.bind_sampler(shader, "peel_depth", previous)

        with framebuffer.bind():
            framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
            return draw_nearest(frame, view, groups, "LESS", bind)

    def free(self) -> None:
        if self._size is not None:
            for target in (*self.accumulators, self.occupancy):
                target.free()
            self.colour = self.holdout = self.depths = self.layer_fbs = self.first = None
            self.accumulators = self.occupancy = None
            self._size = None

    def textures(self) -> list:
        if self._size is None:
            return []
        own = [self.colour, *self.depths] + ([self.holdout] if self.holdout is not None else [])
        return own + [t for target in (*self.accumulators, self.occupancy) for t in target.owned()]


class ResolvePass(TargetPass):
    """Averages each pixel's ``samples`` x ``samples`` sub-pixels (a box filter) of
    ``<view>.scene`` into ``<view>.radiance``; without supersampling the scene target is the
    radiance and nothing is drawn (unless the view asks for a radiance target of its own)."""

    def run(self, frame: Frame, view: View) -> bool:
        scene = frame.outputs[view.output("scene")]
        if view.samples == 1 and not view.own_radiance:
            frame.outputs[view.output("radiance")] = scene
            return True
        self.fit(view.width, view.height, view.format)
        frame.draw_full_screen(gpu_library.post_program(programs.PostFeatures(samples=view.samples)),
                               lambda s: gpu_library.bind_sampler(s, "hdr_image", scene.texture_color),
                               self.target)
        frame.outputs[view.output("radiance")] = self.target
        return True


class ExposurePass(Pass):
    """Automatic exposure: ``<view>.radiance`` reduced to a histogram of log2 luminance on the
    GPU (three small full-screen stages, exposure.frag.glsl), BINS texels read back and metered
    (``exposure.meter``), then adapted from the previous frame by ``frame.adapt``. Writes
    ``frame.exposures[view.name]``; nothing to do under manual exposure."""

    def __init__(self):
        self.targets: dict[str, Target] = {}

    def _fit(self, stage: str, width: int, height: int) -> Target:
        self.targets[stage] = _fitted(self.targets.get(stage), width, height)
        return self.targets[stage]

    def histogram(self, frame: Frame, radiance: Target) -> tuple[np.ndarray, np.ndarray]:
        """(sum of log2 L, pixel count) per bin of ``radiance`` (``exposure.histogram``'s twin)."""
        k = exposure.block_size(radiance.width, radiance.height)
        blocks = self._fit("BLOCKS", -(-radiance.width // k), -(-radiance.height // k))
        rows = self._fit("ROWS", exposure.BINS, blocks.height)
        columns = self._fit("COLUMNS", exposure.BINS, 1)
        source = radiance
        for stage, target in (("BLOCKS", blocks), ("ROWS", rows), ("COLUMNS", columns)):
            def bind(shader, source=source, stage=stage):
                gpu_library.bind_sampler(shader, "source", source.texture_color)
                if stage == "BLOCKS":
                    shader.uniform_float("block", float(k))
            frame.draw_full_screen(gpu_library.exposure_program(stage), bind, target)
            source = target
        values = columns.read()[0]
        return values[:, 0].astype(np.float64), values[:, 1].astype(np.float64)

    def run(self, frame: Frame, view: View) -> bool:
        if view.auto_exposure is None:
            return True
        sums, counts = self.histogram(frame, frame.outputs[view.output("radiance")])
        metered = exposure.meter(sums, counts, view.auto_exposure)
        if metered is None:  # nothing counted (an empty transparent frame): compensation only
            metered = min(max(view.auto_exposure.compensation, view.auto_exposure.min_stops),
                          view.auto_exposure.max_stops)
        stops = frame.adapt(view, metered) if frame.adapt is not None else metered
        frame.exposures[view.name] = (stops, metered)
        return True

    def free(self) -> None:
        for target in self.targets.values():
            target.free()
        self.targets = {}

    def textures(self) -> list:
        return [t for target in self.targets.values() for t in target.owned()]


class DisplayPass(TargetPass):
    """Under one of the engine's own tone mappers: exposure, the tone curve and the transfer
    function over the resolved sub-pixels of ``<view>.scene``, into ``<view>.display``; under
    Blender's view transform with automatic exposure, the exposure alone (Combined stays
    scene-linear)."""

    def run(self, frame: Frame, view: View) -> bool:
        if view.display is None:
            return True
        scene = frame.outputs[view.output("scene")]
        self.fit(view.width, view.height, view.format)
        features = programs.PostFeatures(view.samples, view.display.tone_mapper, view.display.transfer)

        def bind(shader):
            gpu_library.bind_sampler(shader, "hdr_image", scene.texture_color)
            shader.uniform_float("exposure_scale", 2.0 ** frame.exposure(view))

        frame.draw_full_screen(gpu_library.post_program(features), bind, self.target)
        frame.outputs[view.output("display")] = self.target
        return True


class ComparePass(TargetPass):
    """A|B: two views' images composited into ``compare``: model A left of a divider and B right
    of it, or the luminance difference as a heat map with its scale."""

    def run(self, frame: Frame, comparison: Comparison) -> bool:
        a, b = frame.outputs[comparison.a], frame.outputs[comparison.b]
        self.fit(comparison.width, comparison.height, "RGBA16F" if comparison.half_target else "RGBA32F")

        def bind(shader):
            gpu_library.bind_sampler(shader, "image_a", a.texture_color)
            gpu_library.bind_sampler(shader, "image_b", b.texture_color)
            if comparison.features.mode == "SPLIT":
                shader.uniform_float("split", float(comparison.split))
            else:
                shader.uniform_float("range", float(comparison.value_range))

        frame.draw_full_screen(gpu_library.compare_program(comparison.features), bind, self.target)
        frame.outputs["compare"] = self.target
        return True


#: The passes that draw one view, in order.
VIEW_PASSES = (OcclusionPass, OpaquePass, BackgroundPass, RefractionPass, TransparencyPass, ResolvePass,
               ExposurePass, DisplayPass)
