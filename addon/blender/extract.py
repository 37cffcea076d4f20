"""Reads a Blender depsgraph into a ``Snapshot``: the only module that reads scene data for
rendering. Arrays come out through ``foreach_get``; there is no per-vertex Python loop.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import math
import threading
from collections import Counter, OrderedDict

import bpy
import numpy as np

from ..materials import codegen, mesh_attributes, objects, surface
from ..plan import auto_terms, light_tiles, programs, shadows
from ..scene import snapshot as S
from ..scene.matrices import invert
from . import bake, nodes, orco
from .images import IMAGES, image_key

LIGHT_KIND = {"POINT": "POINT", "SPOT": "SPOT", "SUN": "SUN", "AREA": "AREA"}


class ExtractError(RuntimeError):
    """The scene cannot be rendered as it is (no camera, say); the message is for the user."""


def render_size(scene: bpy.types.Scene) -> tuple[int, int]:
    r = scene.render
    scale = r.resolution_percentage / 100.0
    return max(int(r.resolution_x * scale), 1), max(int(r.resolution_y * scale), 1)


# --- materials ---------------------------------------------------------------------------------

def _linked_surface_node(material: bpy.types.Material):
    tree = material.node_tree
    if tree is None:
        return None
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    active = [n for n in outputs if n.is_active_output] or outputs
    for out in active:
        surface = out.inputs.get("Surface")
        if surface is not None and surface.is_linked:
            return surface.links[0].from_node
    return None


def _rgb(value) -> tuple[float, float, float]:
    return (float(value[0]), float(value[1]), float(value[2]))


def _input(node, name, default):
    socket = node.inputs.get(name)
    return default if socket is None else socket.default_value


def material_params(material: bpy.types.Material | None, images: dict | None = None,
                    warnings: list[str] | None = None) -> S.MaterialParams:
    """Explicit Shading Lab values where the user set them, else the surface shader's values
    (Principled, Diffuse or Glossy BSDF), else the material's viewport display values; a surface
    with nodes linked into it is compiled (``MaterialParams.graph``: its values per fragment). Images
    the graph samples are added to ``images`` (key -> ``bpy.types.Image``); what of it is not
    compiled is said in ``warnings``."""
    if material is None:
        return S.DEFAULT_MATERIAL
    maps: dict = _thin_film_version()
    base = _rgb(material.diffuse_color)
    metal = float(material.metallic)
    rough = float(material.roughness)
    f0 = S.DEFAULT_F0
    node = _linked_surface_node(material)
    kind = node.bl_idname if node is not None else ""
    if kind == "ShaderNodeBsdfPrincipled":
        base = _rgb(_input(node, "Base Color", base))
        metal = float(_input(node, "Metallic", metal))
        rough = float(_input(node, "Roughness", rough))
        level = float(_input(node, "Specular IOR Level", 0.5))
        f0 = min(S.f0_from_ior(float(_input(node, "IOR", 1.5))) * 2.0 * level, 1.0)
        maps["alpha"] = float(_input(node, "Alpha", 1.0))
        strength = float(_input(node, "Emission Strength", 0.0))
        maps["emission"] = tuple(c * strength for c in _rgb(_input(node, "Emission Color", (0, 0, 0))))
        maps.update(_principled_lobes(node))
    elif kind == "ShaderNodeEmission":  # a pure emitter: no reflection
        base, metal, f0 = (0.0, 0.0, 0.0), 0.0, 0.0
        strength = float(_input(node, "Strength", 1.0))
        maps["emission"] = tuple(c * strength for c in _rgb(_input(node, "Color", (1, 1, 1))))
    elif kind == "ShaderNodeBsdfDiffuse":
        base, metal, f0 = _rgb(_input(node, "Color", base)), 0.0, 0.0
    elif kind in ("ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic"):
        base, metal = _rgb(_input(node, "Color", base)), 1.0
        rough = float(_input(node, "Roughness", rough))
    elif kind in GLASS_NODES:
        base, metal, rough, f0 = _glass(node, maps)
    graph, aovs = _material_graph(material, images, warnings)
    if graph is not None:  # its closures' inputs, per fragment
        maps["graph"] = graph
    if aovs:
        maps["aovs"] = tuple(sorted(aovs.items()))
    props = getattr(material, "shading_lab", None)
    if props is not None:  # explicit values win over the shader's, textures included
        base = _rgb(props.base_color) if props.use_base_color else base
        metal = float(props.metalness) if props.use_metalness else metal
        rough = float(props.roughness) if props.use_roughness else rough
        f0 = float(props.f0) if props.use_f0 else f0
    metal = min(max(metal, 0.0), 1.0)
    rough = min(max(rough, 0.0), 1.0)
    # Blinn-Phong/Phong fallbacks from the physically based values: a metal's colour goes to its
    # highlight and none to its diffuse term; a dielectric keeps a white highlight; the ambient
    # colour is the diffuse colour (the seed's "typically"); shininess from roughness. A surface
    # with no specular lobe (F0 0: Diffuse BSDF, Emission, Specular IOR Level 0) has no highlight.
    diffuse = tuple(c * (1.0 - metal) for c in base)
    dielectric_spec = 1.0 if f0 > 0.0 else 0.0
    spec = tuple((1.0 - metal) * dielectric_spec + metal * c for c in base)
    shininess = S.shininess_from_roughness(rough)
    ambient = diffuse
    if props is not None:
        spec = _rgb(props.specular_color) if props.use_specular_color else spec
        shininess = float(props.shininess) if props.use_shininess else shininess
        ambient = _rgb(props.ambient_color) if props.use_ambient_color else ambient
    if graph is not None and props is not None:
        maps["graph_keep"] = frozenset(name for name, flag in GRAPH_KEEP.items() if getattr(props, flag))
    return S.MaterialParams(
        name=material.name,
        pass_index=int(getattr(material, "pass_index", 0)),
        base_color=base,
        diffuse_color=diffuse,
        specular_color=spec,
        ambient_color=ambient,
        roughness=rough,
        metalness=metal,
        shininess=max(shininess, 0.0),
        f0=min(max(f0, 0.0), 1.0),
        **{k: v for k, v in maps.items() if v is not None},
        **_material_extras(props),
    )


def _principled_lobes(node) -> dict:
    """The Principled BSDF's lobes beyond its base (MaterialParams' fields), clamped as Cycles'
    svm_node_closure_bsdf clamps them: tints and weights at least 0, roughnesses within [0, 1], the
    coat's IOR at least 1, the Transmission Weight within [0, 1]."""
    def colour(name):
        return tuple(max(c, 0.0) for c in _rgb(_input(node, name, (1.0, 1.0, 1.0))))

    def unit(name, default):
        return min(max(float(_input(node, name, default)), 0.0), 1.0)

    return {"specular_tint": colour("Specular Tint"),
            "coat_weight": max(float(_input(node, "Coat Weight", 0.0)), 0.0),
            "coat_roughness": unit("Coat Roughness", 0.03),
            "coat_ior": max(float(_input(node, "Coat IOR", 1.5)), 1.0), "coat_tint": colour("Coat Tint"),
            "sheen_weight": max(float(_input(node, "Sheen Weight", 0.0)), 0.0),
            "sheen_roughness": unit("Sheen Roughness", 0.5), "sheen_tint": colour("Sheen Tint"),
            "subsurface_weight": unit("Subsurface Weight", 0.0),
            "subsurface_radius": tuple(float(c) for c in
                                       _input(node, "Subsurface Radius", (1.0, 0.2, 0.1))[:3]),
            "subsurface_scale": float(_input(node, "Subsurface Scale", 0.05)),
            "subsurface_ior": float(_input(node, "Subsurface IOR", 1.4)),
            "subsurface_anisotropy": float(_input(node, "Subsurface Anisotropy", 0.0)),
            "subsurface_method": getattr(node, "subsurface_method", "RANDOM_WALK"),
            # the glass part (Cycles' Transmission component): each crossing tinted by sqrt(Base
            # Color), the base colour clamped to [0, 1] first; its IOR the Principled BSDF's
            "transmission_weight": unit("Transmission Weight", 0.0),
            "transmission_ior": max(float(_input(node, "IOR", 1.5)), 1e-5),
            "transmission_tint": tuple(min(max(c, 0.0), 1.0) ** 0.5 for c in _rgb(_input(node, "Base Color",
                                                                                           (0.8, 0.8, 0.8)))),
            # the diffuse base's Oren-Nayar roughness (Blender 4.3 and later; 4.2's: Lambert)
            "diffuse_roughness": unit("Diffuse Roughness", 0.0),
            # what the random walk's entry refracts through (reference/subsurface.py's walk_row)
            "ior": float(_input(node, "IOR", 1.5)),
            "specular_ior_level": float(_input(node, "Specular IOR Level", 0.5)),
            **_thin_film(node)}


