"""The baked fallback (issue #52): what the material compiler cannot compile, Cycles bakes.

An output of a node that does not compile, read by nodes that do (``materials.bake.BakeTarget``),
is baked by Cycles into a float image on the object's UV map: the socket's value wired into an
Emission shader and baked as *Emit*, as Blender's own bakes are (Cycles' bake kernel shades each
texel's centre along the surface normal, kernel/integrator/init_from_bake.h). The compiled graph
samples that image at the UV in its place (``surface.with_bakes``).

**Where a bake runs.** ``bpy.ops.object.bake`` runs on the main thread only, never inside a
draw callback or a depsgraph update: it adds data to the file while it works (a scene, an object,
a material, an image, all removed after) and marks Blender as rendering. So a bake runs

* in a final render on the main thread -- ``blender -b`` batch renders, ``bpy.ops.render.render()``
  from a script -- inside ``render()`` before it draws, with progress (``engine``);
* before F12 and Ctrl+F12 (``operators.SHADINGLAB_OT_render``, on those keys with this engine):
  renders that only bake, on the main thread, a share of the current frame's bakes each, between
  which the interface shows the progress; then Blender's own render, which finds them here;
* for the viewport, in a timer on the main thread after the viewport asked (``schedule``); the
  viewport draws the socket's value meanwhile and says so;
* never in a render Blender runs on a job thread (F12's render itself, an animation's frames,
  material previews): those take what earlier bakes left in the cache, else the socket's value
  and a message.

**What is kept.** Baked pixels live in memory (``CACHE``), by the subgraph's content, the mesh
(its positions, normals, UV map, triangles and texture space), the resolution and, where the
subgraph reads it, the object's placement: nothing is saved into the file, so a bake changes
nothing of it. A change of any of them bakes again; nothing else does.

**What a bake costs and how far it is off.** Each bake is measured when made: a second bake half
a texel over puts Cycles' values at the corners between four texel centres, where the bilinear
reconstruction is farthest from the texels; ``Baked.error`` is the largest and mean difference
there (``materials.bake.interpolation_error``).
"""

from __future__ import annotations

import hashlib
import itertools
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass

import bpy
import numpy as np

from ..materials import bake as baking
from ..scene import snapshot as S
from . import orco

#: The bake's resolution where the scene gives none (Render properties > Shading Lab > Bake).
RESOLUTION = 512
#: Texels a bake extends past its UV islands (Blender's Extend margin): the bilinear sampling of a
#: texel centre at an island's edge reads one texel beyond.
MARGIN = 4
#: The bytes of baked pixels kept (float RGBA: 4 MiB per 512 x 512 bake); the least recently
#: used go first.
BUDGET = 512 << 20
#: The name of the data a bake makes while it works (removed after).
_TEMPORARY = "Shading Lab bake"


@dataclass(frozen=True)
class Baked:
    """One bake: its pixels (``image``: float RGBA, bottom row first, its key the cache's), its
    resolution, its measured error (``materials.bake.BakeError``), the seconds it took (both
    bakes), what it stands for (``label``: "Material > Node > Output") and a ``note``."""

    image: S.ImageData
    resolution: int
    error: baking.BakeError
    seconds: float
    label: str
    note: str = ""  # what the bake gets wrong that its measure cannot see (overlapping UV islands)


class _Cache:
    """Baked pixels by key, at most ``budget`` bytes, least recently used dropped first; read by
    renders on their own threads (a lock guards it). ``bakes`` counts the bakes made."""

    def __init__(self, budget: int = BUDGET):
        self._lock = threading.Lock()
        self._entries: OrderedDict[str, Baked] = OrderedDict()
        self.budget = budget
        self.bakes = 0

    def get(self, key: str) -> Baked | None:
        with self._lock:
            found = self._entries.pop(key, None)
            if found is not None:
                self._entries[key] = found  # most recently used last
            return found

    def put(self, key: str, baked: Baked) -> None:
        with self._lock:
            self._entries[key] = baked
            self.bakes += 1
            while sum(b.image.pixels.nbytes for b in self._entries.values()) > self.budget and \
                    len(self._entries) > 1:
                del self._entries[next(iter(self._entries))]

    def __len__(self) -> int:
        with self._lock:
            return len(self._entries)

    def clear(self) -> None:
        with self._lock:
            self._entries.clear()


