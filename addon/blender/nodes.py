"""Reads a material's shader node tree into plain data (``scene.nodes``) for the material compiler:
nodes with their settings and available sockets by identifier, the links Blender evaluates, the
output in use, and the trees of the node groups it uses (nested ones too), each read once.

What Blender evaluates: a link that is muted, invalid (a cycle, a shader into a value socket) or
touches an unavailable socket (a Mix node's inputs of another data type, a Math node's unused
second value) carries nothing; a muted node passes on its ``internal_links``; the material's
output is the one Blender's ``get_output_node`` picks for the target (``ALL`` outputs serve every
renderer, an ``EEVEE`` or ``CYCLES`` one is preferred by its renderer).
"""

from __future__ import annotations

import bpy
import numpy as np

from ..materials import convert
from ..scene import nodes as N
from .images import image_key

#: The output target a material is read for (Material Output > Target): EEVEE's outputs, as the
#: engine draws what EEVEE draws; ``ALL`` outputs serve it where the file has no EEVEE one.
TARGET = "EEVEE"

#: Properties every node has, which choose nothing it computes.
_NODE_PROPS = {prop.identifier for prop in bpy.types.ShaderNode.bl_rna.properties} | {"rna_type"}
#: Nodes whose outputs hold the value they give (the output socket's own value; the Normal node's
#: direction is its Normal output's value).
_VALUE_NODES = ("ShaderNodeValue", "ShaderNodeRGB", "ShaderNodeNormal")
#: Property kinds the compiler reads (pointers such as an Image Texture's image are read apart).
_VALUE_PROPS = {"ENUM", "BOOLEAN", "INT", "FLOAT", "STRING"}


def _available(socket) -> bool:
    """Blender 5 says ``is_unavailable``; 4.x ``enabled``."""
    unavailable = getattr(socket, "is_unavailable", None)
    return not unavailable if unavailable is not None else bool(getattr(socket, "enabled", True))


def _default(socket):
    value = getattr(socket, "default_value", None)
    if value is None or isinstance(value, (str, bool, int, float)):
        return value
    try:
        return tuple(float(v) for v in value)
    except TypeError:  # a datablock pointer (an object, an image socket's image)
        return None


def _identity_mapping(mapping) -> bool:
    """Whether a texture node's own Texture Mapping (Blender's TexMapping, which Cycles applies
    before the texture) leaves the coordinate unchanged (or the node has none)."""
    if mapping is None:
        return True
    return (tuple(mapping.translation) == (0.0, 0.0, 0.0) and tuple(mapping.rotation) == (0.0, 0.0, 0.0)
            and tuple(mapping.scale) == (1.0, 1.0, 1.0) and not mapping.use_min and not mapping.use_max
            and (mapping.mapping_x, mapping.mapping_y, mapping.mapping_z) == ("X", "Y", "Z")
            and mapping.mapping == "FLAT")


def _props(node) -> dict:
    out = {}
    for prop in node.bl_rna.properties:
        name = prop.identifier
        if name in _NODE_PROPS or prop.type not in _VALUE_PROPS or name.startswith("bl_"):
            continue
        value = getattr(node, name, None)
        if prop.type in ("INT", "FLOAT") and getattr(prop, "is_array", False):
            value = tuple(value)
        out[name] = value
    if not _identity_mapping(getattr(node, "texture_mapping", None)):
        out["texture_mapping"] = True  # a texture node's own mapping (its sidebar): not compiled
    target = getattr(node, "object", None) if node.bl_idname == "ShaderNodeTexCoord" else None
    if target is not None:  # Texture Coordinate > Object in another object's space: its matrix, read now
        out["object_matrix"] = tuple(tuple(float(v) for v in row) for row in target.matrix_world.inverted())
    return out


def _ramp(node) -> dict:
    """A Color Ramp as Cycles bakes it (intern/cycles/blender/util.h colorramp_to_array): the ramp
    Blender evaluates (BKE_colorband_evaluate: every interpolation and colour mode) at i / SIZE,
    i = 0 .. SIZE; interpolated between entries unless the ramp is Constant."""
    ramp = node.color_ramp
    size = N.RAMP_TABLE_SIZE
    table = tuple(tuple(float(c) for c in ramp.evaluate(i / size)) for i in range(size + 1))
    return {"table": table, "interpolate": ramp.interpolation != "CONSTANT"}