def _thin_film(node) -> dict:
    """The Principled BSDF's Thin Film (Blender 4.2 and later; none before): its thickness (nm, at
    least 0: 0.1 or less is no film, Cycles' THINFILM_THICKNESS_CUTOFF) and IOR (at least 1e-5, as
    Cycles' svm_node_closure_bsdf floors it)."""
    return {"thin_film_thickness": max(float(_input(node, "Thin Film Thickness", 0.0)), 0.0),
            "thin_film_ior": max(float(_input(node, "Thin Film IOR", 1.33)), 1e-5)}


def _thin_film_version() -> dict:
    """The rule this Blender's Cycles draws a Thin Film by (``snapshot.THIN_FILM_RULES``: 4.2 and 4.5
    sum its colour through a Gaussian fit in XYZ, leave the metal bare and blend its IOR to the air's
    below 30 nm; 5.0 reads a table, films the metal, blends below 1 nm)."""
    return {"thin_film_rule": S.thin_film_rule(bpy.app.version)}


#: The closures that transmit alone (glsl/transmission.glsl): the Glass BSDF (reflects and transmits
#: by the Fresnel) and the Refraction BSDF (transmits all, reflects nothing).
GLASS_NODES = ("ShaderNodeBsdfGlass", "ShaderNodeBsdfRefraction")


def _glass(node, maps: dict) -> tuple:
    """A Glass or Refraction BSDF as the surface: (base colour, metalness, roughness, F0), its
    transmission into ``maps``, as Cycles' svm_node_closure_bsdf sets its closure up: the Color
    tints each crossing (and the Glass BSDF's reflection), the IOR at least 1e-5, the roughness
    within [0, 1]; the Refraction BSDF has no reflection (F0 0) and no Fresnel."""
    color = tuple(max(c, 0.0) for c in _rgb(_input(node, "Color", (1.0, 1.0, 1.0))))
    ior = max(float(_input(node, "IOR", 1.5)), 1e-5)
    rough = min(max(float(_input(node, "Roughness", 0.0)), 0.0), 1.0)
    glass = node.bl_idname == "ShaderNodeBsdfGlass"
    maps.update(transmission_weight=1.0, transmission_ior=ior, transmission_tint=color,
                reflection_tint=color if glass else (0.0, 0.0, 0.0), transmission_fresnel=glass)
    return color, 0.0, rough, S.f0_from_ior(ior) if glass else 0.0


#: The Material panel's explicit values a compiled graph leaves as they are: its input -> the flag.
GRAPH_KEEP = {"base_color": "use_base_color", "metalness": "use_metalness", "roughness": "use_roughness",
              "f0": "use_f0", "specular_color": "use_specular_color", "shininess": "use_shininess",
              "ambient_color": "use_ambient_color"}


@dataclasses.dataclass(frozen=True)
class GraphReport:
    """What the last read of a material made of its node graph, for the Material panel: whether
    it was compiled (else its surface is one shader read as values), how many of its nodes, which
    did not compile and what the models do not read (``MaterialGraph.missing`` / ``unread``),
    whether its Displacement is linked (never drawn), its AOV Outputs, and which of the nodes
    that did not compile are baked (``bake``: per object, ``bake.status``)."""

    compiled: bool
    nodes: int = 0
    missing: tuple[str, ...] = ()
    unread: tuple[str, ...] = ()
    displacement: bool = False
    aovs: tuple[str, ...] = ()
    #: of ``missing``, the nodes Cycles bakes for the objects using the material (flat names)
    baked: tuple[str, ...] = ()


#: The last GraphReport of each material (by its full name), as a render or the viewport read it.
GRAPH_REPORTS: dict[str, GraphReport] = {}


def _material_graph(material, images: dict | None, warnings: list[str] | None) -> tuple:
    """(the material's node graph compiled, ``surface.compile_material``: None where its surface is
    one closure with nothing linked into it; its AOV Outputs compiled, by name); the images they
    sample go into ``images``. The nodes the surface could not compile are said in ``warnings``."""
    found: dict = {}
    read = nodes.read_material(material, images=found)
    if read is None:
        return None, {}
    graph = surface.compile_material(*read)
    aovs = surface.compile_aovs(*read)
    displacement = surface.displacement_linked(read[0])
    GRAPH_REPORTS[material.name_full] = GraphReport(
        graph is not None, graph.nodes if graph is not None else 0, tuple(graph.missing) if graph else (),
        tuple(graph.unread) if graph else (), displacement, tuple(sorted(aovs)),
        tuple(_baked_nodes(graph, aovs)))
    if displacement and warnings is not None:
        warnings.append(f"Material '{material.name}': its Displacement is not drawn (the surface is drawn "
                        f"as it is, without displacement or bump from the output)")
    for compiled in ([graph] if graph is not None else []) + list(aovs.values()):
        if images is not None:  # a UDIM tile's key (codegen.tile_key) names its image's
            images.update((key, found.get(key) or found[key.rsplit("#", 1)[0]])
                          for entry in compiled.images for key in codegen.sampler_keys(entry))
        if compiled.notes and warnings is not None:
            warnings.append(f"Material '{material.name}': {'; '.join(compiled.notes)}")
    baked = _baked_nodes(graph, aovs)
    if baked and warnings is not None:
        kinds = {m.rsplit(" (", 1)[0]: m for g in [graph, *aovs.values()] if g is not None for m in g.missing}
        named = ", ".join(kinds.get(n, n) for n in baked)
        of = f" of {graph.nodes}" if graph is not None else ""
        warnings.append(f"Material '{material.name}': {len(baked)}{of} nodes not compiled ({named}): baked "
                        f"by Cycles on each object's UV map")
    if graph is None:
        return None, aovs
    if graph.unread and warnings is not None:
        warnings.append(f"Material '{material.name}': its {', '.join(graph.unread)} not drawn (the shading "
                        f"models have no such input)")
    fallen = [m for m in graph.missing if m.rsplit(" (", 1)[0] not in baked]
    if fallen and warnings is not None:
        warnings.append(f"Material '{material.name}': {len(fallen)} of {graph.nodes} nodes not "
                        f"compiled ({', '.join(fallen)}); what they feed takes its socket's own value")
    return graph, aovs