CACHE = _Cache()
_REVISIONS = itertools.count(1 << 40)  # apart from the image reader's (images._REVISIONS)


@dataclass(frozen=True)
class Request:
    """What one object's material needs baked: the original object's and material's full names,
    the targets and their cache keys (in order), the UV map baked on, the resolution, the object's
    placement (its world matrix, for the bake's object), the frame, and where the snapshot uses
    it (``item``: the draw item's index, ``slot``: the material slot's)."""

    object: str
    material: str
    targets: tuple[baking.BakeTarget, ...]
    keys: tuple[str, ...]
    uv: str
    resolution: int
    matrix: tuple[tuple[float, ...], ...]
    frame: float
    item: int
    slot: int

    def missing(self) -> list[tuple[baking.BakeTarget, str]]:
        """The targets not in the cache, with their keys."""
        return [(t, k) for t, k in zip(self.targets, self.keys) if CACHE.get(k) is None]


def key(target: baking.BakeTarget, mesh: str, resolution: int, placement: str, inputs: str = "") -> str:
    """A bake's cache key: its subgraph's content, the mesh, the resolution, where the subgraph
    reads it the object's placement, and ``inputs``: what the images and attributes it reads hold
    (``inputs_digest``)."""
    h = hashlib.sha1(f"{target.content}|{mesh}|{resolution}|{placement if target.placed else ''}|"
                     f"{inputs}".encode())
    return f"bake:{h.hexdigest()[:24]}"


def inputs_digest(target: baking.BakeTarget, geometry: S.MeshGeometry, images: dict) -> str:
    """What the images and mesh attributes a subgraph reads hold: each image's pixels (hashed
    once per read: an image read again unchanged, as a painted one is at every update, bakes
    nothing again) and each attribute's values as the mesh holds them (where the compiled graph
    has them read)."""
    if not target.images and not target.attributes:
        return ""
    h = hashlib.sha1()
    for name in target.images:
        h.update(f"{name}:{_image_digest(images.get(name))}".encode())
    for attribute in target.attributes:
        values = geometry.attributes.get(attribute)
        h.update(repr(attribute).encode())
        if values is not None:
            h.update(np.ascontiguousarray(values).tobytes())
    return h.hexdigest()[:16]


_MESH_DIGESTS: dict[int, tuple] = {}


def mesh_digest(geometry: S.MeshGeometry, texspace) -> str:
    """What of a mesh a bake depends on, hashed: its corners' positions, normals and UV map, its
    triangles by material slot, its texture space (Generated coordinates). Kept per geometry
    object (a viewport update reuses the geometry of meshes it did not change)."""
    held = _MESH_DIGESTS.get(id(geometry))
    if held is not None and held[0] is geometry and held[1] == texspace:
        return held[2]
    h = hashlib.sha1()
    for array in (geometry.positions, geometry.normals, geometry.uvs, geometry.indices):
        if array is not None:
            h.update(np.ascontiguousarray(array).tobytes())
    h.update(repr((geometry.ranges, texspace)).encode())
    digest = h.hexdigest()[:24]
    if len(_MESH_DIGESTS) > 256:  # geometries come and go: keep the table small
        _MESH_DIGESTS.clear()
    _MESH_DIGESTS[id(geometry)] = (geometry, texspace, digest)
    return digest


_IMAGE_DIGESTS: OrderedDict[tuple[str, int], str] = OrderedDict()


def _image_digest(data: S.ImageData | None) -> str:
    """An image's pixels hashed, once per read (by its key and revision)."""
    if data is None:
        return "-"
    found = _IMAGE_DIGESTS.get((data.key, data.revision))
    if found is None:
        found = hashlib.sha1(np.ascontiguousarray(data.pixels).tobytes()).hexdigest()[:16]
        _IMAGE_DIGESTS[(data.key, data.revision)] = found
        while len(_IMAGE_DIGESTS) > 64:  # one entry per image read: a few
            del _IMAGE_DIGESTS[next(iter(_IMAGE_DIGESTS))]
    return found


