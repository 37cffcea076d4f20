"""A material's node graph as the shading programs draw it: the closures reaching its Material
Output compiled into one GLSL function per structure (``codegen``), with what one material of
that structure binds (its constants, images and attributes).

``compile_material(graph, groups)`` flattens the graph and compiles the output's Surface into
``material_graph(GraphInputs g, out Closure surface)`` (glsl/node_closure.glsl). A material whose
surface is one closure node with nothing linked into it returns None: the constant path draws it
as before, at no extra cost.

Outputs of nodes that do not compile, read by nodes that do, are ``MaterialGraph.bakes``
(``materials.bake``); ``with_bakes(graph, baked)`` compiles the graph again with those Cycles
baked sampled from their images (one object's: a bake lies on its mesh's UV map).
"""

from __future__ import annotations

import re
from collections import OrderedDict
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from ..scene.nodes import MATERIAL_OUTPUT, Graph
from ..scene.snapshot import CLOSURE_LOBES, GLOSSY_LOBE, LOBES, lobes_of, version_rule
from . import bake, codegen, evaluate
from .graph import Const, FlatGraph, flatten

#: The function every compiled material defines.
FUNCTION = "material_graph"
#: GraphInputs fields a program fills only where its graph reads them (each a define,
#: ``SL_GRAPH_<FIELD>``): the rest cost nothing to fill.
OPTIONAL_INPUTS = ("tangent", "object", "generated", "object_to_world", "world_to_object", "world_to_view",
                   "view_to_world", "window", "object_color", "object_info", "ng", "clip_start",
                   "uniform_attributes", "triangle", "ray_footprint", "subpixels")
#: The most samplers one material binds (texture units left beside the programs' own; a UDIM
#: image's tiles of one size are one); a node needing more is not compiled, said in ``notes``.
MAX_IMAGES = codegen.MAX_IMAGES
#: The most attributes one material reads (vertex inputs left beside the mesh's own four).
MAX_ATTRIBUTES = 8


@dataclass(frozen=True)
class GraphProgram:
    """What a program needs of a graph's structure: the function's source (``key`` names it),
    how many constants, images and attributes it reads, which optional GraphInputs fields."""

    key: str
    source: str
    constants: int
    images: int
    attributes: int
    uses: frozenset[str]
    attribute_kinds: tuple[str, ...] = ()
    #: the samplers that are 2D arrays (a UDIM image's tiles: FLOAT_2D_ARRAY), by index
    arrays: tuple[int, ...] = ()
    #: how many object, instancer or view-layer attributes it reads (per-draw vec4s)
    uniform_attributes: int = 0
    #: where a closure's normal is bent: Cycles' rule for the light it takes (``bump_shadowing``)
    bump_shadowing: str = ""
    #: where a Diffuse BSDF can draw its Roughness: Cycles' Oren-Nayar (``oren_nayar``)
    oren_nayar: str = ""

    def __eq__(self, other) -> bool:
        return isinstance(other, GraphProgram) and other.key == self.key

    def __hash__(self) -> int:
        return hash(self.key)


