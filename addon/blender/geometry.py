"""Reads an evaluated mesh into ``MeshGeometry``: triangulated corners, normals, UV maps and
tangents, the attributes a material reads, Generated coordinates; kept between renders
(``GEOMETRY_MEMO``) while the mesh stays the same. Arrays come out through ``foreach_get``.
"""

from __future__ import annotations

import copy
import threading
from collections import OrderedDict

import bpy
import numpy as np

from ..materials import mesh_attributes, objects, surface
from ..scene import snapshot as S
from . import orco


def _attribute(mesh, name: str, prop: str, dtype, count: int, width: int = 1) -> np.ndarray | None:
    """A mesh attribute's values as a flat array (Blender's attribute arrays copy out at memory
    speed, unlike the per-item RNA collections); None if the mesh has no such attribute."""
    attribute = mesh.attributes.get(name)
    if attribute is None:
        return None
    out = np.empty(count * width, dtype)
    attribute.data.foreach_get(prop, out)
    return out


def triangle_corners(mesh, corner_positions: np.ndarray,
                     tri_face: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(corners of each loop triangle (n, 3) int32, the face of each): ``mesh.loop_triangles``'
    own ``loops`` and ``polygon_index``, after ``calc_loop_triangles()``; ``corner_positions``
    (one row per corner, float32) decides how quads split; ``tri_face``: the triangles' faces if
    already read (``_triangle_faces``).

    Reading ``loop_triangles`` item by item costs ~0.2 us per triangle; its face indices copy out
    as one array. Triangles and quads - nearly every mesh - are then triangulated here as Blender
    triangulates them (a face's triangles are consecutive, starting at its first corner minus
    twice its index; a quad splits along 0-2 unless that folds it, then along 1-3: Blender's
    mesh_tessellate, is_quad_flip_v3_first_third_fast, in the same float32 operations); meshes
    with larger faces are read from Blender."""
    tri_face = _triangle_faces(mesh) if tri_face is None else tri_face
    n_tri = len(tri_face)
    sizes = np.bincount(tri_face, minlength=len(mesh.polygons)) + 2
    if sizes.max(initial=3) > 4:
        corners = np.empty(n_tri * 3, np.int32)
        mesh.loop_triangles.foreach_get("loops", corners)
        return corners.reshape(-1, 3), tri_face
    starts = np.zeros(len(sizes), np.int32)
    np.cumsum(sizes[:-1], out=starts[1:])
    second = np.zeros(n_tri, np.uint8)  # a quad's second triangle: (0, 2, 3), else (0, 1, 2)
    np.equal(tri_face[1:], tri_face[:-1], out=second[1:].view(bool))
    corners = _SPLITS[second]
    corners += starts[tri_face][:, None]
    quads = np.nonzero(sizes == 4)[0]
    if len(quads):
        first = starts[quads]
        v = [np.take(corner_positions, first + i, axis=0).T for i in range(4)]  # (3, quads) each
        d12, d13, d14 = v[1] - v[0], v[2] - v[0], v[3] - v[0]
        a, b = _cross(d12, d13), _cross(d14, d13)
        flip = np.nonzero(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] > np.float32(0.0))[0]
        if len(flip):
            tri = (first[flip] - 2 * quads[flip]).astype(np.int64)  # the quad's first triangle
            corners[tri] = first[flip][:, None] + _FLIPPED[0]
            corners[tri + 1] = first[flip][:, None] + _FLIPPED[1]
    return corners, tri_face


_SPLITS = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
_FLIPPED = np.array([[0, 1, 3], [1, 2, 3]], np.int32)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of (3, n) float32 vectors, component by component as Blender's cross_v3_v3v3."""
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _triangle_faces(mesh) -> np.ndarray:
    """The face of each loop triangle (after ``calc_loop_triangles()``)."""
    tri_face = np.empty(len(mesh.loop_triangles), np.int32)
    mesh.loop_triangle_polygons.foreach_get("value", tri_face)
    return tri_face


def _edge_arrays(mesh) -> tuple[np.ndarray, np.ndarray]:
    """Each corner's edge and each edge's two vertices (flat)."""
    n_corners, n_edges = len(mesh.loops), len(mesh.edges)
    corner_edge = _attribute(mesh, ".corner_edge", "value", np.int32, n_corners)
    if corner_edge is None:  # older Blender: no corner attribute
        corner_edge = np.empty(n_corners, np.int32)
        mesh.loops.foreach_get("edge_index", corner_edge)
    edge_verts = _attribute(mesh, ".edge_verts", "value", np.int32, n_edges, 2)
    if edge_verts is None:
        edge_verts = np.empty(n_edges * 2, np.int32)
        mesh.edges.foreach_get("vertices", edge_verts)
    return corner_edge, edge_verts


#: Corners of the meshes ``mesh_geometry`` keeps between calls (``GEOMETRY_MEMO``): with the
#: arrays each was made from, ~70 bytes a corner (a million: ~70 MB); a larger mesh is not kept.
MEMO_CORNERS = 1_000_000


class GeometryMemo:
    """The geometries ``mesh_geometry`` made last, each with every array it read to make it
    (positions, corners' vertices and edges, edges' vertices, triangles' faces, material indices,
    corner normals, UVs) and whether tangents were asked for: a mesh that reads the same arrays
    again -- a still mesh rendered again, a frame of an animation where it does not deform -- takes
    the same geometry without the work that follows the reads (splitting quads, the closed
    surface's winding, tangents: ~0.25 ms a small mesh, ~40 ms for 330,000 triangles). Nothing but
    those arrays enters the geometry, so equal arrays give an equal one. Least recently used
    geometries leave first beyond ``limit`` corners; thread-safe (final renders and the viewport
    read scenes on different threads)."""

    def __init__(self, limit: int = MEMO_CORNERS):
        self.limit = limit
        self.hits = 0
        self._lock = threading.Lock()
        self._entries: OrderedDict[str, tuple[tuple, bool, S.MeshGeometry]] = OrderedDict()
        self._corners = 0

    def get(self, key: str, arrays: tuple, tangents: bool) -> S.MeshGeometry | None:
        with self._lock:
            entry = self._entries.get(key)
            if entry is None or entry[1] != tangents or len(entry[0]) != len(arrays) or \
                    not all(map(_same_bits, entry[0], arrays)):
                return None
            self._entries.move_to_end(key)
            self.hits += 1
            return entry[2]

    def put(self, key: str, arrays: tuple, tangents: bool, geometry: S.MeshGeometry) -> None:
        corners = len(geometry.positions)
        with self._lock:
            old = self._entries.pop(key, None)
            if old is not None:
                self._corners -= len(old[2].positions)
            if corners > self.limit:
                return
            self._entries[key] = (arrays, tangents, geometry)
            self._corners += corners
            while self._corners > self.limit:
                _, (_, _, dropped) = self._entries.popitem(last=False)
                self._corners -= len(dropped.positions)

    def clear(self) -> None:
        with self._lock:
            self._entries.clear()
            self._corners = 0


GEOMETRY_MEMO = GeometryMemo()


def _same_bits(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    """Whether two arrays hold the same bits (-0.0 is not 0.0 here, and a NaN equals itself)."""
    if a is None or b is None:
        return a is b
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.itemsize == 4:
        return np.array_equal(a.reshape(-1).view(np.uint32), b.reshape(-1).view(np.uint32))
    return a.tobytes() == b.tobytes()


def _corner_verts(mesh) -> np.ndarray:
    corner_vert = _attribute(mesh, ".corner_vert", "value", np.int32, len(mesh.loops))
    if corner_vert is None:  # older Blender: no corner attribute
        corner_vert = np.empty(len(mesh.loops), np.int32)
        mesh.loops.foreach_get("vertex_index", corner_vert)
    return corner_vert


def mesh_geometry(key: str, mesh: bpy.types.Mesh, tangents: bool = False,
                  memo_key: str | None = None) -> S.MeshGeometry | None:
    """The mesh's corners (position, corner normal, the active UV map's coordinates, tangents when
    ``tangents``) and its triangles as indices into them, grouped by material slot; None when
    empty. Everything is read as whole arrays; no per-corner work happens in Python beyond one
    gather of positions (the GPU draws the triangles indexed). ``memo_key``: where
    ``GEOMETRY_MEMO`` keeps it (default ``key``): a name that stays while the evaluated mesh, and
    with it ``key``, is made anew for each render."""
    mesh.calc_loop_triangles()
    n_tri = len(mesh.loop_triangles)
    if n_tri == 0:
        return None
    n_corner = len(mesh.loops)
    co = _attribute(mesh, "position", "vector", np.float32, len(mesh.vertices), 3)
    if co is None:
        co = np.empty(len(mesh.vertices) * 3, np.float32)
        mesh.vertices.foreach_get("co", co)
    corner_verts = _corner_verts(mesh)
    tri_face = _triangle_faces(mesh)
    face_mat = _attribute(mesh, "material_index", "value", np.int32, len(mesh.polygons))
    normals = np.empty((n_corner, 3), np.float32)
    mesh.corner_normals.foreach_get("vector", normals.reshape(-1))
    uv_layer = mesh.uv_layers.active
    uvs = None
    if uv_layer is not None:
        uvs = np.empty((n_corner, 2), np.float32)
        uv_layer.uv.foreach_get("vector", uvs.reshape(-1))
    corner_edge, edge_verts = _edge_arrays(mesh)
    arrays = (co, corner_verts, tri_face, face_mat, normals, uvs, corner_edge, edge_verts)
    memo_key = key if memo_key is None else memo_key
    kept = GEOMETRY_MEMO.get(memo_key, arrays, tangents)
    if kept is not None:
        if kept.key != key:
            kept = copy.copy(kept)  # the same arrays under this render's key
            kept.key = key
        return kept
    positions = np.take(co.reshape(-1, 3), corner_verts, axis=0)
    tri_corners, tri_face = triangle_corners(mesh, positions, tri_face)
    if face_mat is None or face_mat.min() == face_mat.max():
        slot = int(face_mat[0]) if face_mat is not None else 0
        indices, ranges = tri_corners.reshape(-1), [(max(slot, 0), 0, 3 * n_tri)]
    else:
        tri_mat = face_mat[tri_face]
        order = np.argsort(tri_mat, kind="stable")
        indices = tri_corners[order].reshape(-1)
        slots, starts, counts = np.unique(tri_mat[order], return_index=True, return_counts=True)
        ranges = [(int(s), int(a) * 3, int(c) * 3) for s, a, c in zip(slots, starts, counts)]
    tangent_data = None
    if uv_layer is not None:
        if tangents:
            try:
                mesh.calc_tangents(uvmap=uv_layer.name)
            except RuntimeError:  # n-gons: Blender computes tangents for triangles and quads only
                tangent_data = None  # the normal map is then ignored for this mesh
            else:
                t = np.empty(n_corner * 3, np.float32)
                mesh.loops.foreach_get("tangent", t)
                sign = np.empty(n_corner, np.float32)
                mesh.loops.foreach_get("bitangent_sign", sign)
                tangent_data = np.ascontiguousarray(np.column_stack([t.reshape(-1, 3), sign]), np.float32)
    geometry = S.MeshGeometry(key, positions, normals, ranges, uvs, tangent_data, indices=indices,
                              winding=closed_winding(mesh, corner_verts, positions, tri_corners,
                                                     (corner_edge, edge_verts)))
    GEOMETRY_MEMO.put(memo_key, arrays, tangents, geometry)
    return geometry


def _rgba_property(idb, name: str):
    """Property ``name`` of ``idb`` as an Attribute node reads it (Blender's
    BKE_object_dupli_find_rgba_attribute, learnt from): an RNA path, else a custom property; a
    number as (x, x, x, 1), 2 to 4 numbers as (x, y, z, w) with z 0 and w 1 where missing; None
    where it has none."""
    if idb is None or not name:
        return None
    try:
        value = idb.path_resolve(name)
    except (ValueError, TypeError):
        try:
            value = idb.get(name)
        except (TypeError, AttributeError):
            return None
    if isinstance(value, (bool, int, float)):
        v = float(value)
        return (v, v, v, 1.0)
    try:
        values = [float(x) for x in value]
    except (TypeError, ValueError):
        return None
    if not 2 <= len(values) <= 4:
        return None
    return tuple(values + [0.0, 1.0][len(values) - 2:] if len(values) < 4 else values)


def uniform_attribute(kind: str, name: str, inst, view_layer, scene) -> tuple[float, ...]:
    """An Attribute node's value of type OBJECT (the object, then its data), INSTANCER (the
    instance's instancer, else the object) or VIEW_LAYER (the view layer, then the scene, then its
    world); zeros where none has it (as Cycles). INSTANCER_GENERATED and INSTANCER_UV: an
    instance's coordinates on its instancer (a particle system's, a face's or a vertex's), as Cycles'
    object dupli_generated (orco / 2 - 1/2) and dupli_uv; zeros for an object that is no instance."""
    obj = inst.object
    if kind in ("INSTANCER_GENERATED", "INSTANCER_UV"):
        if not inst.is_instance:
            return (0.0, 0.0, 0.0, 0.0)
        if kind == "INSTANCER_UV":
            return (float(inst.uv[0]), float(inst.uv[1]), 0.0, 0.0)
        return (*(float(np.float32(0.5) * np.float32(c) - np.float32(0.5)) for c in inst.orco), 0.0)
    if kind == "VIEW_LAYER":
        places = (view_layer, scene, scene.world if scene is not None else None)
    else:
        owner = inst.parent if kind == "INSTANCER" and inst.is_instance and inst.parent is not None else obj
        places = (owner.original, getattr(owner.original, "data", None))
    for place in places:
        value = _rgba_property(place, name)
        if value is not None:
            return value
    return (0.0, 0.0, 0.0, 0.0)


def instance_random(inst) -> float:
    """Object Info's Random: an object's from its name, as Cycles computes it
    (``materials.objects.object_random``); an instance's from its depsgraph ``random_id``, scaled
    as Cycles scales it (random_id / 0xFFFFFFFF)."""
    if not inst.is_instance:
        return objects.object_random(inst.object.original.name)
    return float(np.float32(int(inst.random_id) & 0xFFFFFFFF) * (np.float32(1.0) / np.float32(0xFFFFFFFF)))


def _corner_values(mesh, attribute, values: np.ndarray, width: int) -> np.ndarray | None:
    """An attribute's (n, width) values per corner, from its domain (None: a domain a corner does
    not map to)."""
    domain = attribute.domain
    if domain == "CORNER":
        return values
    if domain == "POINT":
        return values[_corner_verts(mesh)]
    if domain == "FACE":
        sizes = np.empty(len(mesh.polygons), np.int32)
        mesh.polygons.foreach_get("loop_total", sizes)
        return np.repeat(values, sizes, axis=0)
    return None


#: Each generic attribute data type: the RNA property its values are read by and its width.
_ATTRIBUTE_READS = {"FLOAT": ("value", 1), "INT": ("value", 1), "BOOLEAN": ("value", 1),
                    "FLOAT_VECTOR": ("vector", 3), "FLOAT2": ("vector", 2), "INT8": ("value", 1),
                    "FLOAT_COLOR": ("color", 4), "BYTE_COLOR": ("color", 4)}


def read_attribute(mesh, kind: str, name: str) -> np.ndarray | None:
    """A node graph's attribute (kind, name) per corner as (n, 4) float32 -- a UV map's (u, v, 0,
    1), a colour attribute's linear RGBA, a generic one's value (x, x, x, 1) or vector (x, y, z,
    1) -- or None where the mesh has none of that name."""
    n = len(mesh.loops)
    if kind in ("POINTINESS", "RANDOM_PER_ISLAND"):
        values = _geometry_attribute(mesh, kind)
        out = np.ones((n, 4), np.float32)
        out[:, :3] = values[:, None]
        return out
    if kind == "TANGENT":  # a named UV map's tangents (object space, w the bitangent's sign)
        if name not in mesh.uv_layers:
            return None
        try:
            mesh.calc_tangents(uvmap=name)
        except RuntimeError:  # n-gons
            return None
        t = np.empty(n * 3, np.float32)
        mesh.loops.foreach_get("tangent", t)
        sign = np.empty(n, np.float32)
        mesh.loops.foreach_get("bitangent_sign", sign)
        return np.ascontiguousarray(np.column_stack([t.reshape(-1, 3), sign]), np.float32)
    if kind == "UV":
        layer = mesh.uv_layers.get(name) if name else (mesh.uv_layers.active or None)
        if layer is None:
            return None
        uv = np.empty(n * 2, np.float32)
        layer.uv.foreach_get("vector", uv)
        out = np.zeros((n, 4), np.float32)
        out[:, :2] = uv.reshape(-1, 2)
        out[:, 3] = 1.0
        return out
    if kind == "COLOR":
        colors = mesh.color_attributes
        if name:
            attribute = colors.get(name)
        else:  # the mesh's default colour attribute (its render colour)
            index = colors.render_color_index
            attribute = colors[index] if 0 <= index < len(colors) else None
    else:
        attribute = mesh.attributes.get(name)
    if attribute is None:
        return None
    prop, width = _ATTRIBUTE_READS.get(attribute.data_type, (None, 0))
    if prop is None:
        return None
    raw = np.empty(len(attribute.data) * width, np.float32)
    attribute.data.foreach_get(prop, raw)
    values = _corner_values(mesh, attribute, raw.reshape(-1, width), width)
    if values is None:
        return None
    out = np.zeros((n, 4), np.float32)
    out[:, 3] = 1.0
    if width == 1:
        out[:, :3] = values
    else:
        out[:, :width] = values
    return out


def _geometry_attribute(mesh, kind: str) -> np.ndarray:
    """The Geometry node's Pointiness or Random Per Island per corner (float32), as Cycles makes
    them of the mesh (``materials.mesh_attributes``) from its positions, vertex normals, edges and
    faces, read as whole arrays."""
    corner_verts = _corner_verts(mesh)
    _corner_edge, edge_verts = _edge_arrays(mesh)
    n_verts = len(mesh.vertices)
    if kind == "POINTINESS":
        co = np.empty(n_verts * 3, np.float32)
        mesh.vertices.foreach_get("co", co)
        normals = np.empty(n_verts * 3, np.float32)
        mesh.vertex_normals.foreach_get("vector", normals)
        return mesh_attributes.pointiness(co, normals, edge_verts)[corner_verts]
    sizes = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    starts = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    per_face = mesh_attributes.random_per_island(edge_verts, n_verts, corner_verts[starts])
    return np.repeat(per_face, sizes)


def with_attributes(geometry: S.MeshGeometry, mesh, wanted, warnings: list[str]) -> S.MeshGeometry:
    """``geometry`` (a copy: the memo's stays as it is) with the attributes ``wanted`` read from
    ``mesh``; one it lacks reads zeros, said in ``warnings``."""
    geometry = copy.copy(geometry)
    geometry.attributes = {}
    for kind, name in sorted(wanted):
        values = read_attribute(mesh, kind, name)
        if values is None:
            warnings.append(f"Mesh '{mesh.name}': no {kind.lower()} attribute '{name or '(default)'}' "
                            f"that its material reads (it reads zeros)")
            continue
        geometry.attributes[(kind, name)] = values
    return geometry


def with_orco(geometry: S.MeshGeometry, obj, mesh, depsgraph, warnings: list[str]) -> S.MeshGeometry:
    """``geometry`` (a copy) with ``obj``'s undeformed positions per corner (``surface.ORCO``:
    (x, y, z, 1)) where a deformation moved its vertices (``orco.undeformed_positions``), for the
    graphs reading Generated; where they cannot be made, ``warnings`` says so."""
    geometry = copy.copy(geometry)
    geometry.attributes = dict(geometry.attributes)
    geometry.orco_read = True
    positions, note = orco.undeformed_positions(obj, mesh, depsgraph)
    if note:
        warnings.append(note)
    if positions is not None:
        values = np.ones((len(mesh.loops), 4), np.float32)
        values[:, :3] = positions[_corner_verts(mesh)]
        geometry.attributes[surface.ORCO] = values
    return geometry


def closed_winding(mesh, corner_verts: np.ndarray, corner_positions: np.ndarray,
                   tri_corners: np.ndarray, edges: tuple[np.ndarray, np.ndarray] | None = None) -> int:
    """``MeshGeometry.winding`` of ``mesh``: +1 (-1) where every edge that borders a face borders
    exactly two, run along it in opposite directions (a closed, consistently oriented surface),
    and the volume it encloses, from its triangles (``tri_corners`` into ``corner_positions``;
    ``corner_verts``: each corner's vertex), is positive (negative); else 0. Whole arrays of
    Blender's corner and edge attributes: ~20 ms for a closed mesh of 330,000 triangles, ~6 ms
    for an open one of a million. ``edges``: each corner's edge and each edge's vertices if
    already read (``_edge_arrays``)."""
    n_edges = len(mesh.edges)
    if n_edges == 0:
        return 0
    corner_edge, edge_verts = _edge_arrays(mesh) if edges is None else edges
    faces = np.bincount(corner_edge, minlength=n_edges)
    if np.any((faces != 0) & (faces != 2)):
        return 0  # a border or a non-manifold edge
    # a corner runs along its edge from its own vertex: of an edge's two corners, one from each end
    from_first = corner_verts == edge_verts.reshape(-1, 2)[corner_edge, 0]
    if np.any(np.bincount(corner_edge, weights=from_first, minlength=n_edges)[faces == 2] != 1.0):
        return 0
    # the divergence theorem: 6 V = sum over triangles of a . (b x c), about a corner of the mesh
    # (float32 products, float64 sums: only the sign is wanted; ~10 ms for 300,000 triangles)
    centred = corner_positions - corner_positions[0]
    a, b, c = (np.take(centred, tri_corners[:, i], axis=0).T for i in range(3))
    terms = a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) + \
        a[2] * (b[0] * c[1] - b[1] * c[0])
    volume = float(np.sum(terms, dtype=np.float64))
    if abs(volume) <= 1e-6 * float(np.sum(np.abs(terms), dtype=np.float64)):
        return 0  # flat: no inside to face
    return 1 if volume > 0.0 else -1
