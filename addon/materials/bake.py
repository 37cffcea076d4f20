"""The baked fallback's plain data (issue #52): what of a material's graph the compiler cannot
compile and Cycles bakes instead, and how a bake is measured. Pure: no ``bpy``.

A node no emitter compiles (``codegen.compile_graph``: a Script node, Sky on a surface, Bevel,
Ambient Occlusion, a texture node whose own Texture Mapping is set ...) leaves its readers their
socket values. Where such a node's output is read by a node that did compile (or by an AOV
Output), that output is a **bake target**: the subgraph above it (the node and everything it
reads) is baked by Cycles into an image on the object's UV map -- the socket's value emitted,
as Blender's own Emit bakes do -- and the compiled graph samples that image at the UV in its
place (``codegen``: ``baked`` maps (node, output) to the image's key). A not-compiled node that
feeds only other not-compiled nodes is part of their bake, not a target of its own.

A bake is kept by its **content** (``BakeTarget.content``: the flat subgraph's nodes, settings
and values, hashed), the mesh and the resolution (the Blender layer adds those, and the object's
placement where the subgraph reads it: ``BakeTarget.placed``).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from .codegen import upstream
from .graph import FlatGraph, Ref

#: Socket types a bake holds (a colour's RGB, a vector's XYZ, a float in R); shaders are not baked.
BAKED_TYPES = ("VALUE", "INT", "BOOLEAN", "VECTOR", "RGBA")

#: Nodes whose value depends on where the object is, how it is seen, or on the scene around it:
#: a subgraph holding one is kept per object placement too (``BakeTarget.placed``).
PLACED_KINDS = frozenset({
    "ShaderNodeNewGeometry", "ShaderNodeObjectInfo", "ShaderNodeCameraData", "ShaderNodeLightPath",
    "ShaderNodeVectorTransform", "ShaderNodeLayerWeight", "ShaderNodeFresnel", "ShaderNodeNormalMap",
    "ShaderNodeBump", "ShaderNodeTangent", "ShaderNodeAmbientOcclusion", "ShaderNodeBevel",
    "ShaderNodeWireframe", "ShaderNodeTexSky", "ShaderNodeTexEnvironment", "ShaderNodeTexIES",
    "ShaderNodeScript", "ShaderNodeTexPointDensity", "ShaderNodeParticleInfo", "ShaderNodeHairInfo",
    "ShaderNodePointInfo", "ShaderNodeVolumeInfo", "ShaderNodeAttribute", "ShaderNodeTexCoord",
})
#: Of those, the ones that read the view (a bake sees the surface along its normal, as Cycles'
#: bakes do: kernel/integrator/init_from_bake.h casts the ray along -N).
VIEW_KINDS = frozenset({"ShaderNodeCameraData", "ShaderNodeLayerWeight", "ShaderNodeFresnel",
                        "ShaderNodeLightPath", "ShaderNodeWireframe"})
#: Texture Coordinate and Geometry outputs that read the view, and those that only the mesh gives.
_VIEW_OUTPUTS = {"ShaderNodeTexCoord": {"Camera", "Window", "Reflection"},
                 "ShaderNodeNewGeometry": {"Incoming"}}
_LOCAL_OUTPUTS = {"ShaderNodeTexCoord": {"Generated", "UV", "Normal", "Object"},
                  "ShaderNodeNewGeometry": {"Pointiness", "Random_Per_Island", "Parametric", "Backfacing"}}


@dataclass(frozen=True)
class BakeTarget:
    """One output a bake stands in for: flat node ``node``'s output ``socket`` (of ``type``);
    ``content``: the subgraph's hash; ``nodes``: the not-compiled nodes inside it (flat names), the
    reason it is baked; ``placed``: it reads the object's placement or the scene around it (kept
    per placement); ``view``: it reads the view (baked as seen along the normal)."""

    node: str
    socket: str
    type: str
    content: str
    nodes: tuple[str, ...]
    placed: bool = False
    view: bool = False
    #: the images (keys in ``Snapshot.images``) and mesh attributes ((kind, name)) it reads: their
    #: contents are part of what a bake is kept by (the Blender layer adds them)
    images: tuple[str, ...] = ()
    attributes: tuple[tuple[str, str], ...] = ()

    @property
    def label(self) -> str:
        """The node as the artist names it, with its output: "Noise Texture > Color"."""
        return f"{self.node.rsplit('/', 1)[-1]} > {self.socket}"


def _reads(flat: FlatGraph, names: list[str]) -> dict[str, set[str]]:
    """The outputs of each of ``names`` that the others of ``names`` read."""
    within = set(names)
    out: dict[str, set[str]] = {n: set() for n in names}
    for name in names:
        for spec in flat.nodes[name].inputs.values():
            if isinstance(spec.source, Ref) and spec.source.node in within:
                out[spec.source.node].add(spec.source.socket)
    return out


def _digest(flat: FlatGraph, names: list[str], node: str, socket: str) -> str:
    """The subgraph's content: each node's kind, settings, inputs (where they come from, their
    values) and its own values, in order, and the output baked."""
    h = hashlib.sha1(f"{node}\x00{socket}".encode())
    for name in names:
        n = flat.nodes[name]
        inputs = sorted((s, i.type, repr(i.source), repr(i.default)) for s, i in n.inputs.items())
        h.update(repr((n.name, n.kind, sorted(n.props.items(), key=lambda kv: kv[0]), inputs,
                       sorted(n.outputs.items()), sorted(n.values.items()))).encode())
    return h.hexdigest()[:20]


def target(flat: FlatGraph, node: str, socket: str, missing: set[str], emitted: frozenset[str]) -> BakeTarget:
    """The bake target of flat node ``node``'s output ``socket``; ``missing``: the flat graph's
    nodes that did not compile; ``emitted``: the node kinds the compiler has emitters for (a kind
    it does not know counts as placed: what it reads is unknown)."""
    names = upstream(flat, node)
    reads = _reads(flat, names)
    reads[node] = reads.get(node, set()) | {socket}
    placed = view = False
    for name in names:
        kind = flat.nodes[name].kind
        outputs = reads.get(name, set())
        if kind in _VIEW_OUTPUTS and outputs & _VIEW_OUTPUTS[kind] or kind in VIEW_KINDS:
            view = True
        props = flat.nodes[name].props
        if kind in _LOCAL_OUTPUTS and outputs <= _LOCAL_OUTPUTS[kind] and not props.get("object_matrix") \
                and not props.get("from_instancer"):
            continue  # object-space coordinates and what the mesh alone gives
        if kind == "ShaderNodeAttribute" and props.get("attribute_type", "GEOMETRY") == "GEOMETRY":
            continue  # the mesh's own attribute
        if kind in PLACED_KINDS or (kind not in emitted and not kind.startswith("ShaderNodeTex")):
            placed = True  # (a kind the compiler does not know may read anything)
    nodes = tuple(n for n in names if n in missing)
    out_type = flat.nodes[node].outputs.get(socket, "VALUE")
    images = tuple(dict.fromkeys(flat.nodes[n].props["image"] for n in names
                                 if flat.nodes[n].props.get("image")))
    attributes = tuple(dict.fromkeys(a for n in names for a in _attributes(flat.nodes[n])))
    return BakeTarget(node, socket, out_type, _digest(flat, names, node, socket), nodes, placed or view, view,
                      images, attributes)


def _attributes(node) -> list[tuple[str, str]]:
    """The mesh attributes a node reads, as ``codegen.ATTRIBUTE_KINDS`` names them."""
    props = node.props
    if node.kind == "ShaderNodeVertexColor":
        return [("COLOR", props.get("layer_name", ""))]
    if node.kind == "ShaderNodeAttribute" and props.get("attribute_type", "GEOMETRY") == "GEOMETRY":
        return [("GENERIC", props.get("attribute_name", ""))]
    if node.kind == "ShaderNodeUVMap" and props.get("uv_map"):
        return [("UV", props["uv_map"])]
    return []


def prune(flat: FlatGraph, sink: str, baked: frozenset[str]) -> FlatGraph:
    """``flat`` without the nodes only the baked nodes' subgraphs read (Cycles computed them into
    the bakes): what ``sink`` reads, not following the inputs of the nodes in ``baked``."""
    keep = set(upstream(flat, sink, baked))
    return FlatGraph({k: v for k, v in flat.nodes.items() if k in keep}, flat.output, flat.cut, flat.luma,
                     flat.version)


# --- measuring a bake ----------------------------------------------------------------------------

def corner_values(texels: np.ndarray) -> np.ndarray:
    """A bake's bilinear reconstruction (Linear interpolation, Extend: the engine's sampling of
    it, glsl/node_texture_image.glsl) at the texel corners (i / R, j / R), i, j = 0 .. R - 1: the
    mean of the four texels around each, the image's edge texels repeated past its border.
    ``texels``: (R, R, C), bottom row first; returns (R, R, C)."""
    padded = np.pad(np.asarray(texels, np.float64), ((1, 0), (1, 0), (0, 0)), mode="edge")
    return 0.25 * (padded[:-1, :-1] + padded[1:, :-1] + padded[:-1, 1:] + padded[1:, 1:])


@dataclass(frozen=True)
class BakeError:
    """How far a bake's bilinear reconstruction lies from Cycles' values where it is farthest
    from the texels (the corners between four texel centres: a second bake half a texel over):
    the largest, mean and 99th-percentile absolute difference over the covered corners (the
    largest lies at an island's border, where the bake's margin repeats the edge texels), the
    values' range, and how many corners were compared."""

    max: float
    mean: float
    p99: float
    scale: float
    points: int

    @property
    def relative(self) -> float:
        """The largest difference as a share of the values' range (1 where it is 0)."""
        return self.max / max(self.scale, 1e-12) if self.scale > 0.0 else self.max

    def text(self) -> str:
        return f"max {self.max:.2g}, 99% {self.p99:.2g}, mean {self.mean:.2g} of range {self.scale:.3g}"


def interpolation_error(texels: np.ndarray, corners: np.ndarray, covered: np.ndarray) -> BakeError:
    """A bake measured (``BakeError``): ``texels`` (R, R, C) the bake, ``corners`` (R, R, C) Cycles'
    values at its texel corners (the check bake), ``covered`` (R, R) where the check bake has a
    value (its texel centre lies on the mesh)."""
    texels = np.asarray(texels, np.float64)
    corners = np.asarray(corners, np.float64)
    mask = np.asarray(covered, bool)
    points = int(mask.sum())
    if not points:
        return BakeError(0.0, 0.0, 0.0, 0.0, 0)
    diff = np.abs(corner_values(texels) - corners)[mask]
    if not np.isfinite(diff).all():  # Cycles gave a NaN or Inf somewhere: say it as infinite
        return BakeError(float("inf"), float("inf"), float("inf"), 0.0, points)
    values = corners[mask]
    scale = float(values.max() - values.min())
    worst = diff.max(axis=-1)  # per corner, the largest of its channels
    return BakeError(float(worst.max()), float(diff.mean()), float(np.percentile(worst, 99.0)), scale, points)