def _baked_nodes(graph, aovs: dict) -> list[str]:
    """The not-compiled nodes of a material's graphs that its bakes stand in for (flat names)."""
    graphs = ([graph] if graph is not None else []) + list(aovs.values())
    return list(dict.fromkeys(n for g in graphs for t in g.bakes for n in t.nodes))


def _material_extras(props) -> dict:
    """The per-material model and term choices, and the Fresnel inputs beyond F0."""
    if props is None:
        return {}

    def chosen(value):
        return "" if value == "SCENE" else value

    extras = dict(model=chosen(props.model), fresnel=chosen(props.fresnel), ndf=chosen(props.ndf),
                  visibility=chosen(props.visibility), diffuse=chosen(props.diffuse),
                  fresnel_p=float(props.fresnel_p),
                  environment_samples={"SCENE": -1, "SPLIT_SUM": 0}.get(props.world_specular,
                                                                        int(props.world_samples)))
    if props.use_f90:
        extras["f90"] = float(props.f90)
    if props.use_complex_ior:
        extras["ior_n"], extras["ior_k"] = _rgb(props.ior_n), _rgb(props.ior_k)
    return extras


# --- geometry ----------------------------------------------------------------------------------

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


def _geometry_key(obj: bpy.types.Object) -> str:
    """The evaluated mesh's identity: instances of one mesh share it, modifiers make a new one."""
    return f"mesh:{obj.data.name_full}:{obj.data.as_pointer():x}"


def _memo_key(obj: bpy.types.Object) -> str:
    """Where ``GEOMETRY_MEMO`` keeps an object's mesh: the original object and mesh, which stay
    from one render's depsgraph to the next (the evaluated mesh, ``_geometry_key``, does not)."""
    data = obj.data.original if obj.data.original is not None else obj.data
    return f"{obj.original.name_full}:{data.name_full}"


def _matrix(m) -> np.ndarray:
    return np.array(m, np.float32)


#: Object types that reach the depsgraph with no mesh of their own, and are not drawn.
UNDRAWN_KINDS = {"CURVES": "hair curves object(s)", "VOLUME": "volume(s)", "POINTCLOUD": "point cloud(s)",
                 "GREASEPENCIL": "Grease Pencil object(s)", "GPENCIL": "Grease Pencil object(s)"}


# --- lights ------------------------------------------------------------------------------------

def light_strength(light: bpy.types.Light) -> np.ndarray:
    """Linear rgb colour x energy x 2^exposure (x blackbody colour when temperature is used)."""
    color = np.array(light.color, np.float64)
    if getattr(light, "use_temperature", False):
        color = color * np.array(light.temperature_color, np.float64)
    return color * float(light.energy) * 2.0 ** float(getattr(light, "exposure", 0.0))


def make_light(light: bpy.types.Light, matrix) -> S.Light:
    """The light as the shaders see it, reaching as far as its Custom Distance (everywhere
    without one); the Light Threshold's reach is the scene's to give (``programs.light_reaches``)."""
    m = np.array(matrix, np.float64)
    position = tuple(float(x) for x in m[:3, 3])
    axis = -m[:3, 2]
    norm = np.linalg.norm(axis)
    direction = tuple(float(x) for x in (axis / norm if norm > 0 else np.array([0.0, 0.0, -1.0])))
    strength = light_strength(light)
    kind = LIGHT_KIND[light.type]
    extra = {}
    normalized = getattr(light, "normalize", True)
    # Cycles (scene/light.cpp): eval_fac = (normalize ? 1 / area : 1) / pi, with area = 4 for a
    # radius-0 point or spot, 1 for a zero-angle sun, and the light's surface for an area light.
    if kind in ("POINT", "SPOT"):
        intensity = strength / (4.0 * math.pi if normalized else math.pi)  # I = P / 4 pi W/sr
    elif kind == "SUN":
        intensity = strength  # W/m^2 at any angle when normalized
        half = 0.5 * float(light.angle)
        if not normalized and half > 0.0:
            intensity = strength * math.pi * math.sin(half) ** 2
    else:  # AREA: a Lambertian emitter of radiance P / (pi A) gives I = P / pi along its normal
        intensity = strength / math.pi
        if not normalized:
            intensity = intensity * _area(light)
    if kind == "SPOT":
        extra = dict(
            spot_cos_half=math.cos(0.5 * light.spot_size),
            spot_smooth=S.spot_smooth(light.spot_size, light.spot_blend),
        )
    if kind == "SUN":
        extra["angle"] = max(float(light.angle), 0.0)
    elif kind == "AREA":
        scale_x, scale_y = (float(np.linalg.norm(m[:3, i])) for i in (0, 1))
        sx, sy, ellipse = _area_shape(light)
        half = (0.5 * sx * scale_x, 0.5 * sy * scale_y)
        extra["radius"] = math.sqrt(half[0] * half[1] * (1.0 if ellipse else 4.0 / math.pi))  # equal area
        extra["axis_x"] = tuple(float(x) for x in m[:3, 0] / max(scale_x, 1e-30))
        extra["half_size"] = half
        extra["ellipse"] = ellipse
        extra["spread"] = min(max(float(getattr(light, "spread", math.pi)), 0.0), math.pi)
    else:
        extra["radius"] = max(float(light.shadow_soft_size), 0.0)
        extra["soft_falloff"] = bool(getattr(light, "use_soft_falloff", False))
    custom = float(light.cutoff_distance) if getattr(light, "use_custom_distance", False) else None
    extra["cutoff"] = extra["influence"] = light_tiles.influence_radius(kind, intensity, 0.0, custom)
    return S.Light(
        kind=kind,
        position=position,
        direction=direction,
        intensity=tuple(float(x) for x in intensity),
        diffuse_factor=float(light.diffuse_factor),
        specular_factor=float(light.specular_factor),
        shadow=bool(getattr(light, "use_shadow", True)),
        shadow_filter=max(float(getattr(light, "shadow_filter_radius", 1.0)), 0.0),
        shadow_resolution_limit=max(float(getattr(light, "shadow_maximum_resolution", 0.001)), 0.0),
        shadow_jitter=bool(getattr(light, "use_shadow_jitter", False)),
        **extra,
    )