@dataclass(eq=False)
class MaterialGraph:
    """One material's compiled graph: its structure's program, its own constants ((n, 4)
    float32, the program's ``GRAPH_CONST``), the images it samples (keys in ``Snapshot.images``;
    a tuple of keys: one 2D-array sampler, a UDIM image's tiles)
    and the attributes it reads ((kind, name), ``codegen.ATTRIBUTE_KINDS``); the nodes that did not
    compile (``"name (kind)"``: their readers took their socket values) of ``nodes`` reached;
    whether its surface can be partly transparent (drawn blended)."""

    program: GraphProgram
    constants: np.ndarray
    images: tuple[str, ...]
    attributes: tuple[tuple[str, str], ...]
    missing: list[str]
    nodes: int
    transparent: bool
    #: closures' inputs linked to nodes that the models do not read ("Coat Weight (Principled BSDF)")
    unread: list[str] = ()
    #: the Principled BSDF's inputs an image gives as it is (``textured``), for the Auto term set's
    #: prediction, which samples their texels
    textured: dict = None
    #: why nodes of ``missing`` did not compile where a limit says it (images, UDIM tiles)
    notes: tuple[str, ...] = ()
    #: the object's, instancer's and view layer's attributes it reads, (kind, name) by slot
    uniform_attributes: tuple[tuple[str, str], ...] = ()
    #: outputs of nodes that did not compile which a bake could stand in for (``bake.BakeTarget``)
    bakes: tuple = ()
    #: the nodes drawn from bakes: those the bakes stand in for and what only they read
    baked: tuple[str, ...] = ()
    #: what it was compiled from, to compile it again with bakes (``with_bakes``): the graph,
    #: its groups, and the AOV's name for an AOV Output's graph (None: the surface)
    read: tuple | None = None
    #: the Principled BSDF's lobes beyond its base its closures can draw (``snapshot.LOBES``)
    lobes: frozenset[str] = frozenset()
    #: the Principled BSDF's inputs a procedural texture gives (``_procedural``), for the Auto term
    #: set's prediction, which evaluates them at its points (``evaluate``): (field, the nodes
    #: they read, the input's source) each
    procedural: tuple = ()

    def _identity(self) -> tuple:
        constants = np.asarray(self.constants, np.float32).tobytes()
        return self.program.key, constants, self.images, self.attributes

    def __eq__(self, other) -> bool:  # equal graphs, read anew, are equal (the Auto term set's caches)
        return isinstance(other, MaterialGraph) and other._identity() == self._identity()

    def __hash__(self) -> int:
        return hash(self._identity())

    @property
    def compiled_share(self) -> float:
        """The share of the graph's nodes that compiled."""
        return 1.0 - len(self.missing) / self.nodes if self.nodes else 1.0


def _surface(flat: FlatGraph):
    output = flat.nodes.get(flat.output) if flat.output else None
    if output is None or output.kind != MATERIAL_OUTPUT or "Surface" not in output.inputs:
        return None, None
    return output, output.inputs["Surface"]


def _plain(flat: FlatGraph) -> bool:
    """Whether the surface is one closure node with nothing linked into it (or no closure)."""
    output, surface = _surface(flat)
    if surface is None or isinstance(surface.source, Const):
        return True
    node = flat.nodes[surface.source.node]
    # (a Holdout: the constant path has no alpha to cut; an anisotropic BSDF: its tangent is per fragment;
    # a closure node's lobe (Translucent, Subsurface Scattering, Toon ...): nor these lobes)
    return node.kind in codegen.CLOSURES and node.kind not in ("ShaderNodeMixShader", "ShaderNodeAddShader",
                                                                "ShaderNodeHoldout") \
        and all(isinstance(i.source, Const) for i in node.inputs.values()) and not codegen.anisotropic(node) \
        and not _closure_lobes(flat) and node.kind not in GRAPH_ONLY


#: Closure nodes the constant path (addon/blender/extract.py's material_params) does not read: compiled
#: even alone with nothing linked.
GRAPH_ONLY = frozenset({"ShaderNodeBsdfSheen", "ShaderNodeBsdfToon", "ShaderNodeEeveeSpecular",
                        "ShaderNodeBsdfMetallic"})


def _transparent(flat: FlatGraph) -> bool:
    """Whether some fragment's coverage can be under 1: a Transparent BSDF, or a Principled BSDF
    whose Alpha is linked or under 1."""
    for node in flat.nodes.values():
        if node.kind == "ShaderNodeBsdfTransparent":
            return True
        alpha = node.inputs.get("Alpha") if node.kind == "ShaderNodeBsdfPrincipled" else None
        if alpha is not None and (not isinstance(alpha.source, Const) or float(alpha.source.value) < 1.0):
            return True
    return False


@lru_cache(maxsize=1)
def _library_functions() -> dict[str, str]:
    """The node library's functions (codegen.LIBRARY and OPTIONAL_LIBRARY): name -> body (overloads
    joined)."""
    glsl = codegen.glsl_dir()
    bodies: dict[str, str] = {}
    for name in codegen.LIBRARY + codegen.OPTIONAL_LIBRARY:
        text = (glsl / name).read_text()
        starts = list(codegen.DEFINED.finditer(text))
        for i, m in enumerate(starts):
            end = starts[i + 1].start() if i + 1 < len(starts) else len(text)
            bodies[m.group(1)] = bodies.get(m.group(1), "") + text[m.start():end]
    return bodies


