"""The GPU copy of one scene: geometry, uniform buffers and textures, uploaded only on change.

A ``SceneResources`` lives as long as its ``Renderer`` (one final render, or a viewport session)
and is brought up to date with ``sync(snapshot)``: each piece of data is packed, compared with
what the GPU already holds and uploaded only when it differs, and counted in ``uploads`` (reset
at each sync) so that tests and the viewport can see what an edit cost:

- ``geometry``: one vertex buffer per material range of each mesh (by geometry key);
- ``objects``: every draw item's matrices, in blocks of ``programs.OBJECT_BLOCK`` (a draw names
  its entry by block and index; one buffer, not one per item per frame);
- ``lights``, one texture (a row per light); ``materials``, one block per material; ``frame``
  (camera, counts), one block, packed when a frame runs (the viewport's camera moves between
  syncs);
- ``textures``: one per image the materials sample, from the pixels the snapshot carries;
- ``shadows``: the shadow maps' layers (``shadows.plan``, fitted to the geometry's bounds), one
  block; the maps themselves are drawn by ``passes.ShadowPass`` when ``caster_key`` or the plan
  changes.

It also groups the draws per shading program (``draw_lists``) and draws a group
(``draw_group``) for the passes that draw geometry.
"""

from __future__ import annotations

import hashlib
import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import gpu
import numpy as np

from ..plan import light_tiles, programs, shadows
from ..scene import matrices
from ..scene.snapshot import MAX_ENVIRONMENT_IMAGES, ImageData, MeshGeometry, Snapshot, World
from . import gpu_library

#: GPU texture format per ``ImageData.storage``: byte images keep their bytes (an sRGB one is
#: decoded to linear by the sampler, before filtering, as Blender's own image textures are).
TEXTURE_FORMATS = {"SRGB8": "SRGB8_A8", "UNORM8": "RGBA8", "HALF": "RGBA16F", "FLOAT": "RGBA32F"}


def _vertex_format() -> gpu.types.GPUVertFormat:
    fmt = gpu.types.GPUVertFormat()
    fmt.attr_add(id="pos", comp_type="F32", len=3, fetch_mode="FLOAT")
    fmt.attr_add(id="nor", comp_type="F32", len=3, fetch_mode="FLOAT")
    fmt.attr_add(id="uv", comp_type="F32", len=2, fetch_mode="FLOAT")
    fmt.attr_add(id="tangent", comp_type="F32", len=4, fetch_mode="FLOAT")
    return fmt


def attribute_buffer(geometry: MeshGeometry, attributes: tuple[tuple[str, str], ...]) -> gpu.types.GPUVertBuf:
    """A vertex buffer of a node graph's ``attributes`` (``attr<k>``, vec4 per corner) from the
    geometry's (zeros where the mesh has no such attribute: a reader of it sees 0, as in Cycles)."""
    count = len(geometry.positions)
    fmt = gpu.types.GPUVertFormat()
    for k in range(len(attributes)):
        fmt.attr_add(id=f"attr{k}", comp_type="F32", len=4, fetch_mode="FLOAT")
    vbo = gpu.types.GPUVertBuf(fmt, count)
    for k, attribute in enumerate(attributes):
        values = geometry.attributes.get(attribute)
        vbo.attr_fill(f"attr{k}", np.ascontiguousarray(values if values is not None else np.zeros((count, 4)),
                                                       np.float32))
    return vbo


def upload_geometry(geometry: MeshGeometry) -> list[tuple[int, gpu.types.GPUBatch, tuple]]:
    """One vertex buffer of the mesh's corners and one indexed batch per material range:
    ``[(slot, batch, (vertex buffer, index buffer)), ...]`` (a batch with a node graph's attributes
    is made from the buffers, ``attribute_buffer``'s added)."""
    count = len(geometry.positions)
    vbo = gpu.types.GPUVertBuf(_vertex_format(), count)
    vbo.attr_fill("pos", np.ascontiguousarray(geometry.positions, np.float32))
    vbo.attr_fill("nor", np.ascontiguousarray(geometry.normals, np.float32))
    uvs = geometry.uvs if geometry.uvs is not None else np.zeros((count, 2), np.float32)
    tangents = geometry.tangents if geometry.tangents is not None else np.zeros((count, 4), np.float32)
    vbo.attr_fill("uv", np.ascontiguousarray(uvs, np.float32))
    vbo.attr_fill("tangent", np.ascontiguousarray(tangents, np.float32))
    batches = []
    for slot, first, n in geometry.ranges:
        if n == 0:
            continue
        triangles = np.ascontiguousarray(geometry.indices[first:first + n], np.int32).reshape(-1, 3)
        elements = gpu.types.GPUIndexBuf(type="TRIS", seq=triangles)
        batches.append((slot, gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=elements), (vbo, elements)))
    return batches