def _area_shape(light) -> tuple[float, float, bool]:
    """An area light's width, height and whether it is a disk or an ellipse."""
    sy = light.size_y if light.shape in ("RECTANGLE", "ELLIPSE") else light.size
    return float(light.size), float(sy), light.shape in ("DISK", "ELLIPSE")


def _area(light) -> float:
    sx, sy, ellipse = _area_shape(light)
    return sx * sy * (math.pi / 4.0 if ellipse else 1.0)


# --- camera and world --------------------------------------------------------------------------

def make_camera(depsgraph, camera_obj, width: int, height: int) -> S.Camera:
    r = depsgraph.scene.render
    cam_eval = camera_obj.evaluated_get(depsgraph)
    projection = cam_eval.calc_matrix_camera(
        depsgraph, x=width, y=height, scale_x=r.pixel_aspect_x, scale_y=r.pixel_aspect_y
    )
    view = invert(np.array(cam_eval.matrix_world, np.float64))
    return S.Camera.from_matrices(view, np.array(projection), cam_eval.data.type != "ORTHO")


def _world_tree(world):
    # Blender 5 worlds always use nodes (use_nodes is deprecated); 4.x honours the toggle
    return world.node_tree if bpy.app.version >= (5, 0, 0) or world.use_nodes else None


def _world_output(tree):
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"]
    active = [n for n in outputs if n.is_active_output] or outputs
    return active[0] if active else None


class _WorldReader:
    """Reads a world's shader graph into radiance terms as Cycles evaluates it: Background
    (colour x strength), its colour from an Environment Texture (equirectangular or mirror ball,
    through Texture Coordinate "Generated" and a Mapping node), Add Shader, Mix Shader by a
    constant factor or by Light Path "Is Camera Ray" (camera rays see one input, lighting uses
    the other). What it cannot read becomes the world's viewport colour, with a warning."""

    def __init__(self, world, snap: S.Snapshot):
        self.world, self.snap = world, snap
        self.unreadable: list[str] = []  # what could not be read (a baked world stands in for it)

    def warn(self, what: str) -> None:
        self.unreadable.append(what)

    def shader(self, socket, weight: np.ndarray, camera: bool | None) -> tuple[list, list]:
        """(camera terms, lighting terms) of what is linked into ``socket``; ``camera`` None
        means both kinds of rays."""
        if not socket.is_linked:
            return [], []
        node = socket.links[0].from_node
        kind = node.bl_idname
        if kind == "ShaderNodeBackground":
            strength_socket = node.inputs["Strength"]
            if strength_socket.is_linked:
                self.warn(f"a link into {node.name}'s Strength")
            term = self.background(node, weight * float(strength_socket.default_value))
            return ([term] if camera in (None, True) else []), ([term] if camera in (None, False) else [])
        if kind == "ShaderNodeAddShader":
            a = self.shader(node.inputs[0], weight, camera)
            b = self.shader(node.inputs[1], weight, camera)
            return a[0] + b[0], a[1] + b[1]
        if kind == "ShaderNodeMixShader":
            fac = node.inputs["Fac"]
            if fac.is_linked and fac.links[0].from_node.bl_idname == "ShaderNodeLightPath" \
                    and fac.links[0].from_socket.name == "Is Camera Ray":
                lighting = self.shader(node.inputs[1], weight, False if camera is None else camera)
                seen = self.shader(node.inputs[2], weight, True if camera is None else camera)
                return lighting[0] + seen[0], lighting[1] + seen[1]
            if fac.is_linked:
                self.warn(f"a link into {node.name}'s Fac")
            f = min(max(float(fac.default_value), 0.0), 1.0)
            a = self.shader(node.inputs[1], weight * (1.0 - f), camera) if f < 1.0 else ([], [])
            b = self.shader(node.inputs[2], weight * f, camera) if f > 0.0 else ([], [])
            return a[0] + b[0], a[1] + b[1]
        self.warn(f"the {node.bl_label} node")
        term = S.EnvironmentTerm(tuple(float(c) for c in weight * np.array(_rgb(self.world.color))))
        return ([term] if camera in (None, True) else []), ([term] if camera in (None, False) else [])

    def background(self, node, weight: np.ndarray) -> S.EnvironmentTerm:
        color = node.inputs["Color"]
        if not color.is_linked:
            return S.EnvironmentTerm(tuple(float(c) for c in weight * np.array(_rgb(color.default_value))))
        source = color.links[0].from_node
        if source.bl_idname != "ShaderNodeTexEnvironment" or source.image is None:
            self.warn(f"the {source.bl_label} node")
            return S.EnvironmentTerm(tuple(float(c) for c in weight * np.array(_rgb(self.world.color))))
        key = image_key(source.image)
        data = self.snap.images.get(key) or IMAGES.get(key, source.image, self.snap.warnings)
        if data is None:  # no pixels (missing file): said in the warnings
            return S.EnvironmentTerm((0.0, 0.0, 0.0))
        self.snap.images[key] = data
        if source.interpolation not in ("Linear", "Closest"):
            self.snap.warnings.append(f"World '{self.world.name}': {source.interpolation} "
                                      f"interpolation of '{source.image.name}' is drawn as Linear")
        return S.EnvironmentTerm(tuple(float(c) for c in weight), data, source.projection,
                                 source.interpolation == "Closest", self.lookup(source.inputs["Vector"]))

    def lookup(self, vector) -> np.ndarray:
        """The texture-space vector as a 4x4 of the world direction (identity: Generated)."""
        if not vector.is_linked:
            return np.eye(4, dtype=np.float32)
        node = vector.links[0].from_node
        if node.bl_idname == "ShaderNodeTexCoord":
            if vector.links[0].from_socket.name != "Generated":
                self.warn(f"Texture Coordinate {vector.links[0].from_socket.name}")
            return np.eye(4, dtype=np.float32)
        if node.bl_idname != "ShaderNodeMapping":
            self.warn(f"the {node.bl_label} node")
            return np.eye(4, dtype=np.float32)
        from mathutils import Euler, Matrix

        values = {}
        for name in ("Location", "Rotation", "Scale"):
            socket = node.inputs.get(name)
            if socket is not None and socket.is_linked:
                self.warn(f"a link into {node.name}'s {name}")
            values[name] = tuple(socket.default_value) if socket is not None else (0.0, 0.0, 0.0)
        rotation = Euler(values["Rotation"], "XYZ").to_matrix().to_4x4()
        scale = Matrix.Diagonal((*values["Scale"], 1.0))
        location = Matrix.Translation(values["Location"])
        kind = node.vector_type
        if kind == "POINT":
            m = location @ rotation @ scale
        elif kind == "TEXTURE":
            m = (location @ rotation @ scale).inverted_safe()
        elif kind == "VECTOR":
            m = rotation @ scale
        else:  # NORMAL: the inverse transpose of rotation x scale (a direction, normalised later)
            m = (rotation @ scale).inverted_safe().transposed()
        inner = self.lookup(node.inputs["Vector"])
        return (np.array(m, np.float64) @ inner).astype(np.float32)