def graph_inputs_read(source: str) -> frozenset[str]:
    """The optional GraphInputs fields a graph's function reads: in its source, or in the library
    functions it calls (at any depth)."""
    library = _library_functions()
    seen, pending, texts = set(), [source], []
    while pending:
        text = pending.pop()
        texts.append(text)
        for name in codegen.CALLED.findall(text):
            if name in library and name not in seen:
                seen.add(name)
                pending.append(library[name])
    joined = "\n".join(texts)
    return frozenset(field for field in OPTIONAL_INPUTS if re.search(rf"\bg\.{field}\b", joined))


#: Cycles' rules for the light a bent normal takes (kernel/closure/bsdf.h bump_shadowing_term), by
#: the Blender that reads the graph (from its Cycles kernels: 4.2's and 4.5's differ, 4.5's and 5.0's
#: agree for the closures drawn; 4.3 and 4.4, not measured, are taken as 4.5): Chiang, Li and Burley
#: 2019 ("Taming the Shadow Terminator": the diffuse lobe smoothed by -g^3 + g^2 + g), or Conty
#: Estevez, Lecocq and Stein 2019 (the diffuse lobe shadowed by a GGX G1); light from behind the
#: smooth surface is rejected by both.
BUMP_SHADOWING = ("CHIANG_2019", "CONTY_2019")
#: The first Blender (major, minor) of each rule but the first
_BUMP_SHADOWING_FROM = ((4, 3),)
#: Cycles' Oren-Nayar for a Diffuse BSDF's Roughness (kernel/closure/bsdf_oren_nayar.h), by the Blender
#: that reads the graph (from each wheel's Cycles kernel: 4.2's differs, 4.5's and 5.0's agree; 4.3 and
#: 4.4, not measured, are taken as 4.5): Fujii's improved Oren-Nayar alone, Roughness 0 exactly being
#: Lambert (4.2), or with OpenPBR's energy-preserving multiple scattering, Lambert below 1e-5 (4.5,
#: 5.0). glsl/closures.glsl draws each (SL_OREN_NAYAR_<RULE>).
OREN_NAYAR = ("FUJII", "FUJII_MULTISCATTER")
#: The first Blender (major, minor) of each rule but the first
_OREN_NAYAR_FROM = ((4, 3),)


def bump_shadowing(version: tuple[int, int]) -> str:
    """Cycles' rule for a bent normal's light in Blender ``version`` (``BUMP_SHADOWING``)."""
    return version_rule(BUMP_SHADOWING, _BUMP_SHADOWING_FROM, version)


def oren_nayar(version: tuple[int, int]) -> str:
    """Cycles' Oren-Nayar in Blender ``version`` (``OREN_NAYAR``)."""
    return version_rule(OREN_NAYAR, _OREN_NAYAR_FROM, version)


def _bent(flat: FlatGraph) -> bool:
    """Whether some closure's Normal is linked (a Normal Map, a Bump, any node): the shading
    models then apply Cycles' rules for a bent normal (glsl/bent_normal.glsl's bump_terminator)."""
    return any(node.kind in codegen.CLOSURES and "Normal" in node.inputs
               and not isinstance(node.inputs["Normal"].source, Const) for node in flat.nodes.values())


def displacement_linked(graph: Graph) -> bool:
    """Whether something is linked into the output's Displacement (not drawn)."""
    return graph.output is not None and any(link.to_node == graph.output and link.to_socket == "Displacement"
                                            for link in graph.links)


def _node_count(flat: FlatGraph) -> int:
    """The artist's nodes of the flat graph (not its conversions or outputs)."""
    return sum(1 for n in flat.nodes.values() if n.kind not in ("Convert", *codegen.SINKS))


def _program_key(digest: str, kinds: tuple[str, ...], rule: str, diffuse: str = "") -> str:
    """A graph program's key: its source's ``digest`` (``codegen.Compiled.key``), the kinds of the
    attributes it reads (a tangent is turned to world space, an island's value is not interpolated,
    an orco becomes Generated: ``programs.graph_defines``), its bent normal's rule and its Oren-Nayar's
    (``diffuse``, after an "o")."""
    return (f"{digest}{''.join(k[0] for k in kinds)}{BUMP_SHADOWING.index(rule) if rule else ''}"
            f"{'o%d' % OREN_NAYAR.index(diffuse) if diffuse else ''}")