def _curves(node, count: int, compose: bool) -> dict:
    """Curves as Cycles bakes them (util.h curvemapping_color_to_array, curvemapping_float_to_array):
    each of the first ``count`` curves at SIZE + 1 positions spanning the x range of all their
    points (min .. max, evaluated in float as Cycles does), the C curve first where ``compose``
    (RGB Curves: R(C(x)) ...); one row per position, a float curve's value in x. BKE_curvemap_evaluateF
    extends each curve past its points as the curve says (Extend)."""
    mapping = node.mapping
    mapping.update()  # what Cycles calls first (BKE_curvemapping_changed_all), then the tables
    mapping.initialize()
    curves = list(mapping.curves)[:count + (1 if compose else 0)]
    lo = min(c.points[0].location[0] for c in curves)
    hi = max(c.points[-1].location[0] for c in curves)
    size = N.RAMP_TABLE_SIZE
    i = np.arange(size + 1, dtype=np.float32)
    xs = np.float32(lo) + i / np.float32(size) * (np.float32(hi) - np.float32(lo))
    table = []
    for x in xs.tolist():
        if compose:
            x_c = mapping.evaluate(curves[3], x)
            row = [mapping.evaluate(c, x_c) for c in curves[:3]]
        else:
            row = [mapping.evaluate(c, x) for c in curves[:count]]
        table.append(tuple(float(v) for v in row))
    return {"table": tuple(table), "range": (float(lo), float(hi)),
            "extrapolate": mapping.extend == "EXTRAPOLATED"}


#: Nodes whose data the compiler reads beyond their properties: ramps and curves, baked as Cycles
#: bakes them (their tables are constants of the compiled graph), and the colour matrices of
#: the Blender that reads them.
_BAKED = {
    "ShaderNodeValToRGB": _ramp,
    "ShaderNodeRGBCurve": lambda node: _curves(node, 3, True),
    "ShaderNodeVectorCurve": lambda node: _curves(node, 3, False),
    "ShaderNodeFloatCurve": lambda node: _curves(node, 1, False),
    "ShaderNodeWavelength": lambda node: {"xyz_to_rgb": xyz_to_rgb()},
    "ShaderNodeTexVoronoi": lambda node: {"voronoi_cells": voronoi_cells()},
    "ShaderNodeTexWave": lambda node: {"wave_phase": wave_phase()},
}


def xyz_to_rgb() -> tuple[tuple[float, float, float], ...]:
    """CIE XYZ to scene linear (Rec. 709) as this Blender's Cycles holds it (its xyz_to_rgb)."""
    return convert.XYZ_TO_RGB if bpy.app.version >= (5, 0, 0) else convert.XYZ_TO_RGB_4


def voronoi_cells() -> str:
    """How this Blender's Cycles hashes a Voronoi cell in 2D-4D: 5.0 its integer index (``INT``),
    4.x its float coordinates (``FLOAT``)."""
    return "INT" if bpy.app.version >= (5, 0, 0) else "FLOAT"


def wave_phase() -> str:
    """How this Blender's Cycles takes a Wave Texture's saw and triangle phase over 2 pi (wave.h's
    n /= M_2PI_F): 4.5 and 5.0 as a product with the reciprocal (``RECIPROCAL``, its kernel's fast
    math), 4.2 as a division rounded once (``DIVIDE``); measured against each wheel's Cycles (4.3
    and 4.4, not measured, taken as 4.5)."""
    return "RECIPROCAL" if bpy.app.version >= (4, 3, 0) else "DIVIDE"


def luma() -> tuple[float, float, float]:
    """A colour's weights read as a float, as this Blender's Cycles holds them (its rgb_to_y:
    Blender 5's colour management moved them)."""
    return convert.LUMA if bpy.app.version >= (5, 0, 0) else convert.LUMA_4


def _group_key(tree) -> str:
    """A node group's identity in the file: its full name (a linked library's groups repeat names)."""
    return tree.name_full