_SUNS: dict = {}  # split_suns results by the term's content (a few ms to a few tens of ms each)
_SUNS_LOCK = threading.Lock()


def _world_suns(terms, threshold: float, angle: float) -> tuple[S.Light, ...]:
    """The lighting field's brightest texels as suns (``environment.split_suns``), cached."""
    from ..reference import environment

    lights = []
    for term in S.World.images(terms)[:S.MAX_ENVIRONMENT_IMAGES]:
        key = (term.image.key, term.image.revision, tuple(term.weight), term.projection,
               np.asarray(term.lookup, np.float32).tobytes(), threshold)
        with _SUNS_LOCK:
            suns = _SUNS.get(key)
        if suns is None:
            suns = environment.split_suns(term, threshold)
            with _SUNS_LOCK:
                if len(_SUNS) > 16:
                    _SUNS.clear()
                _SUNS[key] = suns
        for direction, irradiance, _omega in suns:
            lights.append(S.Light("SUN", (0.0, 0.0, 0.0), tuple(-c for c in direction), irradiance,
                                  angle=angle, world=True, shadow=True))
    return tuple(lights)


def _baked_or_warned(world, snap: S.Snapshot, unreadable: list[str], camera, lighting):
    """A world with parts Shading Lab cannot read: its baked image (World > Shading Lab > Bake
    World) if it has one, with a warning when the world changed since; else what was read, the
    rest as the viewport colour, with a warning saying so."""
    from .world_bake import world_fingerprint

    props = getattr(world, "shading_lab", None)
    baked = props.baked_image if props is not None else None
    what = ", ".join(dict.fromkeys(unreadable))
    if baked is not None:
        data = IMAGES.get(image_key(baked), baked, snap.warnings)
        if data is not None:
            snap.images[image_key(baked)] = data
            if props.baked_fingerprint != world_fingerprint(world):
                snap.warnings.append(f"World '{world.name}' changed since it was baked: bake it again "
                                     f"(World > Shading Lab > Bake World)")
            term = (S.EnvironmentTerm((1.0, 1.0, 1.0), data, "EQUIRECTANGULAR"),)
            return term, term
    snap.warnings.append(f"World '{world.name}': {what} is not read by Shading Lab; it lights and shows "
                         f"as the world's viewport colour (World > Shading Lab > Bake World renders it "
                         f"into an image Shading Lab reads)")
    return camera, lighting


def world_environment(world, snap: S.Snapshot) -> S.World:
    """The world's radiance terms (see ``_WorldReader``) and, for the lighting field, the suns
    split off above Blender's World > Sun > Threshold; a missing world is black."""
    if world is None:
        return S.World()
    tree = _world_tree(world)
    if tree is None:
        term = (S.EnvironmentTerm(_rgb(world.color)),)
        return S.World(term, term)
    output = _world_output(tree)
    if output is None:
        return S.World()
    reader = _WorldReader(world, snap)
    camera, lighting = reader.shader(output.inputs["Surface"], np.ones(3), None)
    if reader.unreadable:
        camera, lighting = _baked_or_warned(world, snap, reader.unreadable, camera, lighting)
    for terms, label in ((camera, "seen by the camera"), (lighting, "lighting the scene")):
        if len(S.World.images(terms)) > S.MAX_ENVIRONMENT_IMAGES:
            snap.warnings.append(f"World '{world.name}': more than {S.MAX_ENVIRONMENT_IMAGES} "
                                 f"environment images {label}; the first {S.MAX_ENVIRONMENT_IMAGES} "
                                 f"are used")
    threshold = float(getattr(world, "sun_threshold", 10.0))  # EEVEE's setting, 10 by default
    suns = _world_suns(lighting, threshold, float(getattr(world, "sun_angle", 0.0))) if threshold > 0 else ()
    return S.World(tuple(camera), tuple(lighting), threshold, suns)


# --- the snapshot ------------------------------------------------------------------------------

def scene_settings(scene) -> S.Settings:
    props = getattr(scene, "shading_lab", None)
    if props is None:
        return S.Settings()
    terms = S.Terms(fresnel=props.fresnel, ndf=props.ndf, visibility=props.visibility, diffuse=props.diffuse,
                    multiscatter=bool(props.multiscatter),
                    normalized_blinn_phong=bool(props.normalized_blinn_phong),
                    principled=props.term_set == "PRINCIPLED")
    auto = None
    if props.exposure_mode == "AUTO":
        auto = S.AutoExposure(method=props.exposure_method, key=float(props.exposure_key),
                              low=float(props.exposure_low) / 100.0, high=float(props.exposure_high) / 100.0,
                              compensation=float(props.exposure), min_stops=float(props.exposure_min),
                              max_stops=float(props.exposure_max), brighter=float(props.adapt_brighter),
                              darker=float(props.adapt_darker))
    return S.Settings(model=props.model, terms=terms, ambient=float(props.ambient), auto_exposure=auto,
                      tone_mapper=props.tone_mapper, exposure=float(props.exposure), transfer=props.transfer,
                      samples=int(props.samples), compare_mode=props.compare_mode,
                      compare_models=(props.compare_a, props.compare_b),
                      compare_split=float(props.compare_split), compare_range=float(props.compare_range),
                      transparency_layers=int(props.transparency_layers),
                      environment_diffuse=props.world_diffuse,
                      ambient_world=props.ambient_source == "WORLD",
                      world_occlusion=bool(props.world_occlusion),
                      occlusion_distance=float(props.occlusion_distance),
                      occlusion_resolution=str(props.occlusion_resolution),
                      shadows=bool(props.shadows), shadow_map_size=int(props.shadow_map_size),
                      soft_shadows=bool(props.soft_shadows),
                      light_threshold=float(props.light_threshold), light_culling=bool(props.light_culling),
                      auto_error_bound=(float(props.auto_error_bound) if props.term_set == "AUTO" else None),
                      auto_quantile=float(props.auto_quantile) / 100.0,
                      environment_samples=(int(props.world_samples) if props.world_specular == "SAMPLED"
                                           else 0))


def final_render_settings(scene) -> S.Settings:
    """``scene_settings`` for a final render: with Blender's Persistent Data (Render > Performance),
    which only final renders honour (a viewport keeps its renderer anyway; previews keep nothing)."""
    return dataclasses.replace(scene_settings(scene),
                               persistent_data=bool(getattr(scene.render, "use_persistent_data", False)))


#: The artist's scene settings for previews, captured on the main thread (see ``remember_settings``).
_ARTIST_SETTINGS: list[S.Settings | None] = [None]