def _compiled(flat: FlatGraph, targets: dict, function: str, whole: FlatGraph,
              baked: dict | None = None) -> MaterialGraph:
    full = flat
    nodes = _node_count(flat)
    if baked:  # what only the bakes read Cycles computed into them
        sink = next(iter(targets.values()))[0]
        flat = bake.prune(flat, sink, frozenset(node for node, _ in baked))
    compiled = codegen.compile_graph(flat, targets, function, whole, baked)
    uses = graph_inputs_read(compiled.source)
    rule = ""
    if _bent(flat):
        uses |= {"bent_normal"}
        rule = bump_shadowing(flat.version)
    # a Diffuse BSDF (its Roughness a constant or per fragment): the reading Blender's Oren-Nayar
    diffuse = ""
    if any(node.kind == "ShaderNodeBsdfDiffuse" for node in flat.nodes.values()):
        diffuse = oren_nayar(flat.version)
    kinds = tuple(kind for kind, _ in compiled.attributes)
    key = _program_key(compiled.key, kinds, rule, diffuse)
    program = GraphProgram(key, compiled.source,
                           len(compiled.constants), len(compiled.images), len(compiled.attributes), uses,
                           kinds, compiled.arrays, len(compiled.uniform_attributes), rule, diffuse)
    missing = set(compiled.missing_nodes)
    emitted = frozenset(codegen.EMITTERS) - codegen.FORCE_BAKE
    bakes = tuple(bake.target(full, node, socket, missing, emitted) for node, socket in compiled.bake_targets)
    drawn_baked = set(compiled.baked) | (set(full.nodes) - set(flat.nodes))
    baked_names = tuple(n for n in full.nodes if n in drawn_baked and full.nodes[n].kind not in
                        ("Convert", *codegen.SINKS))
    textured = _textured(flat)
    return MaterialGraph(program, compiled.constants, compiled.images, compiled.attributes, compiled.missing,
                         nodes, _transparent(flat), _unread(flat), textured,
                         compiled.notes, compiled.uniform_attributes, bakes, baked_names,
                         lobes=_lobes(flat), procedural=_procedural(flat, set(textured), missing))


def _lobes(flat: FlatGraph) -> frozenset[str]:
    """The lobes (``snapshot.LOBES``) the graph's Principled BSDFs can draw: each whose inputs turn
    it on (``snapshot.lobes_of``), a linked input taken as on (its value is per fragment); and an
    anisotropic lobe of any BSDF that has one (``codegen.anisotropic``)."""
    out = set()
    for node in flat.nodes.values():
        if codegen.anisotropic(node):  # a Principled, Glossy or Metallic BSDF's anisotropic lobe
            out.add("ANISOTROPY")
        out |= _node_lobe(node)
        if node.kind in GLASS_CLOSURES:  # transmitting alone
            out.add("TRANSMISSION")
        if node.kind != "ShaderNodeBsdfPrincipled":
            continue
        values = {}
        for socket in ("Specular Tint", "Coat Weight", "Sheen Weight", "Sheen Tint", "Thin Film Thickness",
                       "Subsurface Weight", "Transmission Weight", "Diffuse Roughness"):
            spec = node.inputs.get(socket)
            if spec is not None and not isinstance(spec.source, Const):
                value = {"Specular Tint": (0.0,) * 3, "Coat Weight": 1.0, "Sheen Weight": 1.0,
                         "Sheen Tint": (1.0,) * 3, "Thin Film Thickness": 1.0,
                         "Subsurface Weight": 1.0, "Transmission Weight": 1.0,
                         "Diffuse Roughness": 1.0}[socket]  # linked: on
            elif spec is not None and spec.source.value is not None:
                value = spec.source.value
            else:
                value = codegen.PRINCIPLED_DEFAULTS.get(socket, (0.0,))[0]
            values[socket] = tuple(value)[:3] if isinstance(value, (tuple, list)) else float(value)
        out |= lobes_of(values["Specular Tint"], values["Coat Weight"], values["Sheen Weight"],
                        values["Sheen Tint"], values["Thin Film Thickness"],
                        subsurface_weight=values["Subsurface Weight"],
                        transmission_weight=values["Transmission Weight"],
                        diffuse_roughness=values["Diffuse Roughness"])
    return frozenset(out)