def uv_problem(geometry: S.MeshGeometry) -> str:
    """Why the mesh's UV map cannot hold a bake ("" where it can): none, or none with area."""
    uvs = geometry.uvs
    if uvs is None:
        return "it has no UV map"
    if not len(uvs) or float(np.ptp(uvs[:, 0])) * float(np.ptp(uvs[:, 1])) == 0.0:
        return "its UV map has no area"
    return ""


def uv_notes(geometry: S.MeshGeometry) -> list[str]:
    """What a bake on the mesh's UV map gets wrong that it can tell before baking: UVs outside
    0..1 (a bake covers the unit square; the Extend border repeats its edge). Overlapping islands
    are found while baking (``_overlap``)."""
    uvs = geometry.uvs
    notes = []
    if uvs is not None and len(uvs) and (float(uvs.min()) < -1e-4 or float(uvs.max()) > 1.0 + 1e-4):
        notes.append("its UV map reaches outside 0..1 (a bake covers the unit square)")
    return notes


def can_bake_here() -> str:
    """Why a bake cannot run now ("" where it can): off the main thread (a render Blender runs on a
    job thread: F12's render itself, an animation's frames, previews), or without Cycles."""
    if threading.current_thread() is not threading.main_thread():
        return ("a render Blender runs beside the interface cannot bake: F12 and Ctrl+F12 bake what the "
                "current frame needs before they render; the other frames of an animation whose bakes "
                "change with the frame take their socket values (render it with blender -b to bake "
                "every frame)")
    if "cycles" not in bpy.context.preferences.addons.keys() and not hasattr(bpy.types.Scene, "cycles"):
        return "Cycles is not available to bake with"
    return ""


# --- baking ------------------------------------------------------------------------------------

def _expose(tree, path: str, socket: str, made: list, depsgraph=None):
    """The output socket ``socket`` of the node at flat path ``path`` (``materials.graph``'s names:
    group nodes' names, then the node's) as a socket of ``tree``: a node inside a group is passed
    out through a copy of the group's tree (in ``made``, removed after) with one more output."""
    node = tree.nodes.get(path)
    if node is not None:
        found = next((s for s in node.outputs if s.identifier == socket), None)
        if found is None:
            raise RuntimeError(f"node '{path}' has no output '{socket}'")
        return found
    group = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeGroup" and n.node_tree is not None
                  and path.startswith(n.name + "/")), None)
    if group is None:
        raise RuntimeError(f"no node '{path}' in '{tree.name}'")
    original = group.node_tree
    inner = original.copy()
    made.append(inner)
    if depsgraph is not None:
        _freeze(inner, original.evaluated_get(depsgraph))
    group.node_tree = inner
    source = _expose(inner, path[len(group.name) + 1:], socket, made, depsgraph)
    item = inner.interface.new_socket(_TEMPORARY, in_out="OUTPUT", socket_type="NodeSocketColor")
    outputs = [n for n in inner.nodes if n.bl_idname == "NodeGroupOutput"]
    output = next((n for n in outputs if n.is_active_output), outputs[0] if outputs else None)
    if output is None:
        output = inner.nodes.new("NodeGroupOutput")
    inner.links.new(source, next(s for s in output.inputs if s.identifier == item.identifier))
    return next(s for s in group.outputs if s.identifier == item.identifier)


def _freeze(tree, evaluated) -> None:
    """``tree`` (a copy) holding the values ``evaluated`` (its original as the render evaluated
    it: this frame's animated values) has, its animation dropped: the bake then reads what the
    render reads (a bake does not evaluate a copy's animation reliably: measured, a second copy
    baked in one scene kept the original's unanimated value)."""
    if evaluated is None:
        return
    tree.animation_data_clear()
    for node in tree.nodes:
        source = evaluated.nodes.get(node.name)
        if source is None:
            continue
        for sockets, sources in ((node.inputs, source.inputs), (node.outputs, source.outputs)):
            for socket, value in zip(sockets, sources):
                if socket.identifier == value.identifier and hasattr(socket, "default_value"):
                    try:
                        socket.default_value = value.default_value
                    except (AttributeError, TypeError, ValueError):  # read-only or a pointer: left
                        pass