def remember_settings(scene) -> None:
    """Keep ``scene``'s settings for previews. Called where Blender runs add-on code on the main
    thread (property edits, depsgraph updates, file loads, registration) and by renders: a
    preview renders in a job thread, in Blender's own preview scene, where reading
    ``bpy.context`` is not safe."""
    if scene is not None and getattr(scene, "shading_lab", None) is not None:
        _ARTIST_SETTINGS[0] = scene_settings(scene)


def preview_settings(preview_scene) -> S.Settings:
    """Settings for a material, world or light preview.

    The scene Blender builds for a preview carries default Shading Lab settings, so the model and
    terms come from the artist's scene (the last one remembered): a preview shows what a render
    would. Previews are small and frequent: one sample per pixel, no A|B compare; and manual
    exposure (automatic exposure would meter a dark material up to middle grey).
    """
    artist = _ARTIST_SETTINGS[0]
    settings = artist if artist is not None else scene_settings(preview_scene)
    return dataclasses.replace(settings, samples=1, compare_mode="OFF", auto_exposure=None)


def geometry_updates(depsgraph) -> set[str]:
    """Names of the original objects and meshes whose geometry this depsgraph update changed.

    A transform-only edit sets ``is_updated_transform`` alone and adds nothing here; a material
    edit tags the meshes using it for shading only, which adds nothing either.
    """
    dirty: set[str] = set()
    for update in depsgraph.updates:
        idb = update.id
        if isinstance(idb, (bpy.types.Object, bpy.types.Mesh)) and update.is_updated_geometry:
            dirty.add(idb.original.name_full)
    return dirty


def material_updates(depsgraph) -> set[str] | None:
    """Full names of the materials this depsgraph update changed (their values, their node trees);
    None where something every material may read changed (a node group, an image): read them all."""
    names: set[str] = set()
    for update in depsgraph.updates:
        idb = update.id
        if isinstance(idb, bpy.types.Material):
            names.add(idb.original.name_full)
        elif isinstance(idb, bpy.types.Image) or (isinstance(idb, bpy.types.NodeTree)
                                                   and not idb.is_embedded_data):
            return None  # (a material's own tree comes with the material)
    return names


def _is_dirty(obj, dirty: set[str] | None) -> bool:
    if dirty is None:
        return True
    if obj.original.name_full in dirty:
        return True
    data = obj.data
    return data is not None and data.original is not None and data.original.name_full in dirty


def snapshot(depsgraph, width: int | None = None, height: int | None = None,
             camera: S.Camera | None = None, settings: S.Settings | None = None,
             previous: S.Snapshot | None = None, dirty: set[str] | None = None,
             auto_camera: S.Camera | None = None, auto_choice: bool = True,
             aovs: bool = False, materials_dirty: set[str] | None = None,
             bakes_only: bool = False) -> S.Snapshot:
    """Everything the renderer draws, read from the evaluated scene.

    ``camera`` may be given (the viewport passes its own); otherwise the scene camera is used
    and its absence raises ``ExtractError``. With ``previous`` and ``dirty`` (from
    ``geometry_updates``), geometry of objects not named in ``dirty`` is reused from
    ``previous`` instead of read again; ``Snapshot.fresh`` lists the geometry keys read anew; with
    ``previous`` and ``materials_dirty`` (from ``material_updates``: not None), the materials it
    does not name are taken from ``previous`` (their node graphs are not read nor compiled again).
    Lights, materials, matrices and the world are cheap and always read. With the Auto term set,
    materials get their terms chosen as seen from ``auto_camera`` (else ``camera``), unless
    ``auto_choice`` is off (a viewport that has drawn no view yet chooses at its first draw).
    With ``bakes_only``, only the objects a material of which has fallback bakes are read, for
    their ``bake_requests`` (F12's bake steps: the others' evaluated meshes are not even asked for,
    which would subdivide them).
    """
    scene = depsgraph.scene
    if width is None or height is None:
        width, height = render_size(scene)
    if camera is None:
        if scene.camera is None:
            raise ExtractError("The scene has no active camera: add one or set Scene > Camera")
        camera = make_camera(depsgraph, scene.camera, width, height)
    snap = S.Snapshot(
        camera=camera,
        width=width,
        height=height,
        settings=settings or scene_settings(scene),
    )
    # the evaluated world: its animated values as this frame has them (an animation render job
    # evaluates frames without writing them back to the original data)
    snap.world = world_environment(depsgraph.scene_eval.world, snap)
    snap.world_color = S.World.constant(snap.world.camera)
    snap.lights.extend(snap.world.suns)
    snap.materials[""] = S.DEFAULT_MATERIAL
    if aovs:  # a final render writes the view layer's AOVs (each name once, as Blender keeps them)
        snap.aovs = list({aov.name: (aov.name, aov.type) for aov in depsgraph.view_layer.aovs
                          if aov.name and getattr(aov, "is_valid", True)}.values())
    aov_names = {name for name, _ in snap.aovs}
    reusable = previous.geometries if previous is not None else {}
    skipped_empty: set[str] = set()
    skipped_kinds: Counter = Counter()
    for inst in depsgraph.object_instances:
        obj = inst.object
        if obj.type == "LIGHT":
            if obj.data.type in LIGHT_KIND:
                snap.lights.append(make_light(obj.data, inst.matrix_world))
            continue
        # Curves, surfaces, text, metaballs and geometry-node output reach the depsgraph as mesh
        # instances of their own, beside the source object: take geometry from meshes only, or
        # they are drawn twice (Cycles' BlenderSync::object_is_geometry does the same).
        if obj.type != "MESH":
            if obj.type in UNDRAWN_KINDS:
                skipped_kinds[obj.type] += 1
            continue
        if not inst.show_self:  # an instancer its instances hide (Show Instancer off), as Cycles skips it
            continue
        if bakes_only and not _bakes_in(obj):
            continue
        key = _geometry_key(obj)
        if key in skipped_empty:
            continue
        slots = []
        for slot in obj.material_slots:
            mat = slot.material
            mkey = mat.name_full if mat is not None else ""
            if mkey not in snap.materials:
                kept = previous.materials.get(mkey) if previous is not None and materials_dirty is not None \
                    and mkey not in materials_dirty else None
                if kept is not None:  # unchanged since the last snapshot: not read (nor compiled) again
                    snap.materials[mkey] = kept
                    snap.warnings.extend(previous.material_warnings.get(mkey, ()))
                    snap.material_warnings[mkey] = previous.material_warnings.get(mkey, [])
                    graphs = ([kept.graph] if kept.graph is not None else []) + [g for _, g in kept.aovs]
                    snap.images.update((key, previous.images[key]) for g in graphs for key in g.images
                                       if key in previous.images)
                else:
                    said = len(snap.warnings)
                    snap.materials[mkey] = _material_with_images(snap, mat)
                    snap.material_warnings[mkey] = snap.warnings[said:]
            slots.append(mkey)
        if key not in snap.geometries:
            geometry = reusable.get(key)
            graphs = [snap.materials[m].graph for m in slots if snap.materials[m].graph is not None]
            if aov_names:  # the AOV Outputs' graphs the frame draws
                graphs += [g for m in slots for name, g in snap.materials[m].aovs if name in aov_names]
            tangents = any("tangent" in g.program.uses for g in graphs)
            wanted = {a for g in graphs for a in g.attributes}
            generated = any("generated" in g.program.uses for g in graphs)
            if geometry is None or _is_dirty(obj, dirty) or (tangents and geometry.tangents is None) or \
                    not wanted <= geometry.attributes.keys() or (generated and not geometry.orco_read):
                mesh = obj.to_mesh()
                try:
                    geometry = (mesh_geometry(key, mesh, tangents, _memo_key(obj))
                                if mesh is not None else None)
                    if geometry is not None and wanted:
                        geometry = with_attributes(geometry, mesh, wanted, snap.warnings)
                    if geometry is not None and generated:
                        geometry = with_orco(geometry, obj, mesh, depsgraph, snap.warnings)
                finally:
                    obj.to_mesh_clear()
                if geometry is None:
                    skipped_empty.add(key)
                    continue
                snap.fresh.add(key)
                if tangents and geometry.tangents is None:
                    snap.warnings.append(f"Mesh '{obj.data.name}': its normal map is not drawn (Blender "
                                         f"gives tangents to triangles and quads with a UV map only: "
                                         f"triangulate its n-gons or add a UV map)")
            snap.geometries[key] = geometry
        data = obj.data
        slots = _fallback_slots(snap, inst, slots, key, depsgraph)
        if surface.ORCO in snap.geometries[key].attributes:  # deformed: Generated from its orco
            slots = [_with_orco(snap, m) for m in slots]
        graphs = [g for m in slots for g in (snap.materials[m].graph, *(g for _, g in snap.materials[m].aovs))
                  if g is not None]
        wanted = {a for g in graphs for a in g.uniform_attributes}
        attributes = {a: uniform_attribute(*a, inst, depsgraph.view_layer, depsgraph.scene) for a in wanted}
        snap.items.append(S.DrawItem(key, _matrix(inst.matrix_world), slots or [""],
                                     casts_shadow=bool(getattr(obj, "visible_shadow", True)),
                                     texspace=(tuple(data.texspace_location), tuple(data.texspace_size)),
                                     color=tuple(float(c) for c in obj.color), pass_index=int(obj.pass_index),
                                     random=instance_random(inst), attributes=attributes))
    # before the shadow maps: they fit to the reaches; the scene's box only where a reach needs it
    def box():
        return shadows.scene_bounds(snap, {key: geometry.bounds for key, geometry in snap.geometries.items()})

    snap.lights[:] = programs.light_reaches(snap.lights, snap.settings.light_threshold, box)
    _first, _layers, dropped = shadows.assign(snap)
    if dropped:
        snap.warnings.append(f"{dropped} shadowed light(s) cast no shadow: a frame holds "
                             f"{shadows.MAX_SHADOW_LAYERS} shadow maps (point and area lights take six)")
    skipped = {kind: count for kind, count in skipped_kinds.items() if count}
    if skipped:
        snap.warnings.append("Not drawn (Shading Lab draws meshes): " + ", ".join(
            f"{count} {UNDRAWN_KINDS[kind]}" for kind, count in sorted(skipped.items())))
    if len(snap.lights) > S.MAX_LIGHTS:
        snap.warnings.append(f"{len(snap.lights):,} lights: the first {S.MAX_LIGHTS:,} are drawn, the rest "
                             f"left out")
        del snap.lights[S.MAX_LIGHTS:]
    snap.warnings[:] = dict.fromkeys(snap.warnings)  # each once, however many objects share it
    if snap.settings.auto_error_bound is not None and auto_choice:
        choose_terms(snap, previous.term_choices if previous is not None else None, auto_camera)
    return snap