def _node_lobe(node) -> set[str]:
    """The lobe (``snapshot.LOBES``) a closure node other than the Principled BSDF draws
    (codegen.closure_node_lobes), as a set (empty: none): a Diffuse BSDF's Roughness only where it is
    linked or above 0."""
    lobes = set(codegen.closure_node_lobes(node))
    if "DIFFUSE_ROUGHNESS" in lobes:
        spec = node.inputs.get("Roughness")
        if spec is None or (isinstance(spec.source, Const) and not float(spec.source.value or 0.0) > 0.0):
            return set()  # Lambert (Cycles' below 1e-5: the closure clamps to it, the lobe reads 0)
    return lobes


def _closure_lobes(flat: FlatGraph) -> set[str]:
    """The lobes the graph's closure nodes other than the Principled BSDF draw (``_node_lobe``)."""
    return set().union(*(_node_lobe(node) for node in flat.nodes.values()))


def compile_material(graph: Graph, groups: dict[str, Graph],
                     baked: dict | None = None) -> MaterialGraph | None:
    """The material's compiled surface, or None where the constant path draws it (no output, or
    one closure with nothing linked into it); ``baked``: the outputs Cycles baked, (flat node,
    output) -> image key (``with_bakes``)."""
    flat = flatten(graph, groups, aovs=False)
    if _plain(flat):
        return None
    output, surface = _surface(flat)
    # what the Surface reads: the output's Volume and Displacement are not drawn
    above = set(codegen.upstream(flat, surface.source.node)) | {output.name}
    flat = FlatGraph({k: v for k, v in flat.nodes.items() if k in above}, flat.output, flat.cut, flat.luma,
                     flat.version)
    compiled = _compiled(flat, {"surface": (output.name, "Surface")}, FUNCTION, flatten(graph, groups), baked)
    compiled.read = (graph, groups, None)
    return compiled


#: The attribute of a deformed mesh's undeformed positions (Blender's orco: object space, (x, y, z,
#: 1) per corner; ``scene.snapshot.MeshGeometry.attributes``), which a graph reading Generated
#: takes on such a mesh (``with_orco``).
ORCO = ("ORCO", "")


def with_orco(graph: MaterialGraph) -> MaterialGraph:
    """``graph`` as drawn on a deformed mesh (an armature, shape keys, a lattice, any deforming
    modifier): where it reads Generated, its program takes the mesh's undeformed positions as one
    more attribute (``ORCO``) and Generated from them, as Cycles' attr_create_generated
    (intern/cycles/blender/mesh.cpp) takes Blender's orco layer, so that textures stay on the
    deforming surface; ``graph`` itself where it reads no Generated. An undeformed mesh keeps
    ``graph``: Generated from the fragment's position, no attribute."""
    if "generated" not in graph.program.uses or ORCO in graph.attributes:
        return graph
    p = graph.program
    kinds = p.attribute_kinds + (ORCO[0],)
    program = replace(p, key=_program_key(p.key[:16], kinds, p.bump_shadowing, p.oren_nayar),
                     attributes=p.attributes + 1, attribute_kinds=kinds)
    return replace(graph, program=program, attributes=graph.attributes + (ORCO,))


#: The function a material's AOV Output compiles to: ``material_aov(g, out vec4 color, out float
#: value)``, its Color and Value inputs (the view layer's AOV says which one is written).
AOV_FUNCTION = "material_aov"