def _emitting(material, target: baking.BakeTarget, depsgraph, made: list):
    """A copy of ``material`` (in ``made``) with this frame's values, whose only output emits
    ``target``'s value (a float as grey, a vector's XYZ as RGB, as Blender converts them into a
    colour), with an active Image Texture node for the bake to write into."""
    copy = material.copy()
    made.append(copy)
    copy.name = _TEMPORARY
    tree = copy.node_tree
    _freeze(tree, getattr(material.evaluated_get(depsgraph), "node_tree", None))
    source = _expose(tree, target.node, target.socket, made, depsgraph)
    for node in [n for n in tree.nodes if n.bl_idname in ("ShaderNodeOutputMaterial", "ShaderNodeOutputAOV")]:
        tree.nodes.remove(node)
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    output.target = "ALL"
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = 1.0
    tree.links.new(source, emission.inputs["Color"])
    tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
    output.is_active_output = True
    texture = tree.nodes.new("ShaderNodeTexImage")
    tree.nodes.active = texture
    return copy, texture


def _object_mesh(obj, material, depsgraph, made: list):
    """A copy of the evaluated mesh (modifiers applied) with only the faces of ``material``'s
    slots, every face on slot 0 (in ``made``), its texture space the object's; where a deformation
    moved its vertices, its texture mesh (``Mesh.texture_mesh``, in ``made``) holds their undeformed
    positions (``orco.undeformed_positions``), which ``_bake`` makes Cycles take for Generated."""
    import bmesh

    evaluated = obj.evaluated_get(depsgraph)
    mesh = bpy.data.meshes.new_from_object(evaluated, preserve_all_data_layers=True, depsgraph=depsgraph)
    made.append(mesh)
    undeformed, _note = orco.undeformed_positions(evaluated, mesh, depsgraph)  # (the render said the note)
    if undeformed is not None:
        rest = bpy.data.meshes.new(_TEMPORARY)
        made.append(rest)
        rest.vertices.add(len(undeformed))
        rest.vertices.foreach_set("co", undeformed.ravel())
        mesh.texture_mesh = rest
    slots = {i for i, slot in enumerate(evaluated.material_slots)
             if slot.material is not None and slot.material.original == material}
    bm = bmesh.new()
    try:
        bm.from_mesh(mesh)
        others = [f for f in bm.faces if f.material_index not in slots and slots]
        if others:  # another material's faces may share the UV square
            bmesh.ops.delete(bm, geom=others, context="FACES_ONLY")
        for face in bm.faces:
            face.material_index = 0
        bm.to_mesh(mesh)
    finally:
        bm.free()
    data = evaluated.data
    if data is not None and hasattr(data, "texspace_location"):
        mesh.use_auto_texspace = False
        mesh.texspace_location = tuple(data.texspace_location)
        mesh.texspace_size = tuple(data.texspace_size)
    mesh.materials.clear()
    return mesh


def _bake_image(scene, obj, uv: str, margin: int) -> None:
    with bpy.context.temp_override(scene=scene, view_layer=scene.view_layers[0], active_object=obj,
                                   object=obj, selected_objects=[obj], selected_editable_objects=[obj]):
        result = bpy.ops.object.bake(type="EMIT", margin=margin, margin_type="EXTEND", use_clear=True,
                                     uv_layer=uv, target="IMAGE_TEXTURES", save_mode="INTERNAL",
                                     use_selected_to_active=False)
    if "FINISHED" not in result:
        raise RuntimeError("Cycles' bake did not finish")


def _uv_area(mesh, uvs: np.ndarray) -> float:
    """The summed area of the mesh's triangles on its UV map (``uvs``: per corner, flat)."""
    mesh.calc_loop_triangles()
    corners = np.empty(len(mesh.loop_triangles) * 3, np.int32)
    mesh.loop_triangles.foreach_get("loops", corners)
    t = uvs.reshape(-1, 2)[corners].reshape(-1, 3, 2).astype(np.float64)
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    return float(0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum())