# --- the baked fallback (addon/blender/bake.py) -------------------------------------------------

def _graphs(params: S.MaterialParams) -> list:
    return ([params.graph] if params.graph is not None else []) + [g for _, g in params.aovs]


def bake_resolution(scene) -> int:
    """The resolution of the scene's fallback bakes (Render properties > Shading Lab > Bake)."""
    props = getattr(scene, "shading_lab", None)
    return int(getattr(props, "bake_resolution", bake.RESOLUTION))


def _fallback_slots(snap: S.Snapshot, inst, slots: list[str], key: str, depsgraph) -> list[str]:
    """The object's material slots, each with the fallback bakes the cache holds (a material of
    its own: ``_with_bakes``; the outputs not baked yet keep their socket values); a slot still
    waiting for bakes has its request in ``snap.bake_requests``. An object whose mesh cannot hold
    a bake (no UV map) keeps the socket values, and the warnings say why."""
    geometry = snap.geometries[key]
    obj = inst.object
    owner = obj.original.name_full if obj.original is not None else obj.name_full
    out = []
    for k, mkey in enumerate(slots):
        params = snap.materials[mkey]
        targets = list({(t.node, t.socket): t for g in _graphs(params) for t in g.bakes}.values())
        if not targets:
            out.append(mkey)
            continue
        labels = ", ".join(t.label for t in targets)
        problem = bake.uv_problem(geometry)
        if problem:
            bake.UNBAKEABLE[(owner, mkey)] = problem
            bake.REQUESTS.pop((owner, mkey), None)
            snap.warnings.append(f"Object '{obj.name}', material '{params.name}': {labels} not compiled and "
                                 f"not baked ({problem}): what they feed takes its socket's value")
            out.append(mkey)
            continue
        bake.UNBAKEABLE.pop((owner, mkey), None)
        for note in bake.uv_notes(geometry):
            snap.warnings.append(f"Object '{obj.name}', material '{params.name}': {labels} baked, but {note}")
        texspace = (tuple(obj.data.texspace_location), tuple(obj.data.texspace_size)) \
            if hasattr(obj.data, "texspace_location") else ()
        resolution = bake_resolution(depsgraph.scene)
        matrix = tuple(tuple(float(v) for v in row) for row in inst.matrix_world)
        placement = repr((matrix, owner, tuple(obj.color), obj.pass_index))
        mesh = bake.mesh_digest(geometry, texspace)
        uv = obj.data.uv_layers.active.name
        scene = depsgraph.scene
        keys = tuple(bake.key(t, mesh, resolution, placement, bake.inputs_digest(t, geometry, snap.images))
                     for t in targets)
        request = bake.Request(owner, mkey, tuple(targets), keys, uv, resolution, matrix,
                               scene.frame_current + scene.frame_subframe, len(snap.items), k)
        bake.REQUESTS[(owner, mkey)] = request
        variant, waiting = _with_bakes(snap, request)
        if waiting:
            snap.bake_requests.append(request)
        out.append(variant or mkey)
    return out