def compile_aovs(graph: Graph, groups: dict[str, Graph],
                 baked: dict | None = None) -> dict[str, MaterialGraph]:
    """Each AOV Output's inputs compiled, by its AOV name (the first node of a name, as Cycles
    takes one); an AOV Output of no name writes nothing. ``baked`` as ``compile_material``'s."""
    if not any(node.kind == "ShaderNodeOutputAOV" and not node.muted for node in graph.nodes.values()):
        return {}  # (flatten takes AOV Outputs from the material's own tree only): nothing to flatten
    flat = flatten(graph, groups, output=False)
    whole = None
    out = {}
    for node in flat.nodes.values():
        name = node.props.get("aov_name", "") if node.kind == "ShaderNodeOutputAOV" else ""
        if name and name not in out:
            above = set(codegen.upstream(flat, node.name))
            only = FlatGraph({k: v for k, v in flat.nodes.items() if k in above}, None, flat.cut, flat.luma,
                             flat.version)
            whole = whole or flatten(graph, groups)
            out[name] = _compiled(only, {"color": (node.name, "Color"), "value": (node.name, "Value")},
                                  AOV_FUNCTION, whole, baked)
            out[name].read = (graph, groups, name)
    return out


#: Graphs compiled again with bakes, by what they were compiled from and the bakes' keys: a
#: viewport update or a render reads them from here (``with_bakes``), at most ``_VARIANTS_KEPT``.
_VARIANTS: OrderedDict = OrderedDict()
_VARIANTS_KEPT = 64


def with_bakes(graph: MaterialGraph, baked: dict[tuple[str, str], str]) -> MaterialGraph:
    """``graph`` compiled again with the outputs of ``baked`` ((flat node, output) -> image key)
    sampled from their bakes; ``graph`` itself where none of its bakes is in ``baked``."""
    mine = {(t.node, t.socket) for t in graph.bakes}
    baked = {k: v for k, v in baked.items() if k in mine}
    if not baked or graph.read is None:
        return graph
    key = (graph._identity(), graph.read[2], tuple(sorted(baked.items())))
    found = _VARIANTS.pop(key, None)
    if found is None:
        source, groups, aov = graph.read
        found = compile_material(source, groups, baked) if aov is None else \
            compile_aovs(source, groups, baked)[aov]
    _VARIANTS[key] = found  # most recently used last
    while len(_VARIANTS) > _VARIANTS_KEPT:
        del _VARIANTS[next(iter(_VARIANTS))]
    return found


#: MaterialParams' field of each Principled BSDF input ``textured`` reads.
TEXTURED_INPUTS = {"Base Color": "base_color", "Metallic": "metalness", "Roughness": "roughness"}


def _textured(flat: FlatGraph) -> dict:
    """{MaterialParams field: (image key, channel)} of the one Principled BSDF's Base Color,
    Metallic and Roughness that an Image Texture gives unchanged: its Color (channel None: the
    colour; "luma": a float input reading it, the flat graph's weights), or one channel (0-2) of it
    through a Separate Color in RGB mode (a glTF ORM texture)."""
    principled = [n for n in flat.nodes.values() if n.kind == "ShaderNodeBsdfPrincipled"]
    if len(principled) != 1:
        return {}
    out = {}
    for socket, field in TEXTURED_INPUTS.items():
        spec = principled[0].inputs.get(socket)
        if spec is None or isinstance(spec.source, Const):
            continue
        node, channel = flat.nodes[spec.source.node], None
        if node.kind == "Convert" and node.props.get("from") == "RGBA":
            node, channel = flat.nodes.get(getattr(node.inputs["Value"].source, "node", "")), "luma"
        elif node is not None and node.kind == "ShaderNodeSeparateColor" and node.props.get("mode") == "RGB":
            channel = ("Red", "Green", "Blue").index(spec.source.socket)
            source = node.inputs["Color"].source
            node = flat.nodes.get(source.node) if not isinstance(source, Const) else None
        if node is not None and node.kind == "ShaderNodeTexImage" and node.props.get("image"):
            out[field] = (node.props["image"], channel)
    return out


def _procedural(flat: FlatGraph, textured: set, missing: set) -> tuple:
    """(MaterialParams field, the flat nodes it reads, its source) of the one Principled BSDF's
    Base Color, Metallic and Roughness that ``evaluate`` can compute at points and a procedural
    texture varies: not the ``textured`` fields (an image gives them), nor those reading a node of
    ``missing`` (not compiled: the program draws its socket's value)."""
    principled = [n for n in flat.nodes.values() if n.kind == "ShaderNodeBsdfPrincipled"]
    if len(principled) != 1:
        return ()
    out = []
    for socket, field in TEXTURED_INPUTS.items():
        spec = principled[0].inputs.get(socket)
        if spec is None or isinstance(spec.source, Const) or field in textured:
            continue
        if evaluate.evaluable(flat, spec.source):
            names = evaluate.upstream(flat, spec.source)
            if not missing & set(names):
                sub = FlatGraph(nodes={n: flat.nodes[n] for n in names}, luma=flat.luma, version=flat.version)
                out.append((field, sub, spec.source))
    return tuple(out)