#: Overlap is said where the UV triangles' summed area exceeds the texels the bake covered by
#: this share (islands' edges make the two differ by about their perimeter in texels; at 64 x 64
#: and up that is under a tenth for islands of a few texels' width).
OVERLAP = 1.2


def _overlap(area: float, covered: int, resolution: int) -> str:
    """Why a bake holds one of several UV islands that overlap ("" where they do not): their
    summed area (of UVs inside 0..1: those outside are said before baking) against the texel
    centres the bake covered."""
    if resolution < 64 or not covered or area * resolution ** 2 <= OVERLAP * covered:
        return ""
    share = 1.0 - covered / (area * resolution ** 2)
    return f"its UV islands overlap (about {share:.0%} of their area): a texel holds one of them"


def _pixels(image, resolution: int) -> np.ndarray:
    out = np.empty(resolution * resolution * 4, np.float32)
    image.pixels.foreach_get(out)
    return out.reshape(resolution, resolution, 4)


#: Keys whose bake failed (the viewport does not try them again; a render does).
FAILED: set[str] = set()


def bake(request: Request, depsgraph, progress=None, should_stop=None) -> list[str]:
    """Bake ``request``'s targets that the cache lacks, on the main thread; ``progress(label)``
    is told before each, and none starts once ``should_stop()`` says so. The messages of the
    targets that could not be baked (their readers keep their socket values)."""
    try:
        return _bake(request, depsgraph, progress, should_stop)
    except Exception as exc:  # the scene, object or mesh made for the bake failed: said, never fatal
        FAILED.update(request.keys)
        return [f"Material '{request.material}' on '{request.object}': not baked ({type(exc).__name__}: "
                f"{exc}); what it feeds takes its socket's value"]