def _with_bakes(snap: S.Snapshot, request) -> tuple[str | None, bool]:
    """The key of ``request``'s material with the bakes the cache holds sampled (added to
    ``snap.materials``, the baked pixels to ``snap.images``; None where it holds none of them:
    the material as it is), and whether a bake is still missing (the outputs not baked keep their
    socket values: a bake that failed, or F12's bakes stopped, leaves the others drawn)."""
    found = [bake.CACHE.get(k) for k in request.keys]
    waiting = any(b is None for b in found)
    baked = {(t.node, t.socket): k for t, k, b in zip(request.targets, request.keys, found) if b is not None}
    if not baked:
        return None, waiting
    variant = f"{request.material}\x1f{hashlib.sha1(repr(sorted(baked.items())).encode()).hexdigest()[:16]}"
    if variant not in snap.materials:
        params = snap.materials[request.material]
        graph = surface.with_bakes(params.graph, baked) if params.graph is not None else None
        aovs = tuple((name, surface.with_bakes(g, baked)) for name, g in params.aovs)
        snap.materials[variant] = dataclasses.replace(params, graph=graph, aovs=aovs)
        snap.material_warnings[variant] = snap.material_warnings.get(request.material, [])
        if request.material in snap.term_choices:
            snap.term_choices[variant] = snap.term_choices[request.material]
    for b in found:
        if b is not None:
            snap.images[b.image.key] = b.image
    return variant, waiting


def _with_orco(snap: S.Snapshot, mkey: str) -> str:
    """The key of material ``mkey`` as drawn on a deformed mesh (``surface.with_orco``: Generated
    from its undeformed positions; added to ``snap.materials``); ``mkey`` where none of its graphs
    reads Generated."""
    params = snap.materials[mkey]
    if not any("generated" in g.program.uses for g in _graphs(params)):
        return mkey
    variant = f"{mkey}\x1forco"
    if variant not in snap.materials:
        graph = surface.with_orco(params.graph) if params.graph is not None else None
        aovs = tuple((name, surface.with_orco(g)) for name, g in params.aovs)
        snap.materials[variant] = dataclasses.replace(params, graph=graph, aovs=aovs)
        snap.material_warnings[variant] = snap.material_warnings.get(mkey, [])
        if mkey in snap.term_choices:
            snap.term_choices[variant] = snap.term_choices[mkey]
    return variant


def apply_bakes(snap: S.Snapshot) -> int:
    """Give the draw items whose bakes have since been made their materials with the bakes
    (``snap.bake_requests`` keeps those still missing one); how many slots changed."""
    changed, waiting = 0, []
    for request in snap.bake_requests:
        variant, missing = _with_bakes(snap, request)
        if missing:
            waiting.append(request)
        if variant is None:
            continue
        item = snap.items[request.item]
        if surface.ORCO in snap.geometries[item.geometry].attributes:  # deformed (snapshot's slots)
            variant = _with_orco(snap, variant)
        item.materials[request.slot] = variant
        changed += 1
    snap.bake_requests[:] = waiting
    return changed


#: What ``fallback_materials`` last found of each material: full name -> (its read,
#: ``nodes.read_material``, and ``codegen.FORCE_BAKE`` then; its bakes' labels).
FALLBACK_READS: dict[str, tuple] = {}


def fallback_materials(depsgraph) -> dict[str, tuple[str, ...]]:
    """The materials that the view layer's objects use and whose graphs have node outputs Cycles
    bakes (``MaterialGraph.bakes``), each with the bakes' labels: what F12 asks before it renders,
    reading no object's geometry. The objects: the view layer's (those the viewport hides too) and
    ``depsgraph``'s evaluated ones (instanced collections', materials geometry nodes set). A
    material is compiled again only where its nodes read differently from the last time."""
    materials = {}
    for obj in [*depsgraph.view_layer.objects, *depsgraph.objects]:
        for slot in getattr(obj, "material_slots", ()):
            material = slot.material
            if material is not None and material.original is not None:
                materials.setdefault(material.original.name_full, material.original)
    found = {name: _fallback_labels(material) for name, material in materials.items()}
    return {name: labels for name, labels in found.items() if labels}


def _fallback_labels(material) -> tuple[str, ...]:
    """The labels of the bakes the graphs of ``material`` (an original) have ("Node > Output"),
    compiled again only where its nodes read differently from the last time (``FALLBACK_READS``)."""
    read = nodes.read_material(material)
    if read is None:
        return ()
    known = FALLBACK_READS.get(material.name_full)
    if known is not None and known[0] == (read, codegen.FORCE_BAKE):
        return known[1]
    graphs = [surface.compile_material(*read), *surface.compile_aovs(*read).values()]
    labels = tuple(dict.fromkeys(t.label for g in graphs if g is not None for t in g.bakes))
    FALLBACK_READS[material.name_full] = ((read, codegen.FORCE_BAKE), labels)
    return labels


def _bakes_in(obj) -> bool:
    """Whether a material of ``obj`` (evaluated) has bakes (``_fallback_labels``)."""
    return any(slot.material is not None and slot.material.original is not None
               and _fallback_labels(slot.material.original) for slot in obj.material_slots)


def choose_terms(snap: S.Snapshot, previous: dict | None = None, camera: S.Camera | None = None) -> None:
    """The Auto term set's choice per material (``auto_terms.choose``), fixed into ``snap``."""
    settings = snap.settings
    auto_terms.apply(snap, auto_terms.choose(snap, settings.auto_error_bound, settings.auto_quantile,
                                             previous, camera))


def _material_with_images(snap: S.Snapshot, material) -> S.MaterialParams:
    """``material_params``, with the pixels of the images its graph samples added to
    ``snap.images`` (an image without pixels is said in ``snap.warnings`` and drawn as Blender
    draws a missing image)."""
    found: dict = {}
    params = material_params(material, found, snap.warnings)
    graphs = ([params.graph] if params.graph is not None else []) + [g for _, g in params.aovs]
    keys = {key for g in graphs for entry in g.images for key in codegen.sampler_keys(entry)}
    for key in sorted(keys):
        if key not in snap.images:
            data = IMAGES.get(key, found[key], snap.warnings)
            if data is not None:
                snap.images[key] = data

    def kind(tile: S.ImageData) -> tuple:  # what one 2D array holds alike (half floats with floats)
        return tile.size, "FLOAT" if tile.storage == "HALF" else tile.storage

    for entry in {entry for g in graphs for entry in g.images if isinstance(entry, tuple)}:
        tiles = {key: snap.images[key] for key in entry if key in snap.images}  # a UDIM image's 2D array
        first = next(iter(tiles.values()), None)
        odd = [key.rsplit("#", 1)[1] for key, tile in tiles.items() if kind(tile) != kind(first)]
        if odd:  # gpu_scene.array_texture draws them as missing
            snap.warnings.append(f"Image '{found[entry[0]].name_full}': UDIM tiles {', '.join(odd)} are not "
                                 f"of the first tile's size ({first.size[0]} x {first.size[1]}) and kind of "
                                 f"pixels: they are drawn as missing images")
    return params