#: The Principled BSDF's inputs of each lobe (``snapshot.LOBES``).
LOBE_INPUTS = {"SPECULAR_TINT": ("Specular Tint",),
               "COAT": ("Coat Weight", "Coat Roughness", "Coat IOR", "Coat Tint", "Coat Normal"),
               "SHEEN": ("Sheen Weight", "Sheen Roughness", "Sheen Tint"),
               "THIN_FILM": ("Thin Film Thickness", "Thin Film IOR"),
               "ANISOTROPY": ("Anisotropic", "Anisotropic Rotation", "Tangent"),
               "TRANSLUCENT": (),
               "SUBSURFACE": ("Subsurface Weight", "Subsurface Radius", "Subsurface Scale", "Subsurface IOR",
                              "Subsurface Anisotropy"),
               "TRANSMISSION": ("Transmission Weight",),
               **{lobe: () for lobe in (*CLOSURE_LOBES, GLOSSY_LOBE)}}  # (the closure nodes': READ_INPUTS)
LOBE_INPUTS["DIFFUSE_ROUGHNESS"] = ("Diffuse Roughness",)  # the Principled BSDF's own too (Blender 4.3+)
#: The Glossy and Metallic BSDFs' anisotropic inputs (``codegen.ANISOTROPIC``)
ANISOTROPIC_INPUTS = {"Anisotropy", "Rotation", "Tangent"}
#: The closures that transmit alone (glsl/node_closure.glsl's closure_glass, closure_refraction).
GLASS_CLOSURES = ("ShaderNodeBsdfGlass", "ShaderNodeBsdfRefraction")
#: What of each closure the shading models read (the rest is drawn as nothing: Principled BSDF's
#: coat, sheen, transmission ...).
READ_INPUTS = {"ShaderNodeBsdfPrincipled": set(codegen.PRINCIPLED_BASE_INPUTS) | {"Normal"}
               | {socket for lobe in LOBES for socket in LOBE_INPUTS[lobe]},
               "ShaderNodeBsdfDiffuse": {"Color", "Roughness", "Normal"},
               "ShaderNodeBsdfSheen": {"Color", "Roughness", "Normal"},
               "ShaderNodeBsdfToon": {"Color", "Size", "Smooth", "Normal"},
               "ShaderNodeEeveeSpecular": {*codegen.SPECULAR_INPUTS, "Normal"},
               "ShaderNodeBsdfGlossy": {"Color", "Roughness", "Normal"} | ANISOTROPIC_INPUTS,
               "ShaderNodeBsdfMetallic": {"Base Color", "Edge Tint", "IOR", "Extinction", "Roughness",
                                          "Normal"} | ANISOTROPIC_INPUTS,
               "ShaderNodeBsdfTranslucent": {"Color", "Normal"},
               "ShaderNodeSubsurfaceScattering": {"Color", "Scale", "Radius", "IOR", "Roughness",
                                                  "Anisotropy", "Normal"},
               "ShaderNodeBsdfGlass": {"Color", "Roughness", "IOR", "Normal"},
               "ShaderNodeBsdfRefraction": {"Color", "Roughness", "IOR", "Normal"}}
READ_INPUTS["ShaderNodeBsdfAnisotropic"] = READ_INPUTS["ShaderNodeBsdfGlossy"]  # the Glossy BSDF's own name


def _unread(flat: FlatGraph) -> list[str]:
    """The closures' linked inputs the models do not read, each "input (node)"."""
    out = []
    for node in flat.nodes.values():
        read = READ_INPUTS.get(node.kind)
        if read is None:
            continue
        out += [f"{socket} ({node.name.rsplit('/', 1)[-1]})" for socket, spec in node.inputs.items()
                if socket not in read and not isinstance(spec.source, Const)]
    return out