def _bake(request: Request, depsgraph, progress=None, should_stop=None) -> list[str]:
    obj = _named(bpy.data.objects, request.object)
    material = _named(bpy.data.materials, request.material)
    if obj is None or material is None or material.node_tree is None:
        return [f"Material '{request.material}' on '{request.object}': not baked (the object or material "
                f"is gone)"]
    pending = request.missing()
    if not pending:
        return []
    made: list = []
    scene = None
    problems = []
    r = request.resolution
    try:
        scene = bpy.data.scenes.new(_TEMPORARY)
        scene.render.engine = "CYCLES"
        cycles = scene.cycles
        cycles.device = "CPU"
        cycles.samples = 1  # the first sample shades the texel's centre (init_from_bake.h)
        cycles.use_denoising = False
        cycles.use_adaptive_sampling = False
        cycles.shading_system = _has_script(material.node_tree)  # Script nodes run on OSL alone
        # the frame the render draws (set, not frame_set: no frame-change handlers run for it)
        scene.frame_current = int(request.frame)
        scene.frame_subframe = request.frame - int(request.frame)
        mesh = _object_mesh(obj, material, depsgraph, made)
        temp = bpy.data.objects.new(_TEMPORARY, mesh)
        made.append(temp)
        if mesh.texture_mesh is not None:
            # Blender keeps an orco (the texture mesh's positions: BKE_mesh_orco_verts_get) only for
            # a mesh its modifiers made (mesh_calc_modifiers): one that moves nothing (a twist of 0)
            twist = temp.modifiers.new(_TEMPORARY, "SIMPLE_DEFORM")
            twist.deform_method, twist.angle = "TWIST", 0.0
        temp.matrix_world = [list(row) for row in request.matrix]
        temp.color, temp.pass_index = tuple(obj.color), obj.pass_index
        scene.collection.objects.link(temp)
        layer = mesh.uv_layers.get(request.uv)
        if layer is None:
            return [f"Material '{material.name}' on '{obj.name}': not baked (no UV map '{request.uv}')"]
        uvs = np.empty(len(layer.uv) * 2, np.float32)
        layer.uv.foreach_get("vector", uvs)
        inside = float(uvs.min(initial=0.0)) >= -1e-4 and float(uvs.max(initial=0.0)) <= 1.0 + 1e-4
        area = _uv_area(mesh, uvs) if inside else 0.0
        # the check bake lays the texels out on a map of its own, half a texel over (its texel
        # centres: the bake's corners), leaving the maps the nodes read as they are
        # (by name: adding a layer moves the others, and their Python objects go stale)
        render = next((m.name for m in mesh.uv_layers if m.active_render), None)
        mesh.uv_layers.new(name=_TEMPORARY, do_init=False)
        mesh.uv_layers[_TEMPORARY].uv.foreach_set("vector", uvs + np.float32(0.5 / r))
        mesh.uv_layers.active = mesh.uv_layers[request.uv]
        if render is not None:
            mesh.uv_layers[render].active_render = True
        main = bpy.data.images.new(_TEMPORARY, r, r, alpha=True, float_buffer=True)
        check = bpy.data.images.new(_TEMPORARY, r, r, alpha=True, float_buffer=True)
        made += [main, check]
        for image in (main, check):
            image.colorspace_settings.is_data = True  # the values as they are, no view transform
        for target, cache_key in pending:
            if should_stop is not None and should_stop():
                break
            label = f"{material.name} > {target.label}"
            if progress is not None:
                progress(label)
            start = time.perf_counter()
            try:
                copy, texture = _emitting(material, target, depsgraph, made)
                mesh.materials.clear()
                mesh.materials.append(copy)
                texture.image = main
                _bake_image(scene, temp, request.uv, MARGIN)
                texels = _pixels(main, r)
                texture.image = check
                _bake_image(scene, temp, _TEMPORARY, 0)  # no margin: alpha marks the covered texels
                corners = _pixels(check, r)
            except Exception as exc:  # a node tree or mesh we did not foresee: said, never fatal
                FAILED.add(cache_key)
                problems.append(f"Material '{material.name}' on '{obj.name}': {target.label} not baked "
                                f"({type(exc).__name__}: {exc}); what it feeds takes its socket's value")
                continue
            seconds = time.perf_counter() - start
            channels = 1 if target.type in ("VALUE", "INT", "BOOLEAN") else 3
            error = baking.interpolation_error(texels[..., :channels], corners[..., :channels],
                                             corners[..., 3] > 0.5)
            texels[..., 3] = 1.0
            data = S.ImageData(cache_key, texels, "FLOAT", next(_REVISIONS))
            note = _overlap(area, error.points, r)
            CACHE.put(cache_key, Baked(data, r, error, seconds, label, note))
            if note:
                problems.append(f"Material '{material.name}' on '{obj.name}': {target.label} baked, but "
                                f"{note}")
            if error.points == 0:
                problems.append(f"Material '{material.name}' on '{obj.name}': {target.label}'s bake covers "
                                f"no texel centre of its UV map (islands too small for {r} x {r})")
    finally:
        if scene is not None:
            bpy.data.scenes.remove(scene)
        for block in reversed(made):
            _remove(block)
    return problems


def _has_script(tree, seen=None) -> bool:
    """Whether a node tree (or a group in it, at any depth) holds a Script node."""
    seen = set() if seen is None else seen
    if tree is None or tree.name_full in seen:
        return False
    seen.add(tree.name_full)
    return any(node.bl_idname == "ShaderNodeScript"
               or (node.bl_idname == "ShaderNodeGroup" and _has_script(node.node_tree, seen))
               for node in tree.nodes)


def _named(collection, full_name: str):
    """The datablock of ``collection`` whose full name (with its library's, for linked data) is
    ``full_name``, or None."""
    found = collection.get(full_name)
    if found is not None and found.name_full == full_name:
        return found
    return next((block for block in collection if block.name_full == full_name), None)