def triangle_texture(geometry: MeshGeometry, slot: int) -> gpu.types.GPUTexture:
    """The corners (object space) of the triangles of ``geometry``'s material ``slot``, in the order
    its batch draws them (``gl_PrimitiveID``), three RGBA32F texels a triangle,
    ``programs.TRIANGLE_ROW`` triangles a row: what a graph reading the fragment's triangle
    (Parametric, Wireframe) reads, 48 bytes a triangle. A zero texel where the range holds more rows
    than a texture has (its triangles' Parametric and Wireframe read 0)."""
    first, count = next(((a, n) for s, a, n in geometry.ranges if s == slot), (0, 0))
    n = count // 3
    row = programs.TRIANGLE_ROW
    rows = -(-n // row)
    if n == 0 or rows > gpu.capabilities.max_texture_size_get():
        return gpu.types.GPUTexture((1, 1), format="RGBA32F", data=gpu.types.Buffer("FLOAT", 4, [0.0] * 4))
    width = 3 * min(n, row)
    values = np.zeros((rows * width, 4), np.float32)
    corners = np.asarray(geometry.indices[first:first + count])
    values[:count, :3] = np.take(np.asarray(geometry.positions, np.float32), corners, axis=0)
    data = gpu.types.Buffer("FLOAT", values.size, values.ravel())
    return gpu.types.GPUTexture((width, rows), format="RGBA32F", data=data)


def image_texture(image: ImageData) -> gpu.types.GPUTexture:
    """The GPU copy of an image (bottom row first, as GPU textures are)."""
    h, w = image.pixels.shape[:2]
    values = image.pixels.astype(np.float32)
    if image.pixels.dtype == np.uint8:
        values /= 255.0  # the upload turns v back into the byte round(255 v)
    data = gpu.types.Buffer("FLOAT", w * h * 4, values.ravel())
    return gpu.types.GPUTexture((w, h), format=TEXTURE_FORMATS[image.storage], data=data)


#: The storage a UDIM image's array keeps when its tiles' differ: half floats beside floats are floats.
_WIDER = {"HALF": "FLOAT"}


def array_texture(tiles: tuple[ImageData | None, ...]) -> gpu.types.GPUTexture:
    """The GPU 2D array of a UDIM image's tiles, a layer each in order (bottom row first): the
    first readable tile's size and storage (a HALF tile beside FLOAT ones stored as FLOAT); a tile
    without pixels, or of another size or kind of storage, is a layer of
    ``gpu_library.MISSING_IMAGE`` (``extract`` says so)."""
    first = next((t for t in tiles if t is not None), None)
    if first is None:
        return gpu_library.missing_array_texture()
    storages = {t.storage for t in tiles if t is not None and t.size == first.size}
    storage = "FLOAT" if storages == {"HALF", "FLOAT"} else first.storage
    w, h = first.size
    missing = np.array(gpu_library.MISSING_IMAGE, np.float32)
    values = np.empty((len(tiles), h, w, 4), np.float32)
    for layer, tile in enumerate(tiles):
        if tile is None or tile.size != first.size or _WIDER.get(tile.storage, tile.storage) != \
                _WIDER.get(storage, storage):
            values[layer] = missing
        else:
            values[layer] = tile.pixels
            if tile.pixels.dtype == np.uint8:
                values[layer] /= 255.0  # the upload turns v back into the byte round(255 v)
    data = gpu.types.Buffer("FLOAT", values.size, values.ravel())
    return gpu.types.GPUTexture((w, h), layers=len(tiles), format=TEXTURE_FORMATS[storage], data=data)


def _graph_samplers(snapshot: Snapshot) -> set:
    """Every sampler the materials' node graphs bind (surfaces' and AOV Outputs'): image keys, and
    tuples of keys (a UDIM image's 2D array)."""
    graphs = [g for m in snapshot.materials.values() for g in [m.graph, *(a for _, a in m.aovs)]
              if g is not None]
    return {entry for g in graphs for entry in g.images}


@dataclass(slots=True)
class Draw:
    """One batch of one draw item: the item's order (cancellation is polled every 64 items), its
    object-data block and index, and its material."""

    order: int
    block: int
    index: int
    material: str
    batch: gpu.types.GPUBatch
    slot: int = 0  # the item's material slot the batch draws (its range of the mesh's triangles)


@dataclass
class DrawLists:
    """The draws of one view, grouped per shading program (sorted by defines): opaque surfaces,
    partly transparent ones (drawn by the depth-peeling program) and transmitting ones."""

    opaque: list[tuple[programs.Features, list[Draw]]]
    blended: list[tuple[programs.Features, list[Draw]]]
    #: the transmitting ones (a Transmission Weight, Glass and Refraction BSDFs), drawn over the
    #: opaque scene and the world, which they refract (passes.RefractionPass)
    refracted: list[tuple[programs.Features, list[Draw]]] = field(default_factory=list)


class _Block:
    """A uniform buffer and the bytes it holds; ``put`` uploads only different bytes."""

    def __init__(self):
        self.data: bytes | None = None
        self.ubo: gpu.types.GPUUniformBuf | None = None

    def put(self, data: bytes) -> bool:
        if data == self.data:
            return False
        if self.ubo is None or self.data is None or len(data) != len(self.data):
            self.ubo = gpu.types.GPUUniformBuf(data)
        else:
            self.ubo.update(data)
        self.data = data
        return True


class _RowTexture:
    """A float texture of rows (one per item, ``width`` texels each) and the bytes it holds;
    ``put`` makes a new texture only for different bytes (Python's textures take data only when
    made). Holds what a uniform block cannot: the lights, any number of them."""

    def __init__(self, channels: int = 4):
        self.data: bytes | None = None
        self.texture: gpu.types.GPUTexture | None = None
        self.channels = channels  # floats per texel: RGBA32F or RG32F

    def put(self, rows: np.ndarray) -> bool:
        data = np.ascontiguousarray(rows, np.float32)
        raw = data.tobytes()
        if raw == self.data:
            return False
        height, floats = data.shape
        buffer = gpu.types.Buffer("FLOAT", height * floats, data.ravel())
        self.texture = gpu.types.GPUTexture((floats // self.channels, height),
                                            format="RGBA32F" if self.channels == 4 else "RG32F", data=buffer)
        self.data = raw
        return True


def _stopped(draw: Draw, should_stop: Callable[[], bool] | None) -> bool:
    """Cancellation, polled every 64 draw items."""
    return should_stop is not None and draw.order % 64 == 0 and should_stop()


def _cull(culling: Callable[[Draw], str] | None, draw: Draw, mode: str | None) -> str | None:
    """Set the faces culled for ``draw`` where ``culling`` says and they differ from ``mode``
    (the last set); returns the mode now set."""
    if culling is None:
        return mode
    wanted = culling(draw)
    if wanted != mode:
        gpu.state.face_culling_set(wanted)
    return wanted


class SceneResources:
    def __init__(self):
        self.snapshot: Snapshot | None = None
        self.uploads: Counter = Counter()
        self._batches: dict[str, list[tuple[int, gpu.types.GPUBatch]]] = {}
        self._materials: dict[str, _Block] = {}
        self._graphs: dict[str, _Block] = {}  # node graphs' constants, per material
        self._aov_blocks: dict[tuple[str, str], _Block] = {}  # AOV Outputs' constants, per (material, AOV)
        # batches with a node graph's attributes: (geometry, slot, attributes) -> (the geometry
        # they were made from, batch, its attribute buffer)
        self._attribute_batches: dict[tuple, tuple] = {}
        # the triangles of graphs reading the fragment's triangle: (geometry, slot) -> (the
        # geometry they were made from, triangle_texture's)
        self._triangles: dict[tuple[str, int], tuple] = {}
        # the materials again as rows of one texture, for programs shading deferred (a pixel's
        # material is the G-buffer's row), and each material's row
        self._material_table = _RowTexture()
        self.material_rows: dict[str, int] = {}
        self._lights = _RowTexture()  # beyond what a uniform block holds
        self._light_block = _Block()  # where it holds them (programs.light_block_fits)
        self._light_tiles = _RowTexture(channels=2)  # light culling's tiles and lists (per view)
        self._tiles = None  # (what they were made from, the lists) of the last view's lists
        self._tiles_uploaded = False  # whether those are the lists on the GPU
        self._objects: list[_Block] = []
        self._frame = _Block()
        self._world_camera = _Block()
        self._world_lighting = _Block()
        self.environment = None  # the world's precomputed light (gpu_environment.EnvironmentPass)
        self._textures: dict[str, tuple[ImageData, gpu.types.GPUTexture]] = {}
        # UDIM images' tiles as 2D arrays: tile keys -> (the tiles' ImageData, the texture)
        self._arrays: dict[tuple[str, ...], tuple[tuple, gpu.types.GPUTexture]] = {}
        self._draw_lists: dict[tuple[str, bool, bool], DrawLists] = {}
        # programs and tables drawn with, held for this scene's lifetime (see gpu_library)
        self._programs: dict[programs.Features, gpu.types.GPUShader] = {}
        self._bounds: dict[str, np.ndarray] = {}  # object-space (min, max) per geometry
        self._geometry_version: Counter = Counter()  # uploads per geometry key
        self._digests: dict[str, bytes] = {}  # geometry_digest's, until the geometry is uploaded again
        self._shadows = _Block()
        self.shadow_plan: shadows.ShadowPlan | None = None
        self.caster_key: bytes = b""  # what the shadow maps saw: casters' geometry and matrices
        self.shadow_maps = None  # the 2D-array depth texture (passes.ShadowPass)
        self._coverage_key = None  # (snapshot, casters, coverage_key's) of the last snapshot asked
        self._coverage_frame = None  # (snapshot, the scene camera's frame block): draw_coverage's
        # the lights in the order the programs loop over them, by group, and where each group
        # ends (programs.light_order)
        self.lights: list = []
        self.light_group_ends: tuple[int, ...] = ()
        # programs.uses_light_tiles, with the scene's bounds: whether the views' tiles are made
        # (each view then shades through them where they pay: culls)
        self.light_culling = False
        # their centres and reaches, as light culling's tiles read them (None: no culling)
        self._reach: tuple[np.ndarray, np.ndarray] | None = None

    # --- keeping the GPU copy up to date ------------------------------------------------------

    def sync(self, snapshot: Snapshot, keep: Callable[[str], bool] | None = None) -> None:
        """Upload what ``snapshot`` has that the GPU copy lacks or holds differently; drop what
        it no longer has. ``keep(key)`` False forces a geometry to be uploaded again."""
        self.snapshot = snapshot
        self.uploads = Counter()
        self._draw_lists.clear()
        for key in list(self._batches):
            if key not in snapshot.geometries or (keep is not None and not keep(key)):
                del self._batches[key]
                self._bounds.pop(key, None)
                self._digests.pop(key, None)
        for key, geometry in snapshot.geometries.items():
            if key not in self._batches:
                self._batches[key] = upload_geometry(geometry)
                self._bounds[key] = geometry.bounds
                self._geometry_version[key] += 1
                self._digests.pop(key, None)
                self.uploads["geometry"] += 1
        for held_by in (self._attribute_batches, self._triangles):
            for key, held in list(held_by.items()):
                if snapshot.geometries.get(key[0]) is not held[0]:  # a geometry read anew, or gone
                    del held_by[key]
        for key in set(self._materials) - set(snapshot.materials):
            del self._materials[key]
        for key in set(self._graphs) - {k for k, m in snapshot.materials.items() if m.graph is not None}:
            del self._graphs[key]
        wanted = {(key, name) for key, m in snapshot.materials.items() for name, _ in m.aovs
                  if any(name == aov for aov, _ in snapshot.aovs)}
        for key in set(self._aov_blocks) - wanted:
            del self._aov_blocks[key]
        for key, name in wanted:
            graph = dict(snapshot.materials[key].aovs)[name]
            block = self._aov_blocks.setdefault((key, name), _Block())
            self.uploads["graph constants"] += block.put(np.asarray(graph.constants, np.float32).tobytes())
        for key, material in snapshot.materials.items():
            block = self._materials.setdefault(key, _Block())
            self.uploads["materials"] += block.put(programs.pack_material(material))
            if material.graph is not None:
                graph = self._graphs.setdefault(key, _Block())
                self.uploads["graph constants"] += graph.put(np.ascontiguousarray(material.graph.constants,
                                                                                  np.float32).tobytes())
        self.material_rows = {key: row for row, key in enumerate(snapshot.materials)}
        if snapshot.materials:
            self._material_table.put(np.stack([np.frombuffer(self._materials[key].data, np.float32)
                                               for key in snapshot.materials]))
        self._sync_shadows(snapshot)  # before the lights: they name their first shadow layer
        slots = programs.light_slots(len(snapshot.lights))
        first = self.shadow_plan.first_layer
        order, self.light_group_ends = programs.light_order(snapshot.lights, first)
        self.lights = [snapshot.lights[i] for i in order]
        self._reach = None
        box = self.shadow_plan.box if self.shadow_plan.box is not None else (
            shadows.scene_bounds(snapshot, self._bounds) if snapshot.settings.light_culling and any(
                math.isfinite(light.influence) for light in snapshot.lights) else None)
        self.light_culling = programs.uses_light_tiles(snapshot, box)
        if self.light_culling:  # made once here: every pass of every view asks
            self._reach = (np.array([light.position for light in self.lights], np.float64).reshape(-1, 3),
                           np.array([light.influence for light in self.lights], np.float64))
        lights = programs.pack_lights(self.lights, slots, [first[i] for i in order])
        if programs.light_block_fits(slots):  # the one or the other, the other dropped
            self.uploads["lights"] += self._light_block.put(lights.tobytes())
            if self._lights.texture is not None:
                self._lights = _RowTexture()
        else:
            self.uploads["lights"] += self._lights.put(lights)
            if self._light_block.ubo is not None:
                self._light_block = _Block()
        blocks = programs.pack_objects(snapshot.items)
        del self._objects[len(blocks):]
        while len(self._objects) < len(blocks):
            self._objects.append(_Block())
        for block, data in zip(self._objects, blocks):
            self.uploads["objects"] += block.put(data.tobytes())
        if World.images(snapshot.world.camera):  # a constant world is only a clear colour
            self.uploads["world"] += self._world_camera.put(programs.pack_world(snapshot.world.camera))
        else:
            self._world_camera = _Block()
        if World.images(snapshot.world.lighting):  # baked into the environment maps
            lighting = programs.pack_world(snapshot.world.lighting, snapshot.world.threshold)
            self.uploads["world"] += self._world_lighting.put(lighting)
        else:
            self._world_lighting = _Block()
        for key in set(self._textures) - set(snapshot.images):
            del self._textures[key]
        samplers = _graph_samplers(snapshot)
        arrays = {entry for entry in samplers if isinstance(entry, tuple)}
        layers_only = {key for entry in arrays for key in entry} - samplers  # uploaded in arrays alone
        for key, image in snapshot.images.items():
            if key in layers_only:
                self._textures.pop(key, None)
                continue
            held = self._textures.get(key)
            if held is None or held[0] is not image:
                texture, uploaded = gpu_library.LIBRARY.image_texture(image, image_texture)
                self._textures[key] = (image, texture)
                if uploaded:
                    self.uploads["textures"] += 1
        for keys in set(self._arrays) - arrays:
            del self._arrays[keys]
        for keys in arrays:  # a UDIM image's tiles: one 2D array, made again when a tile is read again
            tiles = tuple(snapshot.images.get(key) for key in keys)
            held = self._arrays.get(keys)
            if held is None or any(a is not b for a, b in zip(held[0], tiles)):
                self._arrays[keys] = (tiles, array_texture(tiles))
                self.uploads["textures"] += 1

    def _sync_shadows(self, snapshot: Snapshot) -> None:
        plan = self.shadow_plan = shadows.plan(snapshot, self._bounds)
        if not plan.layers:
            self._shadows = _Block()
            self.caster_key = b""
            return
        block = programs.pack_shadows(plan, programs.light_slots(plan.layers))
        self.uploads["shadows"] += self._shadows.put(block)
        casters = [(item.geometry, self._geometry_version[item.geometry], item.matrix.tobytes())
                   for item in snapshot.items if item.casts_shadow]
        self.caster_key = repr(casters).encode()

    def geometry_digest(self, key: str) -> bytes:
        """A digest of the uploaded geometry ``key``'s positions, triangles, material ranges and
        winding: equal for equal content, whichever render read it (blake2b, ~1 ms per 10^6 bytes)."""
        digest = self._digests.get(key)
        if digest is None:
            geometry = self.snapshot.geometries[key]
            h = hashlib.blake2b(digest_size=16)
            h.update(np.ascontiguousarray(geometry.positions, np.float32))
            h.update(np.ascontiguousarray(geometry.indices, np.int32))
            h.update(repr((geometry.ranges, geometry.winding)).encode())
            digest = self._digests[key] = h.digest()
        return digest

    def shadow_content_key(self, casters: list[Draw], drawing: tuple = ()) -> bytes:
        """What the shadow maps hold once drawn for ``casters``, by content rather than by upload
        (``caster_key``): the plan's layers, every item's geometry (``geometry_digest``), matrix,
        Cast Shadow and materials per slot (each item's box decides which casters a layer leaves
        out; a slot's material whether its triangles cast), the caster draws, and ``drawing`` (what
        else the shadow pass draws by: its switches, the lights' extents). Two renderers' keys are
        equal where their maps would be: a final render with Persistent Data keeps the maps a render
        of the same content left (passes.ShadowPass). Reads every mesh once per upload (blake2b,
        ~1 ms per 10^6 bytes of positions and triangles)."""
        h = hashlib.blake2b(digest_size=16)
        h.update(self.shadow_plan.key())
        for item in self.snapshot.items:
            h.update(self.geometry_digest(item.geometry) if item.geometry in self._batches else b"-")
            h.update(np.ascontiguousarray(item.matrix, np.float64))
            h.update(b"c" if item.casts_shadow else b"-")
            h.update(repr(item.materials).encode())  # which slot each caster draw is
        h.update(repr(([(draw.order, draw.material) for draw in casters], drawing)).encode())
        return h.digest()

    def handedness(self, draws: list[Draw]) -> np.ndarray:
        """Per draw, the sign of its item's matrix's determinant: -1 where it mirrors (turning its
        triangles' winding), 0 where it flattens."""
        if not draws:
            return np.zeros(0, np.int8)
        items = self.snapshot.items
        m = np.stack([items[d.order].matrix[:3, :3] for d in draws])
        return np.sign(matrices.determinant3(m)).astype(np.int8)

    def caster_facing(self, casters: list[Draw]) -> np.ndarray:
        """Per caster draw: +1 where its item is a closed surface facing out as drawn (the mesh's
        ``winding`` times the sign of its matrix's determinant: a mirror turns its faces), -1
        facing in, 0 where some face of the item is not among ``casters`` or is partly covering
        (``covering``: the rest is seen through it) or its mesh is open."""
        items, geometries = self.snapshot.items, self.snapshot.geometries
        # a partly covering slot (drawn by its coverage) leaves holes: the item is open
        drawn = Counter(draw.order for draw in casters if not self.covering(draw))
        out = self.handedness(casters)
        for i, draw in enumerate(casters):
            item = items[draw.order]
            geometry = geometries.get(item.geometry)
            whole = geometry is not None and drawn[draw.order] == len(self._batches[item.geometry])
            out[i] *= geometry.winding if whole else 0
        return out

    def view_facing(self, draws: list[Draw], view_projection) -> np.ndarray:
        """Per draw, as ``caster_facing`` (+1 closed facing out, -1 in, 0 open), where the item's
        bounding sphere lies wholly beyond the view's near plane (``view_projection``: world ->
        clip), else 0: every ray of the view then enters the closed surface from outside, so its
        nearest face along each faces the viewer and its other faces are hidden behind that one.
        ``draws``: every opaque draw of the view (an item's slots are whole only together)."""
        facing = self.caster_facing(draws)
        if not facing.any():
            return facing
        m = np.asarray(view_projection, np.float64)
        plane = m[3] + m[2]  # clip w + z >= 0: on the near plane's far side
        length = float(np.linalg.norm(plane[:3]))
        if not np.isfinite(length) or length <= 0.0:
            return np.zeros_like(facing)
        spheres = self.caster_spheres(draws)
        beyond = (spheres[:, :3] @ plane[:3] + plane[3]) / length > spheres[:, 3] * 1.001 + 1e-6
        return np.where(beyond, facing, 0).astype(np.int8)

    def shadow_casters(self, covering: bool = True) -> list[Draw]:
        """The draws of the items that cast shadows: the opaque and transmitting ones (glass casts a
        whole shadow, as Cycles' shadow rays stop at it), then (``covering``) the
        partly covering ones (``covering``), which the shadow pass draws by their coverage
        (``draw_coverage``); without, partly covering surfaces cast nothing."""
        items = self.snapshot.items
        lists = self.draw_lists(None, False)
        groups = (lists.opaque, lists.refracted) + ((lists.blended,) if covering else ())
        return [draw for group in groups for _features, draws in group for draw in draws
                if items[draw.order].casts_shadow]

    def covering(self, draw: Draw) -> bool:
        """Whether ``draw``'s surface can cover less than all of a texel (drawn blended): its
        material's Alpha under 1, or its compiled graph's coverage (``MaterialGraph.transparent``)."""
        material = self.snapshot.materials[draw.material]
        return material.alpha < 1.0 or (material.graph is not None and material.graph.transparent)

    def coverage_key(self, casters: list[Draw]) -> bytes:
        """What the partly covering ``casters``' coverage depends on beyond their geometry and
        matrices: each one's graph (structure, constants, images and their pixels' revisions,
        attributes) or Alpha, and what a graph reads of its object (texture space, colour, Object
        Info). Equal keys: equal coverage, the maps kept. Worked out once per snapshot."""
        held = self._coverage_key
        if held is not None and held[0] is self.snapshot and held[1] == len(casters):
            return held[2]
        snapshot = self.snapshot
        h = hashlib.blake2b(digest_size=16)
        for draw in casters:
            if not self.covering(draw):
                continue
            material, item = snapshot.materials[draw.material], snapshot.items[draw.order]
            graph = material.graph
            h.update(repr((draw.order, draw.material, material.alpha)).encode())
            if graph is not None:
                h.update(graph.program.key.encode())
                h.update(np.ascontiguousarray(graph.constants, np.float32).tobytes())
                revisions = [(key, snapshot.images[key].revision if key in snapshot.images else -1)
                             for key in graph.images]
                h.update(repr((revisions, graph.attributes, item.texspace, item.color, item.pass_index,
                               material.pass_index, item.random)).encode())
        key = h.digest()
        self._coverage_key = (snapshot, len(casters), key)
        return key

    def draw_coverage(self, draws: list[Draw], shader, graph) -> None:
        """Draw partly covering casters (``covering``) of one coverage program
        (``gpu_library.shadow_coverage_program``: ``graph`` their compiled graphs' structure, None
        their materials' Alpha) into the bound shadow layer, ``shader`` bound with its layer's
        uniforms: per draw its object and its graph's constants and images, or its Alpha. A graph
        reading the view (Window, Camera) reads the scene camera's (as Cycles' shadow rays do)."""
        materials = self.snapshot.materials
        if graph is not None and graph.uses & gpu_library.shadow_frame_fields():
            held = self._coverage_frame
            if held is None or held[0] is not self.snapshot:
                block = _Block()
                block.put(programs.pack_frame(self.snapshot, None, None, self.light_group_ends))
                held = self._coverage_frame = (self.snapshot, block)
            shader.uniform_block("frame", held[1].ubo)
        pushed = gpu_library.graph_push_constants(graph) if graph is not None else ()
        block = -1
        for draw in draws:
            block = self._bind_object(shader, draw, block)
            material = materials[draw.material]
            if graph is None:
                shader.uniform_float("shadow_alpha", min(max(float(material.alpha), 0.0), 1.0))
            else:
                self._bind_graph(shader, draw, material.graph, pushed, self._graphs[draw.material])
            draw.batch.draw(shader)

    def caster_spheres(self, draws: list[Draw]) -> np.ndarray:
        """(n, 4) world-space bounding spheres of ``draws``' items (``shadows.bounding_spheres``)."""
        items = self.snapshot.items
        if not draws:
            return np.zeros((0, 4))
        boxes = np.stack([self._bounds[items[d.order].geometry] for d in draws])
        return shadows.bounding_spheres(boxes, np.stack([items[d.order].matrix for d in draws]))

    def shadowless_casters(self, draws: list[Draw]) -> np.ndarray:
        """(layers, n): which of ``draws`` (casters) can shadow nothing in each layer of the shadow
        plan (``shadows.shadowless_casters``: a flat caster with the light on one side and every
        object on that side), against every item's box."""
        items = self.snapshot.items
        plan = self.shadow_plan
        if not draws or plan is None:
            return np.zeros((0 if plan is None else plan.layers, len(draws)), bool)
        boxes = np.stack([self._bounds[items[d.order].geometry] for d in draws])
        planes = shadows.flat_planes(boxes, np.stack([items[d.order].matrix for d in draws]))
        if np.isnan(planes[:, 0]).all():
            return np.zeros((plan.layers, len(draws)), bool)
        held = [item for item in items if item.geometry in self._bounds]
        world = shadows.world_corners(np.stack([self._bounds[item.geometry] for item in held]),
                                      np.stack([item.matrix for item in held]))
        return shadows.shadowless_casters(plan, self.snapshot.lights, planes, world)

    def put_frame(self, view_projection: np.ndarray | None, width: int, height: int,
                  samples: int = 1) -> None:
        """The frame block for a view (the camera's, unless the viewport passes its own) of
        ``width`` x ``height`` pixels at ``samples`` x ``samples``, and its light tiles where they
        pay (``tile_lists``)."""
        tiles = self.tile_lists(view_projection, width, height, samples)
        self.uploads["frame"] += self._frame.put(programs.pack_frame(self.snapshot, view_projection, tiles,
                                                                     self.light_group_ends,
                                                                     (width * samples, height * samples),
                                                                     samples))

    def _view_tiles(self, view_projection: np.ndarray | None, width: int, height: int,
                    samples: int) -> light_tiles.TileLists | None:
        """The view's light tiles, made where the scene's lights allow culling
        (``programs.uses_light_tiles``), else None."""
        if self._reach is None:
            return None
        centres, radii = self._reach
        vp = self.snapshot.camera.view_projection if view_projection is None else view_projection
        # the passes of one view ask again (the occlusion's and the opaque pass's): the lists
        # are the last ones' while lights, view and size are (~1 ms of numpy for 2 lights at
        # 640 x 360 on this machine, ~7 ms for 3 with their sphere tests)
        key = (centres.tobytes(), radii.tobytes(), np.asarray(vp, np.float64).tobytes(), width, height,
               samples)
        if self._tiles is None or self._tiles[0] != key:
            self._tiles = (key, light_tiles.tile_lists(centres, radii, vp, width * samples, height * samples,
                                                       light_tiles.TILE * samples))
            self._tiles_uploaded = False
        return self._tiles[1]

    def culls(self, view_projection: np.ndarray | None, width: int, height: int, samples: int = 1) -> bool:
        """Whether the view's surfaces are shaded through light culling's tile lists: where the
        scene's lights allow it and the view's lists leave out enough of them to pay
        (``light_tiles.lists_pay``). Per view: a viewport turning away from a light's reach may
        switch its programs (each variant compiled once)."""
        tiles = self._view_tiles(view_projection, width, height, samples)
        return tiles is not None and light_tiles.lists_pay(tiles, len(self.lights))

    def tile_lists(self, view_projection: np.ndarray | None, width: int, height: int,
                   samples: int = 1) -> light_tiles.TileLists | None:
        """The view's light tiles (uploaded) where they pay (``culls``), else None."""
        if not self.culls(view_projection, width, height, samples):
            return None
        if not self._tiles_uploaded:
            texels = self._tiles[1].texels()
            self.uploads["light tiles"] += self._light_tiles.put(texels.reshape(len(texels), -1))
            self._tiles_uploaded = True
        return self._tiles[1]

    def lights_per_pixel(self, view_projection: np.ndarray | None, width: int, height: int,
                         samples: int = 1) -> float:
        """How many lights a pixel of the view evaluates, on average: its tile's with light
        culling, else every light."""
        tiles = self.tile_lists(view_projection, width, height, samples)
        if tiles is None:
            return float(len(self.lights))
        return tiles.mean_listed

    @property
    def geometry_count(self) -> int:
        return len(self._batches)

    def bind_world(self, shader, terms, lighting: bool = False) -> None:
        """The world block and environment images of ``terms``, the camera's field or (with
        ``lighting``) the lighting one."""
        shader.uniform_block("world", (self._world_lighting if lighting else self._world_camera).ubo)
        for i, term in enumerate(World.images(terms)[:MAX_ENVIRONMENT_IMAGES]):
            gpu_library.bind_sampler(shader, f"env_image_{i}", self._textures[term.image.key][1])

    # --- drawing ------------------------------------------------------------------------------

    def draw_lists(self, model: str | None, half_target: bool, light_culling: bool = False) -> DrawLists:
        """Every batch of every item, grouped by the program its material needs in ``model``
        (a material's own model wins), shading through light culling's tile lists or not (the
        view's ``culls``); made once per sync and view kind."""
        view_kind = (model, half_target, light_culling)
        lists = self._draw_lists.get(view_kind)
        if lists is not None:
            return lists
        snapshot = self.snapshot
        plan = self.shadow_plan  # planned once per sync, not counted again per material
        features = {key: programs.Features.from_snapshot(snapshot, model=model, material=m,
                                                         half_target=half_target, shadow_layers=plan.layers,
                                                         first_layer=plan.first_layer,
                                                         light_culling=light_culling)
                    for key, m in snapshot.materials.items()}
        opaque: dict[programs.Features, list[Draw]] = {}
        blended: dict[programs.Features, list[Draw]] = {}
        refracted: dict[programs.Features, list[Draw]] = {}
        block_size = programs.OBJECT_BLOCK
        for order, item in enumerate(snapshot.items):
            for slot, batch, parts in self._batches.get(item.geometry, ()):
                key = item.materials[slot] if slot < len(item.materials) else item.materials[-1]
                material = snapshot.materials[key]
                if material.graph is not None and material.graph.attributes:
                    batch = self._attribute_batch(item.geometry, slot, parts, material.graph.attributes)
                draw = Draw(order, order // block_size, order % block_size, key, batch, slot)
                if "TRANSMISSION" in features[key].lobes:
                    # a glass, partly transparent too: its transparent part is what lies behind it
                    # unrefracted, which the refraction pass has (glsl/mesh.frag.glsl)
                    refracted.setdefault(features[key], []).append(draw)
                elif material.alpha < 1.0 or (material.graph is not None and material.graph.transparent):
                    blended.setdefault(replace(features[key], peel=True, occlusion=False), []).append(draw)
                else:
                    opaque.setdefault(features[key], []).append(draw)

        def ordered(groups):
            return sorted(groups.items(), key=lambda kv: kv[0].defines())

        lists = self._draw_lists[view_kind] = DrawLists(ordered(opaque), ordered(blended), ordered(refracted))
        return lists

    def _attribute_batch(self, key: str, slot: int, parts: tuple, attributes: tuple) -> gpu.types.GPUBatch:
        """The batch of ``key``'s ``slot`` with a node graph's ``attributes`` beside the mesh's own
        (made once per geometry upload)."""
        geometry = self.snapshot.geometries[key]
        held = self._attribute_batches.get((key, slot, attributes))
        if held is not None and held[0] is geometry:
            return held[1]
        vbo, elements = parts
        extra = attribute_buffer(geometry, attributes)
        batch = gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=elements)
        batch.vertbuf_add(extra)
        self._attribute_batches[(key, slot, attributes)] = (geometry, batch, extra)
        self.uploads["attributes"] += 1
        return batch

    def _triangle_texture(self, draw: Draw) -> gpu.types.GPUTexture:
        """``triangle_texture`` of ``draw``'s geometry and slot (made once per geometry upload)."""
        key = (self.snapshot.items[draw.order].geometry, draw.slot)
        geometry = self.snapshot.geometries[key[0]]
        held = self._triangles.get(key)
        if held is None or held[0] is not geometry:
            held = self._triangles[key] = (geometry, triangle_texture(geometry, draw.slot))
            self.uploads["triangles"] += 1
        return held[1]

    def program(self, features: programs.Features) -> gpu.types.GPUShader:
        shader = self._programs.get(features)
        if shader is None:
            shader = self._programs[features] = gpu_library.shading_program(features)
        return shader

    def _bind_program(self, features: programs.Features, lobes,
                      bind: Callable[[gpu.types.GPUShader], None] | None) -> gpu.types.GPUShader:
        """Bind ``features``' program and what every draw of it reads."""
        shader = self.program(features)
        shader.bind()
        shader.uniform_block("frame", self._frame.ubo)
        if features.light_block:
            shader.uniform_block("light_block", self._light_block.ubo)
        else:
            gpu_library.bind_sampler(shader, "light_data", self._lights.texture)
        if features.light_tiles:
            gpu_library.bind_sampler(shader, "light_tiles", self._light_tiles.texture)
        try:
            shader.uniform_float("lobes", lobes)
        except ValueError:  # the compiler removed it: a surface giving no light (a Holdout)
            pass
        if features.uses_albedo_table:
            gpu_library.bind_sampler(shader, "ms_table",
                                     gpu_library.albedo_table(features.terms, "GLOSSY" in features.lobes))
        if features.uses_s_table:
            gpu_library.bind_sampler(shader, "s_table", gpu_library.s_table())
        if features.uses_sheen_table:
            gpu_library.bind_sampler(shader, "sheen_table", gpu_library.sheen_table())
        if features.uses_thin_film_table:
            gpu_library.bind_sampler(shader, "thin_film_table", gpu_library.thin_film_table())
        if features.uses_subsurface_table:
            gpu_library.bind_sampler(shader, "subsurface_table", gpu_library.subsurface_table())
        if features.uses_ltc:
            gpu_library.bind_sampler(shader, "ltc_table", gpu_library.ltc_table(features.terms))
        if features.environment:
            shader.uniform_block("env", self.environment.block)
            if features.uses_split_table:
                gpu_library.bind_sampler(shader, "split_table", gpu_library.split_table(features.terms))
            if features.environment == "MAP":
                gpu_library.bind_sampler(shader, "env_atlas", self.environment.atlas)
                if features.uses_env_chain:
                    gpu_library.bind_sampler(shader, "env_chain", self.environment.chain)
                    gpu_library.bind_sampler(shader, "env_chain_clamped", self.environment.clamped_chain)
                    shader.uniform_block("chain", self.environment.chain_block)
        if features.shadow_layers:
            shader.uniform_block("shadow", self._shadows.ubo)
            gpu_library.bind_sampler(shader, "shadow_maps", self.shadow_maps)
        if bind is not None:
            bind(shader)
        return shader

    def draw_group(self, features: programs.Features, draws: list[Draw], lobes,
                   should_stop: Callable[[], bool] | None = None,
                   bind: Callable[[gpu.types.GPUShader], None] | None = None,
                   culling: Callable[[Draw], str] | None = None) -> bool:
        """Draw ``draws`` (one feature set's) into the bound framebuffer; False if cancelled.
        ``culling``: the faces the rasteriser drops per draw (the state is left at the last
        draw's: callers restore it)."""
        shader = self._bind_program(features, lobes, bind)
        materials = self.snapshot.materials
        pushed = gpu_library.graph_push_constants(features.graph) if features.graph is not None else ()
        block = -1
        mode = None
        for draw in draws:
            if _stopped(draw, should_stop):
                return False
            mode = _cull(culling, draw, mode)
            block = self._bind_object(shader, draw, block)
            shader.uniform_block("material", self._materials[draw.material].ubo)
            if features.graph is not None:
                self._bind_graph(shader, draw, materials[draw.material].graph, pushed,
                                 self._graphs[draw.material])
            draw.batch.draw(shader)
        return True

    def _bind_graph(self, shader, draw: Draw, graph, pushed: tuple[str, ...], block: _Block) -> None:
        """A node graph's constants (``block``) and images, and what it reads of the draw's object."""
        shader.uniform_block("graph", block.ubo)
        for k, image in enumerate(graph.images):
            if isinstance(image, tuple):  # a UDIM image's tiles
                held = self._arrays.get(image)
                texture = held[1] if held is not None else gpu_library.missing_array_texture()
            else:
                held = self._textures.get(image)
                texture = held[1] if held is not None else gpu_library.missing_texture()
            gpu_library.bind_sampler(shader, f"graph_image_{k}", texture)
        if "triangle" in graph.program.uses:
            gpu_library.bind_sampler(shader, "graph_triangles", self._triangle_texture(draw))
        if pushed:
            item = self.snapshot.items[draw.order]
            material = self.snapshot.materials[draw.material]
            values = {"graph_texspace": (*item.texspace[0], 0.0),
                      # a flat mesh's texture space has a size of 0 along its normal: 1 there
                      "graph_texspace_size": (*(s if abs(s) > 1e-12 else 1.0 for s in item.texspace[1]), 0.0),
                      "graph_object_color": item.color,
                      "graph_object_info": (float(item.pass_index), float(material.pass_index), item.random,
                                            0.0)}
            for k, attribute in enumerate(getattr(graph, "uniform_attributes", ())):
                values[f"graph_uniform_attribute{k}"] = item.attributes.get(attribute, (0.0, 0.0, 0.0, 0.0))
            for name in pushed:
                try:
                    shader.uniform_float(name, values[name])
                except ValueError:  # the compiler removed it: an output that no input reads
                    pass

    def draw_aov(self, name: str, value: bool) -> None:
        """Every item into the bound target (depth-tested: the nearest surface's) with the program
        of its material's AOV Output ``name`` (``gpu_library.aov_program``), or zeros where its
        material has none."""
        snapshot = self.snapshot
        zero = None
        groups: dict = {}
        for order, item in enumerate(snapshot.items):
            for slot, batch, parts in self._batches.get(item.geometry, ()):
                key = item.materials[slot] if slot < len(item.materials) else item.materials[-1]
                graph = dict(snapshot.materials[key].aovs).get(name)
                if graph is not None and graph.attributes:
                    batch = self._attribute_batch(item.geometry, slot, parts, graph.attributes)
                block, index = divmod(order, programs.OBJECT_BLOCK)
                draw = Draw(order, block, index, key, batch, slot)
                program = graph.program if graph is not None else programs.ZERO_AOV
                groups.setdefault(program, []).append((draw, graph))
        for program, draws in groups.items():
            shader = gpu_library.aov_program(program, value)
            shader.bind()
            shader.uniform_block("frame", self._frame.ubo)
            pushed = gpu_library.graph_push_constants(program)
            block = -1
            for draw, graph in draws:
                block = self._bind_object(shader, draw, block)
                if graph is None:
                    if zero is None:
                        zero = _Block()
                        zero.put(bytes(16))
                    shader.uniform_block("graph", zero.ubo)
                else:
                    self._bind_graph(shader, draw, graph, pushed, self._aov_blocks[(draw.material, name)])
                draw.batch.draw(shader)

    def _bind_object(self, shader, draw: Draw, block: int) -> int:
        """Bind ``draw``'s object: its block of objects (unless ``block``, the one bound, holds it)
        and its index there; returns the block bound."""
        if draw.block != block:
            shader.uniform_block("objects", self._objects[draw.block].ubo)
        shader.uniform_int("object_index", draw.index)
        return draw.block

    def draw_gbuffer(self, groups: list[tuple[int, list[Draw]]],
                     should_stop: Callable[[], bool] | None = None,
                     culling: Callable[[Draw], str] | None = None) -> bool:
        """Draw each (group, draws) into the bound G-buffer (glsl/gbuffer.frag.glsl): group -1 for
        surfaces shaded forward; False if cancelled. ``culling`` as ``draw_group``'s."""
        shader = gpu_library.gbuffer_program()
        shader.bind()
        shader.uniform_block("frame", self._frame.ubo)
        block = -1
        mode = None
        for group, draws in groups:
            for draw in draws:
                if _stopped(draw, should_stop):
                    return False
                mode = _cull(culling, draw, mode)
                block = self._bind_object(shader, draw, block)
                shader.uniform_int("gbuffer", (self.material_rows[draw.material], group))
                draw.batch.draw(shader)
        return True

    def shade_deferred(self, features: programs.Features, group: int, lobes, gbuffer,
                       full_screen: gpu.types.GPUBatch,
                       bind: Callable[[gpu.types.GPUShader], None] | None = None) -> None:
        """Shade the G-buffer's pixels of ``group`` with ``features``' deferred program into the
        bound framebuffer. ``gbuffer``: the position and normal textures, and the face's with shadows."""
        shader = self._bind_program(features, lobes, bind)
        gpu_library.bind_sampler(shader, "material_table", self._material_table.texture)
        gpu_library.bind_sampler(shader, "gbuffer_position", gbuffer[0])
        gpu_library.bind_sampler(shader, "gbuffer_normal", gbuffer[1])
        if features.shadow_layers:
            gpu_library.bind_sampler(shader, "gbuffer_face", gbuffer[2])
        shader.uniform_int("deferred_group", group)
        full_screen.draw(shader)

    def draw_positions(self, draws: list[Draw], shader, frame_block: bool = True,
                       culling: list[str] | None = None) -> None:
        """Draw ``draws`` with a program that needs only positions and normals (the prepass), or
        (``frame_block`` False) positions under its own projection (a shadow map). ``culling``:
        per draw, the faces the rasteriser drops ("NONE", "BACK", "FRONT"), drawn a mode at a time
        (the state is left at the last mode: callers restore it)."""
        if culling is not None:
            for mode in ("NONE", "BACK", "FRONT"):
                group = [d for d, m in zip(draws, culling) if m == mode]
                if group:
                    gpu.state.face_culling_set(mode)
                    self.draw_positions(group, shader, frame_block)
            return
        shader.bind()
        if frame_block:
            shader.uniform_block("frame", self._frame.ubo)
        block = -1
        for draw in draws:
            block = self._bind_object(shader, draw, block)
            draw.batch.draw(shader)

    def free(self) -> None:
        """Drop every GPU object (Blender frees each with its last reference)."""
        self._batches.clear()
        self._digests.clear()
        self._materials.clear()
        self._graphs.clear()
        self._aov_blocks.clear()
        self._attribute_batches.clear()
        self._triangles.clear()
        self._objects.clear()
        self._textures.clear()
        self._arrays.clear()
        self._draw_lists.clear()
        self._programs.clear()
        self._lights = _RowTexture()
        self._light_block = _Block()
        self._material_table = _RowTexture()
        self.material_rows = {}
        self._light_tiles = _RowTexture(channels=2)
        self._tiles = None
        self._reach = None
        self._frame = _Block()
        self._world_camera = _Block()
        self._world_lighting = _Block()
        self._shadows = _Block()
        self._bounds.clear()
        self.shadow_plan = None
        self.shadow_maps = None
        self._coverage_key = self._coverage_frame = None
        self.environment = None
        self.snapshot = None