def _image_props(node, images: dict | None) -> dict:
    """An Image Texture node's image as the compiler needs it: its key (``images.image_key``, the
    key of its pixels in ``Snapshot.images``; None without an image), and what decides how Cycles
    reads its texels: alpha mode, colour space (and whether it is data), float or bytes, source
    (``TILED``: a UDIM image, with its tile numbers and sizes). The image goes into ``images`` by key."""
    image = getattr(node, "image", None)
    if image is None:
        return {"image": None}
    key = image_key(image)
    if images is not None:
        images[key] = image
    settings = image.colorspace_settings
    tiled = image.source == "TILED"
    return {"image": key, "image_alpha_mode": image.alpha_mode, "image_colorspace": settings.name,
            "image_is_data": bool(settings.is_data), "image_is_float": bool(image.is_float),
            "image_source": image.source,
            "image_tiles": tuple(sorted(tile.number for tile in image.tiles)) if tiled else (),
            # each tile's size (Blender loads the tile to say it; 0 x 0: a tile without pixels)
            "image_tile_sizes": tuple(tuple(t.size) for t in sorted(image.tiles, key=lambda t: t.number))
            if tiled else ()}


def read_node(node, images: dict | None = None) -> N.Node:
    """One node as plain data; an Image Texture's image goes into ``images`` (key -> image)."""
    inputs = {s.identifier: N.Socket(s.identifier, s.type, _default(s)) for s in node.inputs
              if _available(s) and s.identifier != "__extend__"}
    outputs = {s.identifier: s.type for s in node.outputs if _available(s) and s.identifier != "__extend__"}
    passes = tuple((link.from_socket.identifier, link.to_socket.identifier) for link in node.internal_links) \
        if node.mute else ()
    tree = getattr(node, "node_tree", None) if node.bl_idname == N.GROUP else None
    values = {s.identifier: _default(s) for s in node.outputs} if node.bl_idname in _VALUE_NODES else {}
    props = _props(node)
    if node.bl_idname == "ShaderNodeTexImage":
        props.update(_image_props(node, images))
    baked = _BAKED.get(node.bl_idname)
    if baked is not None:
        props.update(baked(node))
    return N.Node(name=node.name, kind=node.bl_idname, inputs=inputs, outputs=outputs, props=props,
                  muted=bool(node.mute), passes=passes, group=_group_key(tree) if tree is not None else None,
                  active_output=bool(getattr(node, "is_active_output", False)),
                  values=values)


def _groups_in(tree) -> list:
    return [node.node_tree for node in tree.nodes if node.bl_idname == N.GROUP and node.node_tree is not None]


def read_tree(tree, output=None, images: dict | None = None) -> N.Graph:
    """One tree as plain data; ``output``: the name of its output node in use (None for a group);
    the images its Image Texture nodes read go into ``images`` (key -> ``bpy.types.Image``)."""
    nodes = {node.name: read_node(node, images) for node in tree.nodes}
    links = []
    for link in tree.links:
        if link.is_muted or not link.is_valid or link.from_node is None or link.to_node is None:
            continue
        if not (_available(link.from_socket) and _available(link.to_socket)):
            continue
        links.append(N.Link(link.from_node.name, link.from_socket.identifier,
                            link.to_node.name, link.to_socket.identifier))
    return N.Graph(nodes, tuple(links), output)


def read_material(material, target: str = TARGET,
                  images: dict | None = None) -> tuple[N.Graph, dict[str, N.Graph]] | None:
    """A material's tree and its node groups' trees (by ``_group_key``), nested ones too; None for
    a material without a node tree. The images its Image Texture nodes read (in groups too) are
    added to ``images`` (``images.image_key`` -> ``bpy.types.Image``), as
    ``materials.material_params`` adds its maps'."""
    tree = getattr(material, "node_tree", None)
    if tree is None:
        return None
    output = tree.get_output_node(target)
    graph = read_tree(tree, output.name if output is not None else None, images)
    graph = N.Graph(graph.nodes, graph.links, graph.output, luma(), mute_converts=bpy.app.version < (5, 0, 0),
                    version=tuple(bpy.app.version[:2]))
    groups: dict[str, N.Graph] = {}
    pending = _groups_in(tree)
    while pending:
        group = pending.pop()
        key = _group_key(group)
        if key in groups:
            continue
        groups[key] = read_tree(group, images=images)
        pending += _groups_in(group)
    return graph, groups