def _remove(block) -> None:
    """A datablock the bake made, removed from the file."""
    kind = type(block).__name__
    if isinstance(block, bpy.types.Object):
        bpy.data.objects.remove(block)
    elif isinstance(block, bpy.types.Mesh):
        bpy.data.meshes.remove(block)
    elif isinstance(block, bpy.types.Material):
        bpy.data.materials.remove(block)
    elif isinstance(block, bpy.types.Image):
        bpy.data.images.remove(block)
    elif isinstance(block, bpy.types.NodeTree):
        bpy.data.node_groups.remove(block)
    else:  # pragma: no cover - every kind made above is removed above
        raise TypeError(f"cannot remove a {kind}")


def bake_all(requests, depsgraph, progress=None, should_stop=None) -> list[str]:
    """Bake every request's missing targets (each key once), none started once ``should_stop()``
    says so; the messages of what failed."""
    problems, seen = [], set()
    for request in requests:
        if should_stop is not None and should_stop():
            break
        if set(request.keys) <= seen:
            continue
        problems += bake(request, depsgraph, progress, should_stop)
        seen |= set(request.keys)
    return problems


def missing_keys(requests) -> set[str]:
    """The keys of the bakes the requests still wait for."""
    return {k for r in requests for _, k in r.missing()}


def count_missing(requests) -> int:
    """How many bakes the requests still wait for (each key once)."""
    return len(missing_keys(requests))


# --- the viewport's bakes: a timer on the main thread ------------------------------------------

#: Requests the viewport made, baked by ``run_pending`` (a timer on the main thread).
_QUEUE: list[Request] = []
_QUEUE_LOCK = threading.Lock()
#: Counts the timer's completed runs: a viewport that drew before it sees it change and takes the
#: new bakes (``extract.apply_bakes``).
GENERATION = [0]
#: What the last bake run could not bake (the viewport says it).
LAST_PROBLEMS: list[str] = []


def schedule(requests) -> bool:
    """Queue the viewport's requests for ``run_pending``, started by a timer on the main thread
    (never inside a draw callback or a depsgraph update); False where no timer runs (background)."""
    fresh = [r for r in requests if any(k not in FAILED for _, k in r.missing())]
    if not fresh:
        return False
    with _QUEUE_LOCK:
        known = {k for r in _QUEUE for k in r.keys}
        _QUEUE.extend(r for r in fresh if not set(r.keys) <= known)
    if bpy.app.background:
        return False
    if not bpy.app.timers.is_registered(run_pending):
        bpy.app.timers.register(run_pending, first_interval=0.2)
    return True


def run_pending() -> None:
    """Bake the queued requests with the view layer's evaluated depsgraph (the viewport's), then
    ask the 3D views to draw again (the timer's callback: returns None, not repeated)."""
    with _QUEUE_LOCK:
        requests = list(_QUEUE)
        _QUEUE.clear()
    if not requests:
        return None
    try:
        depsgraph = bpy.context.evaluated_depsgraph_get()
        LAST_PROBLEMS[:] = bake_all(requests, depsgraph)
    except Exception as exc:  # no view layer in this context, say: the viewport says it
        LAST_PROBLEMS[:] = [f"Fallbacks not baked ({type(exc).__name__}: {exc})"]
    GENERATION[0] += 1
    wm = getattr(bpy.context, "window_manager", None)
    for window in getattr(wm, "windows", ()):
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()
    return None


def status(object_name: str, material_name: str) -> list[tuple[baking.BakeTarget, Baked | None]]:
    """The last snapshot's bakes of a material on an object: each target with its bake (None: not
    baked); for the Material panel (``REQUESTS``)."""
    request = REQUESTS.get((object_name, material_name))
    if request is None:
        return []
    return [(t, CACHE.get(k)) for t, k in zip(request.targets, request.keys)]


#: The last request per (object, material), as the last render or viewport update made them.
REQUESTS: dict[tuple[str, str], Request] = {}
#: Why a material on an object is not baked where it cannot be (no UV map ...): (object, material) -> text.
UNBAKEABLE: dict[tuple[str, str], str] = {}


def forget() -> None:
    """Drop every bake and what the panels say of them (a file load, unregistering)."""
    CACHE.clear()
    REQUESTS.clear()
    UNBAKEABLE.clear()
    LAST_PROBLEMS.clear()
    FAILED.clear()
    with _QUEUE_LOCK:
        _QUEUE.clear()
