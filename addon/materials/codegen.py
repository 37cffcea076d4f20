"""A flat node graph (``graph.flatten``) as one GLSL function evaluated per fragment.

``compile_graph(flat, targets)`` writes a function that computes the inputs of the nodes the
targets name (an AOV Output's Color and Value, later the closures' inputs) from the fragment's
``GraphInputs`` (glsl/node_inputs.glsl: its texture coordinates ...), each node's outputs once,
in the flat graph's order, each node through one library function per node variant
(``glsl/node_*.glsl``; the node's settings choose the function, as EEVEE's ``gpu_fn`` does).

Constants are not in the source: every constant a node reads (an unlinked socket, a Value or RGB
node) is a slot of ``Compiled.constants`` read through ``GRAPH_CONST(i)`` (a vec4), which the
program defines (a uniform block in the engine, an array in the tests). Two graphs of one
structure compile to the same source and share one program; editing a value compiles nothing.
Tables are constants too: a Color Ramp's or a curve's baked entries (``_Writer.table``) are
consecutive slots the library reads through ``graph_table(i)`` (glsl/node_ramp.glsl), which every
compiled source defines ahead of its function as ``GRAPH_CONST(i)``: the program defines
``GRAPH_CONST`` before the source, and holds one compiled graph. A table is 257 slots (65 for a
Float Curve): a ramp costs 4 KiB of constants.

Images and attributes are not in the source either: an Image Texture node's image is sampler
``graph_image_<k>`` (``Compiled.images[k]``: the image's key in ``Snapshot.images``), a named UV
map, colour attribute or attribute is ``g.attributes[k]`` (``Compiled.attributes[k]``: its kind and
name); the program binds the images and fills the attributes (the mesh's, by name). One image read
by several nodes at one coordinate is sampled once (the expression is shared).

A node no emitter knows compiles to nothing: every input linked to it reads its own socket value
instead (Blender's fallback for what a renderer cannot evaluate); ``Compiled.missing`` names it,
and ``Compiled.bake_targets`` names its outputs that compiled nodes read. Where Cycles baked such
an output into an image on the object's UV map (``compile_graph``'s ``baked``: (node, output) ->
the image's key in ``Snapshot.images``; ``materials.bake``), the output is that image sampled at
the UV (Linear, Extend) instead.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from . import textures
from .graph import CONVERT, Const, FlatGraph, FlatNode, Ref


def glsl_dir() -> Path:
    """``glsl/`` beside the package when installed as an extension, else at the repository root."""
    here = Path(__file__).resolve().parents[1]  # the package: addon/ in the source tree
    for candidate in (here / "glsl", here.parent / "glsl"):
        if (candidate / "brdf.glsl").is_file():
            return candidate
    raise FileNotFoundError(f"Shading Lab's GLSL sources are missing (looked beside {here})")


#: The most samplers one material's graph binds (texture units left beside the programs' own:
#: addon/frame/gpu_library.GRAPH_IMAGE_SLOT on); a node needing more does not compile (``notes``).
MAX_IMAGES = 10
#: The most tiles of a UDIM image drawn (an array's layers: 256 is OpenGL's least
#: GL_MAX_ARRAY_TEXTURE_LAYERS); an image of more does not compile (``notes``).
MAX_TILES = 256
#: GLSL type of each socket type.
GLSL_TYPES = {"VALUE": "float", "INT": "float", "BOOLEAN": "float", "VECTOR": "vec3", "RGBA": "vec4",
              "SHADER": "Closure"}
#: The library files a compiled graph reads, in order.
LIBRARY = ("node_inputs.glsl", "node_convert.glsl", "node_color.glsl", "node_math.glsl", "node_mix.glsl",
           "node_converter.glsl", "node_vector_math.glsl", "node_texture_image.glsl", "node_normal.glsl",
           "node_ramp.glsl", "node_vector.glsl", "node_closure.glsl")
#: Library files compiled into a program only where its graph calls one of their functions (the
#: procedural textures: only what the scene requires), each after the files it calls.
OPTIONAL_LIBRARY = ("node_hash.glsl", "node_tex_white_noise.glsl", "node_tex_gabor.glsl")
#: the pattern textures, after the float arithmetic they share (node_float.glsl)
OPTIONAL_LIBRARY += ("node_float.glsl", "node_tex_gradient.glsl", "node_tex_checker.glsl",
                     "node_tex_magic.glsl", "node_tex_brick.glsl", "node_tex_radial_tiling.glsl")
OPTIONAL_LIBRARY += ("node_tex_voronoi.glsl",)  # after node_hash.glsl, whose hashes it calls
OPTIONAL_LIBRARY += ("node_tex_noise.glsl", "node_tex_wave.glsl")  # Noise; Wave (calls Noise's fBM)
OPTIONAL_LIBRARY += ("node_anisotropy.glsl",)  # an anisotropic BSDF's stretch and tangent
#: the subsurface's mean free path, the Subsurface Scattering node
OPTIONAL_LIBRARY += ("node_subsurface.glsl",)
OPTIONAL_LIBRARY += ("node_closure_bsdfs.glsl",)  # the Sheen and Toon BSDFs
#: Node kinds drawn from a bake even where an emitter compiles them (empty: none). Tests and the
#: benchmark set it to compare a node's bake with its compiled code and with Cycles.
FORCE_BAKE: frozenset[str] = frozenset()
#: A GLSL function's definition at a line's start (its name), and any call (the name called).
DEFINED = re.compile(r"^[A-Za-z_]\w*\s+(\w+)\s*\(", re.M)
CALLED = re.compile(r"\b(\w+)\s*\(")


@lru_cache(maxsize=None)
def _optional_file(name: str) -> tuple[frozenset[str], frozenset[str]]:
    """The functions ``name`` (of OPTIONAL_LIBRARY) defines and the names it calls."""
    text = (glsl_dir() / name).read_text()
    return frozenset(DEFINED.findall(text)), frozenset(CALLED.findall(text))


def library(source: str) -> tuple[str, ...]:
    """The library files a compiled graph's ``source`` needs, in order: ``LIBRARY``, then each
    file of ``OPTIONAL_LIBRARY`` whose functions the source calls, or another needed file calls."""
    calls, needed = set(CALLED.findall(source)), set()
    changed = True
    while changed:
        changed = False
        for name in OPTIONAL_LIBRARY:
            defined, called = _optional_file(name)
            if name not in needed and defined & calls:
                needed.add(name)
                calls |= called
                changed = True
    return LIBRARY + tuple(name for name in OPTIONAL_LIBRARY if name in needed)

#: The Math node's operations, each its library function (glsl/node_math.glsl).
MATH_OPERATIONS = (
    "ADD", "SUBTRACT", "MULTIPLY", "DIVIDE", "MULTIPLY_ADD", "POWER", "LOGARITHM", "SQRT",
    "INVERSE_SQRT", "ABSOLUTE", "EXPONENT", "MINIMUM", "MAXIMUM", "LESS_THAN", "GREATER_THAN", "SIGN",
    "COMPARE", "SMOOTH_MIN", "SMOOTH_MAX", "ROUND", "FLOOR", "CEIL", "TRUNC", "FRACT", "MODULO",
    "FLOORED_MODULO", "WRAP", "SNAP", "PINGPONG", "SINE", "COSINE", "TANGENT", "ARCSINE", "ARCCOSINE",
    "ARCTANGENT", "ARCTAN2", "SINH", "COSH", "TANH", "RADIANS", "DEGREES",
)
_MATH_FUNCTIONS = {op: "math_" + {"FRACT": "fraction"}.get(op, op.lower()) for op in MATH_OPERATIONS}
#: The Vector Math node's operations (glsl/node_vector_math.glsl's vmath_*), and those giving a float.
VECTOR_MATH_OPERATIONS = (
    "ADD", "SUBTRACT", "MULTIPLY", "DIVIDE", "MULTIPLY_ADD", "CROSS_PRODUCT", "PROJECT", "REFLECT",
    "REFRACT", "FACEFORWARD", "DOT_PRODUCT", "DISTANCE", "LENGTH", "SCALE", "NORMALIZE", "ABSOLUTE",
    "POWER", "SIGN", "MINIMUM", "MAXIMUM", "FLOOR", "CEIL", "FRACTION", "MODULO", "WRAP", "SNAP", "SINE",
    "COSINE", "TANGENT",
)
VECTOR_MATH_VALUES = ("DOT_PRODUCT", "DISTANCE", "LENGTH")
#: The Mix node's colour blend modes, each its library function (glsl/node_mix.glsl).
MIX_BLEND_TYPES = ("MIX", "DARKEN", "MULTIPLY", "BURN", "LIGHTEN", "SCREEN", "DODGE", "ADD", "OVERLAY",
                   "SOFT_LIGHT", "LINEAR_LIGHT", "DIFFERENCE", "EXCLUSION", "SUBTRACT", "DIVIDE", "HUE",
                   "SATURATION", "COLOR", "VALUE")
_MIX_FUNCTIONS = {mode: "mix_" + {"MIX": "blend"}.get(mode, mode.lower()) for mode in MIX_BLEND_TYPES}


@dataclass
class Compiled:
    """A graph's GLSL: ``source`` (the function ``name``), the constants it reads
    (``GRAPH_CONST(i)``, (n, 4) float32), the GLSL type of each target (its ``out`` parameter, in
    order), the nodes it could not compile (``"name (kind)"``), and a key of its structure."""

    name: str
    source: str
    constants: np.ndarray
    targets: dict[str, str]
    missing: list[str] = field(default_factory=list)
    #: the images the graph samples (``graph_image_<k>``), by key in ``Snapshot.images``; a tuple
    #: of keys is a 2D-array sampler, a layer per key (a UDIM image's tiles, ``tile_key``)
    images: tuple[str | tuple[str, ...], ...] = ()
    #: the attributes the graph reads (``g.attributes[k]``): (kind, name), kind one of
    #: ``ATTRIBUTE_KINDS``; an empty name is the mesh's default of that kind
    attributes: tuple[tuple[str, str], ...] = ()
    #: the object's, instancer's and view layer's attributes it reads (``g.uniform_attributes[k]``):
    #: (kind: OBJECT, INSTANCER or VIEW_LAYER, name), and an instance's coordinates on its instancer
    #: (INSTANCER_GENERATED, INSTANCER_UV: Texture Coordinate's and UV Map's From Instancer)
    uniform_attributes: tuple[tuple[str, str], ...] = ()
    #: why nodes did not compile where a limit says it (``MAX_IMAGES``, ``MAX_TILES``)
    notes: tuple[str, ...] = ()
    #: outputs of nodes that did not compile which compiled nodes read (what a bake could stand
    #: in for): (flat node, output socket)
    bake_targets: tuple[tuple[str, str], ...] = ()
    #: the nodes whose outputs are sampled from bakes (``compile_graph``'s ``baked``)
    baked: tuple[str, ...] = ()
    #: the flat names of the nodes that did not compile (``missing`` says "name (kind)")
    missing_nodes: tuple[str, ...] = ()

    @property
    def arrays(self) -> tuple[int, ...]:
        """The samplers that are 2D arrays (``graph_image_<k>``: sampler2DArray)."""
        return tuple(k for k, image in enumerate(self.images) if isinstance(image, tuple))

    @property
    def key(self) -> str:
        return hashlib.sha1(self.source.encode()).hexdigest()[:16]


#: What ``g.attributes[k]`` holds: a UV map's (u, v, 0, 1), a colour attribute's RGBA (linear), a
#: generic attribute's value (Attribute node: a float as (x, x, x, 1), a vector (x, y, z, 1)), a
#: named UV map's tangent (as ``GraphInputs.tangent``: world-space unit tangent, the bitangent's sign),
#: the Geometry node's Pointiness and Random Per Island (x; a triangle's island the same at its corners).
ATTRIBUTE_KINDS = ("UV", "COLOR", "GENERIC", "TANGENT", "POINTINESS", "RANDOM_PER_ISLAND")
#: The GraphInputs a graph reads, as a word in its source (renamed in a Bump's offset branches).
_G = re.compile(r"\bg\b")


class _Writer:
    def __init__(self, flat: FlatGraph, whole: FlatGraph | None = None):
        self.flat = flat
        self.whole = whole if whole is not None else flat  # what the nodes' outputs feed
        self.lines: list[str] = []
        self.constants: list[tuple[float, float, float, float]] = []
        self.values: dict[tuple[str, str], str] = {}  # (node, output) -> GLSL variable
        self.skipped: set[str] = set()
        self.missing: list[str] = []
        self.missing_nodes: list[str] = []  # the flat names of ``missing``
        self.silent: list[str] = []  # of those, the ones that compiled to nothing (readers fall back)
        self.baked: dict[tuple[str, str], str] = {}  # (node, output) -> a bake's image key
        self.from_bakes: list[str] = []  # nodes whose outputs are sampled from bakes
        self.images: list[str | tuple[str, ...]] = []
        self.notes: list[str] = []  # why nodes did not compile, where a limit says it
        self.attributes: list[tuple[str, str]] = []
        self.uniform_attributes: list[tuple[str, str]] = []
        self.shared: dict[str, str] = {}  # an expression computed once -> its variable
        self.count = 0  # variables declared
        #: the GraphInputs the expressions being written read: ``g``, or in a Bump's branch the
        #: fragment moved to a neighbour (``_height_at``)
        self.g = "g"

    def bind(self, expr: str) -> str:
        """``expr`` reading this branch's GraphInputs."""
        return expr if self.g == "g" else _G.sub(self.g, expr)

    def image(self, key: str | tuple[str, ...]) -> str | None:
        """The sampler of image ``key`` (one per image, however many nodes read it); a tuple of
        keys is one 2D-array sampler, a layer per key (a UDIM image's tiles). None where the
        material would need more than ``MAX_IMAGES`` samplers (said in ``notes``)."""
        if key not in self.images:
            if len(self.images) >= MAX_IMAGES:
                return None
            self.images.append(key)
        return f"graph_image_{self.images.index(key)}"

    def over_limit(self, node: FlatNode, needed: int) -> None:
        self.notes.append(f"{node.name.rsplit('/', 1)[-1]}: more than {MAX_IMAGES} images in one material "
                          f"({needed} over); not drawn")

    def attribute(self, kind: str, name: str) -> str:
        """``g.attributes[k]`` of the attribute (kind, name), one slot per attribute."""
        assert kind in ATTRIBUTE_KINDS, kind
        if (kind, name) not in self.attributes:
            self.attributes.append((kind, name))
        return f"g.attributes[{self.attributes.index((kind, name))}]"

    def uniform_attribute(self, kind: str, name: str) -> str | None:
        """``g.uniform_attributes[k]`` of an Attribute node's object, instancer or view-layer
        attribute (kind, name); None beyond ``MAX_UNIFORM_ATTRIBUTES`` of them."""
        if (kind, name) not in self.uniform_attributes:
            if len(self.uniform_attributes) >= MAX_UNIFORM_ATTRIBUTES:
                return None
            self.uniform_attributes.append((kind, name))
        return f"g.uniform_attributes[{self.uniform_attributes.index((kind, name))}]"

    def once(self, type_: str, expr: str) -> str:
        """A variable holding ``expr`` (of GLSL ``type_``), declared the first time it is asked
        for: the same image at the same coordinate sampled once for every node reading it."""
        expr = self.bind(expr)
        var = self.shared.get(expr)
        if var is None:
            var = self.shared[expr] = f"s{len(self.shared)}"
            self.lines.append(f"  {type_} {var} = {expr};")
        return var

    def constant(self, value, type_: str) -> str:
        if type_ == "SHADER":  # an unlinked shader socket: no closure
            return "closure_none()"
        if type_ == "RGBA":
            v = tuple(float(x) for x in value[:4])
        elif type_ == "VECTOR":  # (a 2D vector socket, as Radial Tiling's, holds two)
            v = (*(float(x) for x in value[:3]), *(0.0,) * (4 - len(value[:3])))
        else:
            v = (float(value), 0.0, 0.0, 0.0)
        self.constants.append(v)
        read = f"GRAPH_CONST({len(self.constants) - 1})"
        return {"RGBA": read, "VECTOR": read + ".xyz"}.get(type_, read + ".x")

    def table(self, rows) -> int:
        """The slot of the first of ``rows`` (each up to 4 floats, one vec4 constant each) in the
        constants: a baked ramp or curve, which the library reads through ``graph_table(slot + k)``
        (the slot is where the table is, the same for any values of a graph's structure)."""
        base = len(self.constants)
        for row in rows:
            values = tuple(float(x) for x in row)
            self.constants.append(values + (0.0,) * (4 - len(values)))
        return base

    def arg(self, node: FlatNode, socket: str) -> str:
        """The GLSL expression of ``node``'s input ``socket``."""
        spec = node.inputs[socket]
        source = spec.source
        if isinstance(source, Ref):
            known = self.values.get((source.node, source.socket))
            if known is not None:
                return known
            if spec.default is not None:  # linked to what did not compile: the socket's own value
                return self.constant(spec.default, spec.type)
            return self.constant(_zero(spec.type), spec.type)
        assert isinstance(source, Const)
        value = source.value if source.value is not None else _zero(source.type)
        return self.constant(value, source.type)

    def define(self, node: FlatNode, outputs: dict[str, str]) -> None:
        """Declare ``node``'s outputs (socket -> GLSL expression), each once."""
        for socket, expr in outputs.items():
            type_ = node.outputs.get(socket, "VALUE")
            var = f"n{self.count}_{''.join(c if c.isalnum() else '_' for c in socket)}"
            self.count += 1
            self.lines.append(f"  {GLSL_TYPES.get(type_, 'float')} {var} = {self.bind(expr)};")
            self.values[(node.name, socket)] = var


def _zero(type_: str):
    return {"RGBA": (0.0, 0.0, 0.0, 1.0), "VECTOR": (0.0, 0.0, 0.0)}.get(type_, 0.0)


# --- emitters: node -> {output socket: GLSL expression} -----------------------------------------

def _value(w: _Writer, node: FlatNode) -> dict:
    return {s: w.constant(node.values.get(s, _zero(t)), t) for s, t in node.outputs.items()}


def _mat4(w: _Writer, rows) -> str:
    """A 4 x 4 matrix (rows, as mathutils gives them) as a GLSL mat4 of four constants (columns)."""
    columns = [tuple(float(rows[r][c]) for r in range(4)) for c in range(4)]
    return f"mat4({', '.join(w.constant(c, 'RGBA') for c in columns)})"


def _from_instancer(w: _Writer, kind: str) -> str | None:
    """An instance's coordinates on its instancer (``INSTANCER_GENERATED``, ``INSTANCER_UV``: Cycles'
    object dupli_generated and dupli_uv, zeros for an object that is no instance), a per-draw vec4
    as the object's attributes are (``g.uniform_attributes``); None beyond their limit."""
    a = w.uniform_attribute(kind, "")
    return f"{a}.xyz" if a is not None else None


def _texcoord(w: _Writer, node: FlatNode) -> dict | None:
    """Texture Coordinate (Cycles' svm_node_tex_coord): Generated and Object from GraphInputs, the
    Object output in another object's space where its Object is set (that object's matrix, read
    with the graph: a constant), Normal in object space, Camera, Window, Reflection. From
    Instancer: Generated and UV are the instancer's at the instance (``_from_instancer``)."""
    generated, uv = "g.generated", "g.uv"
    if node.props.get("from_instancer"):
        read = _read_outputs(w.flat, node)
        if "Generated" in read:
            generated = _from_instancer(w, "INSTANCER_GENERATED")
        if "UV" in read:
            uv = _from_instancer(w, "INSTANCER_UV")
        if generated is None or uv is None:
            return None
    matrix = node.props.get("object_matrix")
    known = {"Generated": generated, "Normal": "node_texcoord_normal(g)", "UV": uv,
             "Object": f"node_texcoord_object_from({_mat4(w, matrix)}, g)" if matrix else "g.object",
             "Camera": "node_texcoord_camera(g)", "Window": "node_texcoord_window(g)",
             "Reflection": "node_texcoord_reflection(g)"}
    return {s: e for s, e in known.items() if s in node.outputs}


def _uv_map(w: _Writer, node: FlatNode) -> dict | None:
    """UV Map: the active map (g.uv) or a named one (an attribute); From Instancer: the instancer's
    UV at the instance, whichever map is named (Cycles' NODE_TEXCO_DUPLI_UV)."""
    if node.props.get("from_instancer"):
        uv = _from_instancer(w, "INSTANCER_UV")
        return {"UV": uv} if uv is not None else None
    name = node.props.get("uv_map", "")
    return {"UV": f"{w.attribute('UV', name)}.xyz" if name else "g.uv"}


def _tangent_of(w: _Writer, name: str) -> str:
    """A UV map's tangent: the active map's ``g.tangent``, a named map's an attribute."""
    return w.attribute("TANGENT", name) if name else "g.tangent"


def _tangent(w: _Writer, node: FlatNode) -> dict | None:
    """Tangent (Cycles' svm_node_tangent): a UV map's, or radial about an axis of Generated."""
    if node.props.get("direction_type") == "UV_MAP":
        return {"Tangent": f"node_tangent_uv({_tangent_of(w, node.props.get('uv_map', ''))}, g)"}
    axis = node.props.get("axis", "Z")
    if axis not in ("X", "Y", "Z"):
        return None
    return {"Tangent": f"node_tangent_radial_{axis.lower()}(g)"}


def _object_info(w: _Writer, node: FlatNode) -> dict:
    known = {"Location": "g.object_to_world[3].xyz", "Color": "vec4(g.object_color.rgb, 1.0)",
             "Alpha": "g.object_color.a", "Object Index": "g.object_info.x",
             "Material Index": "g.object_info.y", "Random": "g.object_info.z"}
    return {s: e for s, e in known.items() if s in node.outputs}


def _camera_data(w: _Writer, node: FlatNode) -> dict:
    known = {"View Vector": "node_camera_view_vector(g)", "View Z Depth": "node_camera_view_z_depth(g)",
             "View Distance": "node_camera_view_distance(g)"}
    return {s: e for s, e in known.items() if s in node.outputs}


def _light_path(w: _Writer, node: FlatNode) -> dict:
    """Light Path for what a rasteriser draws, a camera ray's hit (Cycles' svm_node_light_path on
    its camera rays): Is Camera Ray 1, every other kind and every depth 0, Ray Length the
    distance the camera ray travelled."""
    known = {"Is Camera Ray": "1.0", "Ray Length": "node_light_path_ray_length(g)"}
    return {s: known.get(s, "0.0") for s in node.outputs}


_SPACES = ("WORLD", "OBJECT", "CAMERA")


def _vector_transform(w: _Writer, node: FlatNode) -> dict | None:
    """Vector Transform (Cycles' svm_node_vector_transform): a point, vector or normal from one of
    world, object and camera space to another (a space to itself: unchanged, as Cycles does)."""
    kind = node.props.get("vector_type", "VECTOR")
    src, dst = node.props.get("convert_from", "WORLD"), node.props.get("convert_to", "OBJECT")
    if kind not in ("POINT", "VECTOR", "NORMAL") or src not in _SPACES or dst not in _SPACES:
        return None
    v = w.arg(node, "Vector")
    if src == dst:
        return {"Vector": v}
    return {"Vector": f"vector_transform_{kind.lower()}({v}, graph_space_{src.lower()}_to_{dst.lower()}(g))"}


#: Attribute nodes of other types than Geometry a graph reads at most (each a per-draw vec4).
MAX_UNIFORM_ATTRIBUTES = 2


def _attribute(w: _Writer, node: FlatNode) -> dict | None:
    """Attribute: of the geometry (by name: a generic attribute, colour attribute or UV map), or
    the object's, its instancer's or the view layer's (a property by name, the same over the
    object: ``g.uniform_attributes``, the engine resolves it as Cycles' lookup_instance_property)."""
    kind = node.props.get("attribute_type", "GEOMETRY")
    if kind == "GEOMETRY":
        a = w.attribute("GENERIC", node.props.get("attribute_name", ""))
    elif kind in ("OBJECT", "INSTANCER", "VIEW_LAYER"):
        a = w.uniform_attribute(kind, node.props.get("attribute_name", ""))
        if a is None:
            return None
    else:
        return None
    known = {"Color": f"vec4({a}.rgb, 1.0)", "Vector": f"{a}.xyz", "Fac": f"node_attribute_fac({a})",
             "Alpha": f"{a}.a"}
    return {s: e for s, e in known.items() if s in node.outputs}


def _color_attribute(w: _Writer, node: FlatNode) -> dict:
    """Color Attribute: a colour attribute by name (the mesh's default one where none is named)."""
    a = w.attribute("COLOR", node.props.get("layer_name", ""))
    return {"Color": f"vec4({a}.rgb, 1.0)", "Alpha": f"{a}.a"}


_NORMAL_MAP_SPACES = ("TANGENT", "OBJECT", "WORLD", "BLENDER_OBJECT", "BLENDER_WORLD")


def _normal_map(w: _Writer, node: FlatNode) -> dict | None:
    """Normal Map (Cycles' svm_node_normal_map): tangent space with the active or a named UV map's
    tangent, object or world space, and Blender's object and world spaces (y, z flipped)."""
    space = node.props.get("space", "TANGENT")
    if space not in _NORMAL_MAP_SPACES:
        return None
    strength, color = w.arg(node, "Strength"), w.arg(node, "Color")
    if space == "TANGENT":
        t = _tangent_of(w, node.props.get("uv_map", ""))
        return {"Normal": f"node_normal_map_tangent({strength}, {color}, {t}, g)"}
    return {"Normal": f"node_normal_map_{space.lower()}({strength}, {color}, g)"}


#: The Bump node's Filter Width where Blender's Bump has none (before 4.3): Cycles then stepped a
#: whole ray differential (svm_node_bump_P_dx without a width) and bent by the whole determinant,
#: which is the later rule at width 1 (Blender's versioning sets an older file's Filter Width to 1).
BUMP_FILTER_WIDTH = 1.0


def upstream(flat: FlatGraph, name: str, stop: frozenset[str] = frozenset()) -> list[str]:
    """The flat nodes ``name`` reads, itself included, in the flat graph's order; the inputs of
    the nodes in ``stop`` are not followed (their outputs come from bakes: ``materials.bake``)."""
    seen, pending = set(), [name]
    while pending:
        current = pending.pop()
        if current in seen or current not in flat.nodes:
            continue
        seen.add(current)
        if current not in stop:
            inputs = flat.nodes[current].inputs.values()
            pending += [i.source.node for i in inputs if isinstance(i.source, Ref)]
    return [n for n in flat.nodes if n in seen]


def _height_at(w: _Writer, node: FlatNode, axis: str, filter_width: str) -> str:
    """The Bump's Height at the fragment moved along Cycles' position differential ``axis`` (its
    bump offsets of the inputs) by ``filter_width`` (glsl/node_normal.glsl's graph_inputs_dx / _dy):
    every node the Height reads written again, reading the moved fragment's GraphInputs."""
    spec = node.inputs["Height"]
    if not isinstance(spec.source, Ref) or (spec.source.node, spec.source.socket) not in w.values:
        return w.arg(node, "Height")  # a constant height (or one that did not compile): no slope
    moved = w.once("GraphInputs", f"graph_inputs_d{axis}(g, {filter_width})")
    above = upstream(w.flat, spec.source.node)
    saved = w.values, w.g
    w.values = {k: v for k, v in w.values.items() if k[0] not in above}
    w.g = moved
    try:
        for name in above:
            other = w.flat.nodes[name]
            outputs, _ = _emit(w, other)
            if outputs is not None:  # what did not compile was named missing the first time
                w.define(other, outputs)
        return w.arg(node, "Height")
    finally:
        w.values, w.g = saved


def _bump(w: _Writer, node: FlatNode) -> dict:
    """Bump (Cycles' svm_node_set_bump): the Height here and at the fragment moved by Filter Width
    times Cycles' two position differentials."""
    fw = w.arg(node, "Filter Width") if "Filter Width" in node.inputs \
        else w.constant(BUMP_FILTER_WIDTH, "VALUE")
    h = w.arg(node, "Height")
    hx, hy = _height_at(w, node, "x", fw), _height_at(w, node, "y", fw)
    fn = "node_bump_inverted" if node.props.get("invert") else "node_bump"
    args = (w.arg(node, "Strength"), w.arg(node, "Distance"), fw, h, hx, hy, _normal_input(w, node))
    return {"Normal": f"{fn}({', '.join(args)}, g)"}


def _normal_input(w: _Writer, node: FlatNode) -> str:
    """A node's Normal input: the fragment's shading normal where nothing is linked to it (its
    socket's value is Blender's placeholder, not a normal)."""
    spec = node.inputs.get("Normal")
    return w.arg(node, "Normal") if spec is not None and isinstance(spec.source, Ref) else "g.n"


def _geometry(w: _Writer, node: FlatNode) -> dict:
    """The Geometry node (Cycles' svm_node_geometry): Position, Normal, Tangent (radial about
    Generated's Z as Cycles' primitive_tangent), True Normal, Incoming, Backfacing from the
    fragment; Parametric from its triangle (``g.triangle``); Pointiness and Random Per Island as
    the attributes Cycles makes of the mesh (``POINTINESS``, ``RANDOM_PER_ISLAND``: the engine
    computes them per corner where a graph reads them, addon/materials/mesh_attributes.py). Only
    the outputs the graph reads are written: what they need of the mesh is drawn only where needed."""
    read = _read_outputs(w.flat, node)
    read = [s for s in node.outputs if s in read]  # in the node's order: one source per structure
    known = {"Position": "g.position", "Normal": "g.n", "Tangent": "node_tangent_radial_z(g)",
             "True Normal": "g.ng", "Incoming": "g.i", "Backfacing": "(g.backfacing ? 1.0 : 0.0)",
             "Parametric": "node_geometry_parametric(g)"}
    attributes = {"Pointiness": "POINTINESS", "Random Per Island": "RANDOM_PER_ISLAND"}
    return {s: known[s] if s in known else f"{w.attribute(attributes[s], '')}.x" for s in read
            if s in known or s in attributes}


def _read_outputs(flat: FlatGraph, node: FlatNode) -> set[str]:
    """The outputs of ``node`` that some node of ``flat`` reads."""
    return {i.source.socket for other in flat.nodes.values() for i in other.inputs.values()
            if isinstance(i.source, Ref) and i.source.node == node.name}


def _wireframe(w: _Writer, node: FlatNode) -> dict:
    """Wireframe (Cycles' svm_node_wireframe): 1 within Size / 2 of an edge of the fragment's
    triangle, Size in world units or (Pixel Size) in the camera ray's width at the fragment."""
    fn = "node_wireframe_pixel" if node.props.get("use_pixel_size") else "node_wireframe"
    return {"Fac": f"{fn}({w.arg(node, 'Size')}, g)"}


def _layer_weight(w: _Writer, node: FlatNode) -> dict:
    blend, n = w.arg(node, "Blend"), _normal_input(w, node)
    return {"Fresnel": f"node_layer_weight_fresnel({blend}, {n}, g)",
            "Facing": f"node_layer_weight_facing({blend}, {n}, g)"}


def _math(w: _Writer, node: FlatNode) -> dict | None:
    fn = _MATH_FUNCTIONS.get(node.props.get("operation"))
    if fn is None:
        return None
    args = [w.arg(node, s) if s in node.inputs else "0.0" for s in ("Value", "Value_001", "Value_002")]
    expr = f"{fn}({', '.join(args)})"
    if node.props.get("use_clamp"):
        expr = f"clamp({expr}, 0.0, 1.0)"
    return {"Value": expr}


def _mix(w: _Writer, node: FlatNode) -> dict | None:
    """The Mix node: floats and vectors interpolated (a vector by one factor or by one per
    component), colours by their blend mode; the factor clamped to [0, 1] where the node says so
    (Clamp Factor), a colour's result too (Clamp Result); a colour keeps A's alpha."""
    kind = node.props.get("data_type")
    uniform = node.props.get("factor_mode", "UNIFORM") == "UNIFORM" or kind != "VECTOR"
    fac = w.arg(node, "Factor_Float" if uniform else "Factor_Vector")
    if node.props.get("clamp_factor", True):
        fac = f"clamp({fac}, 0.0, 1.0)"
    if kind == "FLOAT":
        return {"Result_Float": f"mix({w.arg(node, 'A_Float')}, {w.arg(node, 'B_Float')}, {fac})"}
    if kind == "VECTOR":
        return {"Result_Vector": f"mix({w.arg(node, 'A_Vector')}, {w.arg(node, 'B_Vector')}, {fac})"}
    fn = _MIX_FUNCTIONS.get(node.props.get("blend_type"))
    if kind != "RGBA" or fn is None:
        return None
    return {"Result_Color": _blend(fn, fac, w.arg(node, "A_Color"), w.arg(node, "B_Color"),
                                   node.props.get("clamp_result"))}


def _blend(fn: str, fac: str, a: str, b: str, clamp_result) -> str:
    """Colour ``a`` blended with ``b`` by the blend mode's function ``fn`` at factor ``fac``, the
    result clamped to [0, 1] where asked; ``a``'s alpha kept (the Mix node's and Mix RGB's)."""
    rgb = f"{fn}({fac}, {a}.rgb, {b}.rgb)"
    if clamp_result:
        rgb = f"clamp({rgb}, 0.0, 1.0)"
    return f"vec4({rgb}, {a}.a)"


def _call(fn: str, w: _Writer, node: FlatNode, inputs: tuple[str, ...], output: str) -> dict:
    return {output: f"{fn}({', '.join(w.arg(node, s) for s in inputs)})"}


def _clamp(w: _Writer, node: FlatNode) -> dict:
    fn = "clamp_range" if node.props.get("clamp_type") == "RANGE" else "clamp_minmax"
    return _call(fn, w, node, ("Value", "Min", "Max"), "Result")


_MAP_RANGE_KINDS = ("LINEAR", "STEPPED", "SMOOTHSTEP", "SMOOTHERSTEP")


def _map_range(w: _Writer, node: FlatNode) -> dict | None:
    """Map Range: on a float (Cycles adds a Clamp, in either order of the target range, after a
    linear or stepped mapping whose Clamp is on), or per component of a vector."""
    kind = node.props.get("interpolation_type", "LINEAR")
    if kind not in _MAP_RANGE_KINDS:
        return None
    clamp = bool(node.props.get("clamp"))
    if node.props.get("data_type", "FLOAT") == "FLOAT_VECTOR":
        names = ("Vector", "From_Min_FLOAT3", "From_Max_FLOAT3", "To_Min_FLOAT3", "To_Max_FLOAT3")
        args = [w.arg(node, s) for s in names]
        args.append(w.arg(node, "Steps_FLOAT3") if "Steps_FLOAT3" in node.inputs else "vec3(0.0)")
        kinds = _MAP_RANGE_KINDS.index(kind)
        return {"Vector": f"map_range_vector({kinds}, {str(clamp).lower()}, {', '.join(args)})"}
    args = [w.arg(node, s) for s in ("Value", "From Min", "From Max", "To Min", "To Max")]
    args.append(w.arg(node, "Steps") if "Steps" in node.inputs else "0.0")
    expr = f"map_range_{kind.lower()}({', '.join(args)})"
    if clamp and kind in ("LINEAR", "STEPPED"):
        expr = f"clamp_range({expr}, {args[3]}, {args[4]})"
    return {"Result": expr}


def _separate_color(w: _Writer, node: FlatNode) -> dict | None:
    mode = node.props.get("mode", "RGB")
    if mode not in ("RGB", "HSV", "HSL"):
        return None
    color = f"{w.arg(node, 'Color')}.rgb"
    value = color if mode == "RGB" else f"color_rgb_to_{mode.lower()}({color})"
    return {"Red": f"{value}.x", "Green": f"{value}.y", "Blue": f"{value}.z"}


def _combine_color(w: _Writer, node: FlatNode) -> dict | None:
    mode = node.props.get("mode", "RGB")
    if mode not in ("RGB", "HSV", "HSL"):
        return None
    rgb = f"vec3({', '.join(w.arg(node, s) for s in ('Red', 'Green', 'Blue'))})"
    return {"Color": f"vec4({rgb if mode == 'RGB' else f'color_{mode.lower()}_to_rgb({rgb})'}, 1.0)"}


def _vector_math(w: _Writer, node: FlatNode) -> dict | None:
    op = node.props.get("operation")
    if op not in VECTOR_MATH_OPERATIONS:
        return None
    vectors = ("Vector", "Vector_001", "Vector_002")
    args = [w.arg(node, s) if s in node.inputs else "vec3(0.0)" for s in vectors]
    args.append(w.arg(node, "Scale") if "Scale" in node.inputs else "1.0")
    call = f"vmath_{op.lower()}({', '.join(args)})"
    return {"Value": f"{call}.w"} if op in VECTOR_MATH_VALUES else {"Vector": f"{call}.xyz"}


def _separate_xyz(w: _Writer, node: FlatNode) -> dict:
    v = w.arg(node, "Vector")
    return {axis: f"{v}.{axis.lower()}" for axis in ("X", "Y", "Z") if axis in node.outputs}


def _combine_xyz(w: _Writer, node: FlatNode) -> dict:
    return {"Vector": f"vec3({', '.join(w.arg(node, s) for s in ('X', 'Y', 'Z'))})"}


def _convert(w: _Writer, node: FlatNode) -> dict:
    f, t = node.props["from"], node.props["to"]
    kind = {"INT": "VALUE", "BOOLEAN": "VALUE"}
    f, t = kind.get(f, f), kind.get(t, t)
    expr = w.arg(node, "Value")
    if f == t:
        return {"Value": expr}
    if f == "RGBA" and t == "VALUE":
        return {"Value": _luminance(w, expr)}
    return {"Value": f"convert_{f.lower()}_to_{t.lower()}({expr})"}


def _luminance(w: _Writer, color: str) -> str:
    """A colour read as a float, with the running Blender's weights (part of the program's source:
    one Blender, one set)."""
    return f"convert_rgba_to_value({color}, vec3({', '.join(repr(c) for c in w.flat.luma)}))"

# --- ramps, curves, vectors (glsl/node_ramp.glsl, node_vector.glsl, node_converter.glsl) ----------

def _ramp(w: _Writer, node: FlatNode) -> dict | None:
    """Color Ramp: the table the reader baked (every interpolation and colour mode), looked up
    as Cycles' svm_node_rgb_ramp; Constant picks an entry, the others blend two."""
    table = node.props.get("table")
    if table is None:
        return None
    fn = "node_ramp_linear" if node.props.get("interpolate", True) else "node_ramp_constant"
    color = w.once("vec4", f"{fn}({w.table(table)}, {w.arg(node, 'Fac')})")
    return {"Color": color, "Alpha": f"{color}.a"}


def _curves(w: _Writer, node: FlatNode) -> dict | None:
    """RGB Curves, Vector Curves, Float Curve: the reader's table over the curves' x range, as
    Cycles' svm_node_curves / svm_node_curve, extrapolated past the range where the curve's
    Extend says so; the input blended with the result by the factor."""
    table, bounds = node.props.get("table"), node.props.get("range")
    if table is None or bounds is None:
        return None
    suffix = "_extrapolated" if node.props.get("extrapolate") else ""
    lo, hi = (w.constant(b, "VALUE") for b in bounds)
    if node.kind == "ShaderNodeFloatCurve":
        values = [row[0] for row in table]
        base = w.table([values[i:i + 4] for i in range(0, len(values), 4)])  # four to a vec4
        args = f"{base}, {lo}, {hi}, {w.arg(node, 'Factor')}, {w.arg(node, 'Value')}"
        return {"Value": f"node_float_curve{suffix}({args})"}
    args = f"{w.table(table)}, {lo}, {hi}, {w.arg(node, 'Fac')}"
    if node.kind == "ShaderNodeRGBCurve":
        return {"Color": f"node_rgb_curves{suffix}({args}, {w.arg(node, 'Color')})"}
    return {"Vector": f"node_vector_curves{suffix}({args}, {w.arg(node, 'Vector')})"}


def _mapping(w: _Writer, node: FlatNode) -> dict | None:
    """Mapping (Cycles' svm_mapping): Point and Texture with a Location, Vector and Normal without."""
    kind = node.props.get("vector_type", "POINT")
    if kind not in ("POINT", "TEXTURE", "VECTOR", "NORMAL"):
        return None
    names = ("Vector", "Location", "Rotation", "Scale") if kind in ("POINT", "TEXTURE") else \
        ("Vector", "Rotation", "Scale")
    return _call(f"node_mapping_{kind.lower()}", w, node, names, "Vector")


_ROTATE_FUNCTIONS = {"AXIS_ANGLE": ("node_vector_rotate_axis_angle", ("Vector", "Center", "Axis")),
                     "X_AXIS": ("node_vector_rotate_x", ("Vector", "Center")),
                     "Y_AXIS": ("node_vector_rotate_y", ("Vector", "Center")),
                     "Z_AXIS": ("node_vector_rotate_z", ("Vector", "Center"))}


def _vector_rotate(w: _Writer, node: FlatNode) -> dict | None:
    """Vector Rotate (Cycles' svm_node_vector_rotate): about an axis (Invert: the angle negated)
    or by an Euler rotation (Invert: its inverse), around Center."""
    kind, invert = node.props.get("rotation_type"), bool(node.props.get("invert"))
    if kind == "EULER_XYZ":
        fn = "node_vector_rotate_euler_inverse" if invert else "node_vector_rotate_euler"
        return _call(fn, w, node, ("Vector", "Center", "Rotation"), "Vector")
    if kind not in _ROTATE_FUNCTIONS:
        return None
    fn, names = _ROTATE_FUNCTIONS[kind]
    angle = w.arg(node, "Angle")
    args = [w.arg(node, s) for s in names] + [f"-{angle}" if invert else angle]
    return {"Vector": f"{fn}({', '.join(args)})"}


def _normal(w: _Writer, node: FlatNode) -> dict:
    """The Normal node (Cycles' svm_node_normal): its direction (a constant) made unit, and its
    cosine to the input."""
    direction = w.constant(node.values.get("Normal", (0.0, 0.0, 1.0)), "VECTOR")
    return {"Normal": f"node_normal_direction({direction})",
            "Dot": f"node_normal_dot({direction}, {w.arg(node, 'Normal')})"}


def _wavelength(w: _Writer, node: FlatNode) -> dict | None:
    rows = node.props.get("xyz_to_rgb")
    if rows is None:
        return None
    args = ", ".join([w.arg(node, "Wavelength"), *(w.constant(row, "VECTOR") for row in rows)])
    return {"Color": f"node_wavelength({args})"}


def _mix_rgb(w: _Writer, node: FlatNode) -> dict | None:
    """The legacy Mix node (ShaderNodeMixRGB) as Cycles' svm_node_mix: the factor clamped to
    [0, 1] (svm_mix_clamped_factor), the blend mode's function of glsl/node_mix.glsl, the result
    clamped where Clamp is on; Use Alpha is not read (Cycles does not); Color1's alpha kept."""
    fn = _MIX_FUNCTIONS.get(node.props.get("blend_type"))
    if fn is None:
        return None
    a = w.arg(node, "Color1")
    fac = f"clamp({w.arg(node, 'Fac')}, 0.0, 1.0)"
    return {"Color": _blend(fn, fac, a, w.arg(node, "Color2"), node.props.get("use_clamp"))}


def _separate(space: str, inputs: str, outputs: tuple[str, str, str]):
    """The legacy Separate RGB / HSV (Blender 4): the colour's channels, or its HSV (Cycles'
    svm_node_separate_hsv)."""
    def emit(w: _Writer, node: FlatNode) -> dict:
        color = f"{w.arg(node, inputs)}.rgb"
        value = color if space == "RGB" else w.once("vec3", f"color_rgb_to_hsv({color})")
        return {name: f"{value}.{c}" for name, c in zip(outputs, "xyz") if name in node.outputs}
    return emit


def _combine(space: str, inputs: tuple[str, str, str], output: str):
    """The legacy Combine RGB / HSV (Blender 4): a colour of the three (Cycles' svm_node_combine_hsv)."""
    def emit(w: _Writer, node: FlatNode) -> dict:
        rgb = f"vec3({', '.join(w.arg(node, s) for s in inputs)})"
        return {output: f"vec4({rgb if space == 'RGB' else f'color_hsv_to_rgb({rgb})'}, 1.0)"}
    return emit


#: The Principled BSDF's inputs the models read, in glsl/node_closure.glsl's closure_principled order
#: (its normals, Normal and Coat Normal, after them).
PRINCIPLED_BASE_INPUTS = ("Base Color", "Metallic", "Roughness", "IOR", "Specular IOR Level", "Alpha",
                          "Emission Color", "Emission Strength")
PRINCIPLED_INPUTS = PRINCIPLED_BASE_INPUTS + ("Specular Tint", "Coat Weight", "Coat Roughness", "Coat IOR",
                                              "Coat Tint", "Sheen Weight", "Sheen Roughness", "Sheen Tint",
                                              "Thin Film Thickness", "Thin Film IOR")
PRINCIPLED_INPUTS += ("Transmission Weight",)

#: The values of the Principled BSDF's lobe inputs a node read from an older file may lack (Blender's
#: defaults: they add no lobe), with their socket types.
PRINCIPLED_DEFAULTS = {"Specular Tint": ((1.0, 1.0, 1.0, 1.0), "RGBA"), "Coat Weight": (0.0, "VALUE"),
                       "Coat Roughness": (0.03, "VALUE"), "Coat IOR": (1.5, "VALUE"),
                       "Coat Tint": ((1.0, 1.0, 1.0, 1.0), "RGBA"), "Sheen Weight": (0.0, "VALUE"),
                       "Sheen Roughness": (0.5, "VALUE"), "Sheen Tint": ((1.0, 1.0, 1.0, 1.0), "RGBA"),
                       "Thin Film Thickness": (0.0, "VALUE"), "Thin Film IOR": (1.33, "VALUE"),
                       "Transmission Weight": (0.0, "VALUE")}


def _principled(w: _Writer, node: FlatNode) -> dict:
    """The Principled BSDF (closure_principled); its Coat Normal is its Normal where nothing is
    linked to it, as Cycles' svm_node_closure_bsdf takes it."""
    args = [w.arg(node, s) if s in node.inputs else w.constant(*PRINCIPLED_DEFAULTS[s])
            for s in PRINCIPLED_INPUTS]
    n = _normal_input(w, node)
    coat = node.inputs.get("Coat Normal")
    coat_n = w.arg(node, "Coat Normal") if coat is not None and isinstance(coat.source, Ref) else n
    path = _subsurface_path(w, node, "subsurface_method", "Subsurface Radius", "Subsurface Scale",
                            args[0], "Subsurface IOR")
    weight = (w.arg(node, "Subsurface Weight") if "Subsurface Weight" in node.inputs
              else w.constant(0.0, "VALUE"))
    # the diffuse base's Oren-Nayar roughness (Blender 4.3 and later; before, Lambert)
    rough = (w.arg(node, "Diffuse Roughness") if "Diffuse Roughness" in node.inputs
             else w.constant(0.0, "VALUE"))
    walk = _subsurface_walk(w, node, "subsurface_method", "Subsurface Anisotropy", "Subsurface IOR",
                            (args[3], args[4]))
    closure = f"closure_principled({', '.join(args)}, {n}, {coat_n}, {weight}, {path}, {rough}, {walk})"
    return {"BSDF": _anisotropic(w, node, closure)}


#: The anisotropic BSDFs' inputs (glsl/node_anisotropy.glsl), by node kind: the amount's socket, the
#: rotation's, the GLSL function of the lobe's stretch, and the amount's threshold (Cycles'
#: svm_node_closure_bsdf: the Principled and Metallic BSDFs' saturated amount above 0, the Glossy
#: BSDF's |Anisotropy| above 1e-4; the Principled BSDF's tangent only from 1e-5, CLOSURE_WEIGHT_CUTOFF).
ANISOTROPIC = {"ShaderNodeBsdfPrincipled": ("Anisotropic", "Anisotropic Rotation",
                                            "principled_anisotropic_stretch", lambda a: a >= 1e-5),
               "ShaderNodeBsdfMetallic": ("Anisotropy", "Rotation", "principled_anisotropic_stretch",
                                          lambda a: a > 0.0),
               "ShaderNodeBsdfGlossy": ("Anisotropy", "Rotation", "glossy_anisotropic_stretch",
                                        lambda a: abs(a) > 1e-4)}
ANISOTROPIC["ShaderNodeBsdfAnisotropic"] = ANISOTROPIC["ShaderNodeBsdfGlossy"]  # the Glossy BSDF's own name


def anisotropic(node: FlatNode) -> bool:
    """Whether the BSDF ``node`` can draw an anisotropic lobe: its amount linked (per fragment: on),
    or its value past Cycles' threshold (``ANISOTROPIC``)."""
    spec = ANISOTROPIC.get(node.kind)
    amount = node.inputs.get(spec[0]) if spec is not None else None
    if amount is None:
        return False
    if not isinstance(amount.source, Const):
        return True
    value = amount.source.value
    return value is not None and spec[3](float(value))


def _anisotropic(w: _Writer, node: FlatNode, closure: str) -> str:
    """The BSDF's ``closure`` made anisotropic where it can be (``anisotropic``): its stretch, Tangent
    (where nothing is linked to it the Geometry node's, radial about Generated's Z, as Cycles links
    LINK_TANGENT sockets) and Rotation about its normal. Isotropic BSDFs compile without them (and
    without Generated); turning the amount on or off changes the source, as it changes the program's
    lobes (SL_ANISOTROPY) too."""
    if not anisotropic(node):
        return closure
    amount, rotation, stretch, _ = ANISOTROPIC[node.kind]
    tangent = node.inputs.get("Tangent")
    t = w.arg(node, "Tangent") if tangent is not None and isinstance(tangent.source, Ref) \
        else "node_tangent_radial_z(g)"
    turn = w.arg(node, rotation) if rotation in node.inputs else w.constant(0.0, "VALUE")
    n = _normal_input(w, node)
    return f"closure_anisotropic({closure}, {stretch}({w.arg(node, amount)}), {t}, {turn}, {n})"



#: The subsurface methods' mean free path functions (glsl/node_subsurface.glsl)
SUBSURFACE_PATHS = {"BURLEY": "subsurface_path", "RANDOM_WALK": "subsurface_path",
                    "RANDOM_WALK_SKIN": "subsurface_path_skin"}


def _subsurface_path(w: _Writer, node: FlatNode, method: str, radius: str, scale: str, albedo: str,
                     ior: str) -> str:
    """The mean free path of a Principled BSDF's subsurface or a Subsurface Scattering node, its
    method (the node's setting ``method``) choosing the function; a missing input: Blender's default."""
    def arg(socket, default, kind):
        return w.arg(node, socket) if socket in node.inputs else w.constant(default, kind)

    r = f"{arg(radius, (1.0, 0.2, 0.1), 'VECTOR')}.xyz"
    s = arg(scale, 0.05, "VALUE")
    function = SUBSURFACE_PATHS.get(node.props.get(method, "RANDOM_WALK"), "subsurface_path")
    if function == "subsurface_path_skin":
        return f"{function}({r}, {s}, {albedo}.rgb, {arg(ior, 1.4, 'VALUE')})"
    return f"{function}({r}, {s})"


def _subsurface_walk(w: _Writer, node: FlatNode, method: str, anisotropy: str, ior: str,
                     principled: tuple | None = None) -> str:
    """The random walk's row of a Principled BSDF's subsurface or a Subsurface Scattering node
    (glsl/node_subsurface.glsl's subsurface_walk_*), its method (the node's setting ``method``)
    choosing the function: Christensen-Burley none; Random Walk the Principled BSDF's IOR, Specular
    IOR Level (``principled``: their expressions; its Roughness the material's) or the node's IOR
    and Roughness;
    Skin the ``ior`` socket's. A missing input: Blender's default."""
    def arg(socket, default):
        return w.arg(node, socket) if socket in node.inputs else w.constant(default, "VALUE")

    g = arg(anisotropy, 0.0)
    kind = node.props.get(method, "RANDOM_WALK")
    if kind == "BURLEY":
        return f"subsurface_walk_burley({g})"
    if kind == "RANDOM_WALK_SKIN":
        return f"subsurface_walk_skin({g}, {arg(ior, 1.4)})"
    if principled is not None:
        return f"subsurface_walk_principled({g}, {', '.join(principled)})"
    return f"subsurface_walk_random({g}, {arg(ior, 1.4)}, {arg('Roughness', 1.0)})"


def _subsurface(w: _Writer, node: FlatNode) -> dict:
    """The Subsurface Scattering node (closure_subsurface), its Falloff choosing the mean free path
    and the random walk's row."""
    color = _closure_color(w, node)
    path = _subsurface_path(w, node, "falloff", "Radius", "Scale", color, "IOR")
    walk = _subsurface_walk(w, node, "falloff", "Anisotropy", "IOR")
    return {"BSSRDF": f"closure_subsurface({color}, {path}, {walk}, {_normal_input(w, node)})"}


def _closure_color(w: _Writer, node: FlatNode) -> str:
    """A closure's colour input ("Color", the Metallic BSDF's "Base Color"); grey where it has none."""
    for socket in ("Color", "Base Color"):
        if socket in node.inputs:
            return w.arg(node, socket)
    return "vec4(0.8, 0.8, 0.8, 1.0)"


def _closure_roughness(w: _Writer, node: FlatNode) -> str:
    return w.arg(node, "Roughness") if "Roughness" in node.inputs else "0.5"


def _unknown_closure(w: _Writer, node: FlatNode) -> dict:
    """A closure no emitter knows (Glass, Toon, Subsurface ...): a dielectric of its colour and
    roughness, so that the material keeps its colour; the node is reported as not compiled."""
    color, rough = _closure_color(w, node), _closure_roughness(w, node)
    return {s: f"closure_bsdf({color}.rgb, 0.0, {rough}, 0.04, {_normal_input(w, node)})"
            for s, t in node.outputs.items() if t == "SHADER"}


def _glass(function: str, w: _Writer, node: FlatNode) -> dict:
    """Glass and Refraction BSDFs (glsl/node_closure.glsl's closure_glass, closure_refraction): a
    transmitting dielectric of their colour, roughness and IOR; their distribution (GGX, Beckmann,
    Multiscatter GGX) is drawn as the Principled set's GGX."""
    return {"BSDF": f"{function}({_closure_color(w, node)}, {_closure_roughness(w, node)}, "
                    f"{w.arg(node, 'IOR')}, {_normal_input(w, node)})"}


#: The Glossy BSDF's distributions, each its closure (glsl/node_closure.glsl, node_closure_bsdfs.glsl).
GLOSSY_DISTRIBUTIONS = {"MULTI_GGX": "closure_glossy", "GGX": "closure_glossy_ggx",
                        "BECKMANN": "closure_glossy_beckmann",
                        "ASHIKHMIN_SHIRLEY": "closure_glossy_ashikhmin_shirley"}


def _glossy(w: _Writer, node: FlatNode) -> dict | None:
    """Glossy and Anisotropic BSDFs: its colour times its distribution's lobe (a metal of its colour
    where the program does not draw the GLOSSY lobe), anisotropic where it is (``_anisotropic``)."""
    fn = GLOSSY_DISTRIBUTIONS.get(node.props.get("distribution", "MULTI_GGX"))
    if fn is None:
        return None
    args = f"{_closure_color(w, node)}, {_closure_roughness(w, node)}, {_normal_input(w, node)}"
    return {"BSDF": _anisotropic(w, node, f"{fn}({args})")}


def _metallic(w: _Writer, node: FlatNode) -> dict | None:
    """The Metallic BSDF (glsl/node_closure_bsdfs.glsl): F82 Tint the Principled BSDF's metal with its
    edge tint; Physical Conductor the metal of its IOR's and Extinction's reflectance at normal
    incidence; its GGX and Beckmann distributions marked (Multiscatter GGX: the metal's own)."""
    fresnel = node.props.get("fresnel_type", "F82")
    if fresnel == "F82":
        out = _bsdf("closure_metallic_f82", w, node, ("Base Color", "Edge Tint", "Roughness"))
    elif fresnel == "PHYSICAL_CONDUCTOR":
        out = _bsdf("closure_metallic_conductor", w, node, ("IOR", "Extinction", "Roughness"))
    else:
        return None
    mark = {"GGX": "closure_metallic_ggx", "BECKMANN": "closure_metallic_beckmann"}.get(
        node.props.get("distribution", "MULTI_GGX"))
    closure = f"{mark}({out['BSDF']})" if mark else out["BSDF"]
    return {"BSDF": _anisotropic(w, node, closure)}


def _bsdf(fn: str, w: _Writer, node: FlatNode, inputs: tuple[str, ...]) -> dict:
    """A BSDF node's closure: ``fn`` of its ``inputs`` and its Normal."""
    return {"BSDF": f"{fn}({', '.join(w.arg(node, s) for s in inputs)}, {_normal_input(w, node)})"}


def _sheen(w: _Writer, node: FlatNode) -> dict | None:
    """The Sheen BSDF: Microfiber the Principled BSDF's sheen alone, Ashikhmin the velvet
    (glsl/node_closure_bsdfs.glsl)."""
    fn = {"MICROFIBER": "closure_sheen_microfiber", "ASHIKHMIN": "closure_sheen_ashikhmin"}.get(
        node.props.get("distribution", "MICROFIBER"))
    if fn is None:
        return None
    return _bsdf(fn, w, node, ("Color", "Roughness"))


def _toon(w: _Writer, node: FlatNode) -> dict | None:
    """The Toon BSDF, its Diffuse or Glossy component (glsl/node_closure_bsdfs.glsl)."""
    component = node.props.get("component", "DIFFUSE")
    if component not in ("DIFFUSE", "GLOSSY"):
        return None
    args = ", ".join(w.arg(node, s) for s in ("Color", "Size", "Smooth"))
    return {"BSDF": f"closure_toon({args}, {_normal_input(w, node)}, {str(component == 'GLOSSY').lower()})"}


#: The Specular BSDF's (EEVEE's node) inputs read, in glsl/node_closure_bsdfs.glsl's closure_specular order.
SPECULAR_INPUTS = ("Base Color", "Specular", "Roughness", "Emissive Color", "Transparency")
#: The closure nodes that are a lobe by themselves, whatever their settings.
CLOSURE_NODE_LOBES = {"ShaderNodeBsdfToon": "TOON", "ShaderNodeBsdfTranslucent": "TRANSLUCENT",
                      "ShaderNodeSubsurfaceScattering": "SUBSURFACE"}
#: The Sheen BSDF's distributions and the lobe each draws.
SHEEN_LOBES = {"MICROFIBER": "SHEEN", "ASHIKHMIN": "VELVET"}


def closure_node_lobes(node: FlatNode) -> frozenset[str]:
    """The lobes (``snapshot.LOBES``) a closure node other than the Principled BSDF draws (empty: none):
    the Diffuse BSDF's Oren-Nayar roughness, the Sheen BSDF's (Microfiber: the Principled BSDF's sheen),
    the Toon BSDF's, the Translucent BSDF's and the Subsurface Scattering node's; the Glossy BSDF's and
    the Metallic BSDF's GGX and Beckmann distributions, the Metallic BSDF's F82 edge tint where it is
    not white (a Physical Conductor's always: its fitted edge tint, ``_metallic``), the Specular BSDF's
    coloured F0."""
    if node.kind in CLOSURE_NODE_LOBES:
        return frozenset({CLOSURE_NODE_LOBES[node.kind]})
    if node.kind == "ShaderNodeBsdfDiffuse":
        return frozenset({"DIFFUSE_ROUGHNESS"})
    if node.kind == "ShaderNodeBsdfSheen":
        lobe = SHEEN_LOBES.get(node.props.get("distribution", "MICROFIBER"))
        return frozenset({lobe} if lobe else ())
    if node.kind in ("ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic"):
        return frozenset({"GLOSSY"})
    if node.kind == "ShaderNodeBsdfMetallic":
        out = {"GLOSSY"} if node.props.get("distribution") in ("GGX", "BECKMANN") else set()
        fresnel = node.props.get("fresnel_type", "F82")
        if fresnel == "PHYSICAL_CONDUCTOR":
            out.add("SPECULAR_TINT")
        elif fresnel == "F82":
            tint = node.inputs.get("Edge Tint")  # the metal's F82 edge tint
            white = (1.0,) * 3
            if not (tint is None or isinstance(tint.source, Const) and tuple(tint.source.value[:3]) == white):
                out.add("SPECULAR_TINT")
        return frozenset(out)
    if node.kind == "ShaderNodeEeveeSpecular":  # its Specular's colour: the dielectric's F0 tint
        spec = node.inputs.get("Specular")
        grey = spec is not None and isinstance(spec.source, Const) and len(set(spec.source.value[:3])) == 1
        return frozenset() if grey else frozenset({"SPECULAR_TINT"})
    return frozenset()


CLOSURES = {
    "ShaderNodeBsdfPrincipled": _principled,
    "ShaderNodeBsdfDiffuse": lambda w, n: _bsdf("closure_diffuse", w, n, ("Color", "Roughness")),
    "ShaderNodeBsdfSheen": _sheen,
    "ShaderNodeBsdfToon": _toon,
    "ShaderNodeEeveeSpecular": lambda w, n: _bsdf("closure_specular", w, n, SPECULAR_INPUTS),
    "ShaderNodeBsdfGlossy": _glossy,
    "ShaderNodeBsdfAnisotropic": _glossy,
    "ShaderNodeBsdfMetallic": _metallic,
    "ShaderNodeBsdfGlass": lambda w, n: _glass("closure_glass", w, n),
    "ShaderNodeBsdfRefraction": lambda w, n: _glass("closure_refraction", w, n),
    "ShaderNodeEmission": lambda w, n: _call("closure_emission", w, n, ("Color", "Strength"), "Emission"),
    "ShaderNodeBsdfTransparent": lambda w, n: _call("closure_transparent", w, n, ("Color",), "BSDF"),
    "ShaderNodeBsdfTranslucent": lambda w, n: {"BSDF": f"closure_translucent({_closure_color(w, n)}, "
                                                       f"{_normal_input(w, n)})"},
    "ShaderNodeSubsurfaceScattering": _subsurface,
    "ShaderNodeHoldout": lambda w, n: {"Holdout": "closure_holdout()"},
    "ShaderNodeMixShader": lambda w, n: _call("closure_mix", w, n, ("Fac", "Shader", "Shader_001"), "Shader"),
    "ShaderNodeAddShader": lambda w, n: _call("closure_add", w, n, ("Shader", "Shader_001"), "Shader"),
}


#: The Image Texture node's settings, as glsl/node_texture_image.glsl names them (Smart is
#: Cycles' cubic filter).
IMAGE_INTERPOLATIONS = {"Closest": "TEX_IMAGE_CLOSEST", "Linear": "TEX_IMAGE_LINEAR",
                        "Cubic": "TEX_IMAGE_CUBIC", "Smart": "TEX_IMAGE_CUBIC"}
IMAGE_EXTENSIONS = {e: f"TEX_IMAGE_{e}" for e in ("REPEAT", "EXTEND", "CLIP", "MIRROR")}
IMAGE_PROJECTIONS = ("FLAT", "BOX", "SPHERE", "TUBE")
#: The colour space whose 8-bit images the engine uploads as SRGB8 (decoded by the sampler), as
#: addon/blender/extract.py's _read_image decides; other 8-bit images are UNORM8, their bytes.
SRGB_SPACE = "sRGB"


def image_texels(props: dict) -> str:
    """How the node's sampler holds its image and how Cycles stores it
    (glsl/node_texture_image.glsl's TEX_IMAGE_TEXELS_*), from the image's settings the reader
    read: float images as they are; 8-bit ones as bytes (sRGB ones as the engine's SRGB8 storage,
    images.read_image), alpha premultiplied in bytes as Cycles' image loader does unless the
    image is data, channel packed or has its alpha ignored."""
    if props.get("image_is_float"):
        return "TEX_IMAGE_TEXELS_FLOAT"
    srgb = props.get("image_colorspace") == SRGB_SPACE
    associate = _associates_alpha(props)
    return f"TEX_IMAGE_TEXELS_{'SRGB' if srgb else 'BYTES'}{'_ASSOCIATE' if associate else ''}"


def _associates_alpha(props: dict) -> bool:
    """Cycles' rule for an image's alpha (ImageMetaData::finalize, ImageTextureNode::compile): the
    colour is premultiplied (and divided again where the Alpha output is read) unless the image is
    data (Non-Color) or its alpha is channel packed or ignored."""
    return not (props.get("image_is_data") or props.get("image_alpha_mode") in ("CHANNEL_PACKED", "NONE"))


def sampler_keys(entry: str | tuple[str, ...]) -> tuple[str, ...]:
    """The image keys of one of ``Compiled.images``: a key, or a 2D array's (a UDIM image's tiles)."""
    return entry if isinstance(entry, tuple) else (entry,)


def tile_key(key: str, tile: int) -> str:
    """The key of a UDIM image's tile ``tile`` in ``Snapshot.images`` (image ``key``'s)."""
    return f"{key}#{tile}"


def _tiled(w: _Writer, node: FlatNode, co: str, args: str) -> str | None:
    """A UDIM image's Flat, Sphere or Tube sample (filtered, before tex_image_output), as Cycles'
    svm_node_tex_image finds the tile at the projected uv: one 2D-array sampler of the tiles where
    every tile has one size (the tiles Blender has no pixels for are layers drawn as missing),
    else a sampler per tile; the tile numbers are a table of constants. None where the limits
    (``MAX_TILES``, ``MAX_IMAGES``) do not let it compile."""
    props = node.props
    tiles = tuple(props.get("image_tiles") or ())
    if not tiles:
        return None
    if len(tiles) > MAX_TILES:
        w.notes.append(f"{node.name.rsplit('/', 1)[-1]}: {len(tiles)} UDIM tiles, more than {MAX_TILES}; "
                       f"not drawn")
        return None
    rows = 1 << max(0, (len(tiles) + 3) // 4 - 1).bit_length()  # a power of two: a tile more seldom
    # changes the source
    padded = list(tiles) + [0] * (4 * rows - len(tiles))
    table = w.table([padded[i:i + 4] for i in range(0, len(padded), 4)])
    projection = props.get("projection", "FLAT")
    uv = {"FLAT": f"{co}.xy", "SPHERE": f"tex_image_map_to_sphere(tex_image_remap_square({co}))",
          "TUBE": f"tex_image_map_to_tube(tex_image_remap_square({co}))"}[projection]
    keys = tuple(tile_key(props["image"], t) for t in tiles)
    sizes = {tuple(s) for s in props.get("image_tile_sizes") or () if tuple(s) != (0, 0)}
    if len(sizes) <= 1:
        image = w.image(keys)
        if image is None:
            w.over_limit(node, 1)
            return None
        return w.once("vec4", f"node_tex_image_tiled({image}, {uv}, {table}, {rows}, {args})")
    new = [key for key in keys if key not in w.images]  # tiles of different sizes: a sampler each
    if len(w.images) + len(new) > MAX_IMAGES:
        w.over_limit(node, len(w.images) + len(new) - MAX_IMAGES)
        return None
    images = [w.image(key) for key in keys]
    tile = w.once("vec3", f"tex_image_tile({uv}, {table}, {rows})")
    sample = "node_tex_image_missing()"
    for k in reversed(range(len(images))):  # the tile's index as a float: exact
        sample = f"({tile}.z == {k}.0 ? tex_image_filter({images[k]}, {tile}.xy, {args}) : {sample})"
    return w.once("vec4", sample)


def _image_texture(w: _Writer, node: FlatNode) -> dict | None:
    """The Image Texture node (glsl/node_texture_image.glsl): its image filtered as Cycles does
    at the Vector (the UV map's where nothing is linked), by projection, interpolation and
    extension. The Color output is divided by alpha only where the node's Alpha is read (Cycles'
    NODE_IMAGE_ALPHA_UNASSOCIATE); an 8-bit sRGB image is decoded after filtering. Without an
    image: Cycles' missing-texture magenta. A UDIM (tiled) image: the tile at the coordinate
    (``_tiled``); Box projects onto tile 1001 alone, as Cycles (ImageTextureNode::cull_tiles)."""
    props = node.props
    if props.get("texture_mapping"):
        return None  # the node's own Texture Mapping (its sidebar) is not compiled
    if props.get("image") is None:
        return {"Color": "node_tex_image_missing()", "Alpha": "node_tex_image_missing().a"}
    interpolation = IMAGE_INTERPOLATIONS.get(props.get("interpolation"))
    extension = IMAGE_EXTENSIONS.get(props.get("extension"))
    projection = props.get("projection", "FLAT")
    if interpolation is None or extension is None or projection not in IMAGE_PROJECTIONS:
        return None
    tiled = props.get("image_source") == "TILED"
    spec = node.inputs.get("Vector")
    co = w.arg(node, "Vector") if spec is not None and isinstance(spec.source, Ref) else "g.uv"
    texels = image_texels(props)
    alpha_read = "Alpha" in _read_outputs(w.whole, node)
    unassociate = "true" if alpha_read and _associates_alpha(props) else "false"
    decode = "true" if texels.startswith("TEX_IMAGE_TEXELS_SRGB") else "false"
    if projection == "BOX":
        image = w.image(tile_key(props["image"], 1001) if tiled else props["image"])
        if image is None:
            w.over_limit(node, 1)
            return None
        normal = "(vec4(g.n, 0.0) * g.object_to_world).xyz"  # object_inverse_normal_transform: M^T n
        blend = w.constant(props.get("projection_blend", 0.0), "VALUE")
        sample = w.once("vec4", f"node_tex_image_box({image}, {co}, {normal}, {blend}, {interpolation}, "
                                f"{extension}, {texels}, {unassociate}, {decode})")
        return {"Color": f"vec4({sample}.rgb, 1.0)", "Alpha": f"{sample}.a"}
    if tiled:
        filtered = _tiled(w, node, co, f"{interpolation}, {extension}, {texels}")
        if filtered is None:
            return None
    else:
        image = w.image(props["image"])
        if image is None:
            w.over_limit(node, 1)
            return None
        filtered = w.once("vec4", f"node_tex_image_{projection.lower()}({image}, {co}, {interpolation}, "
                                  f"{extension}, {texels})")
    color = w.once("vec4", f"tex_image_output({filtered}, {unassociate}, {decode})")
    return {"Color": f"vec4({color}.rgb, 1.0)", "Alpha": f"{color}.a"}


EMITTERS = {
    "ShaderNodeValue": _value,
    "ShaderNodeRGB": _value,
    "ShaderNodeTexCoord": _texcoord,
    "ShaderNodeNewGeometry": _geometry,
    "ShaderNodeWireframe": _wireframe,
    "ShaderNodeFresnel": lambda w, n: {"Fac": f"node_fresnel({w.arg(n, 'IOR')}, {_normal_input(w, n)}, g)"},
    "ShaderNodeLayerWeight": _layer_weight,
    "ShaderNodeUVMap": _uv_map,
    "ShaderNodeTangent": _tangent,
    "ShaderNodeObjectInfo": _object_info,
    "ShaderNodeCameraData": _camera_data,
    "ShaderNodeLightPath": _light_path,
    "ShaderNodeVectorTransform": _vector_transform,
    "ShaderNodeAttribute": _attribute,
    "ShaderNodeVertexColor": _color_attribute,
    "ShaderNodeNormalMap": _normal_map,
    "ShaderNodeBump": _bump,
    "ShaderNodeMath": _math,
    "ShaderNodeMix": _mix,
    "ShaderNodeVectorMath": _vector_math,
    "ShaderNodeClamp": _clamp,
    "ShaderNodeMapRange": _map_range,
    "ShaderNodeSeparateColor": _separate_color,
    "ShaderNodeCombineColor": _combine_color,
    "ShaderNodeInvert": lambda w, n: _call("invert_color", w, n, ("Fac", "Color"), "Color"),
    "ShaderNodeGamma": lambda w, n: _call("gamma_color", w, n, ("Color", "Gamma"), "Color"),
    "ShaderNodeBrightContrast": lambda w, n: _call("brightness_contrast", w, n,
                                                   ("Color", "Bright", "Contrast"), "Color"),
    "ShaderNodeRGBToBW": lambda w, n: {"Val": _luminance(w, w.arg(n, "Color"))},
    "ShaderNodeHueSaturation": lambda w, n: _call("hue_saturation_value", w, n,
                                                  ("Hue", "Saturation", "Value", "Fac", "Color"), "Color"),
    "ShaderNodeSeparateXYZ": _separate_xyz,
    "ShaderNodeCombineXYZ": _combine_xyz,
    "ShaderNodeTexImage": _image_texture,
    "ShaderNodeValToRGB": _ramp,
    "ShaderNodeRGBCurve": _curves,
    "ShaderNodeVectorCurve": _curves,
    "ShaderNodeFloatCurve": _curves,
    "ShaderNodeBlackbody": lambda w, n: _call("node_blackbody", w, n, ("Temperature",), "Color"),
    "ShaderNodeWavelength": _wavelength,
    "ShaderNodeMapping": _mapping,
    "ShaderNodeVectorRotate": _vector_rotate,
    "ShaderNodeNormal": _normal,
    "ShaderNodeMixRGB": _mix_rgb,
    "ShaderNodeSeparateRGB": _separate("RGB", "Image", ("R", "G", "B")),
    "ShaderNodeCombineRGB": _combine("RGB", ("R", "G", "B"), "Image"),
    "ShaderNodeSeparateHSV": _separate("HSV", "Color", ("H", "S", "V")),
    "ShaderNodeCombineHSV": _combine("HSV", ("H", "S", "V"), "Color"),
    CONVERT: _convert,
    **textures.EMITTERS,
    **CLOSURES,
}
#: Nodes that compute nothing themselves: the outputs whose inputs are the targets.
SINKS = ("ShaderNodeOutputAOV", "ShaderNodeOutputMaterial")


#: The socket types a bake holds, and how a baked texel (its RGB; a float in R) is read as each.
_BAKED_READS = {"VALUE": "{t}.r", "INT": "{t}.r", "BOOLEAN": "{t}.r", "VECTOR": "{t}.rgb",
                "RGBA": "vec4({t}.rgb, 1.0)"}


def _baked(w: _Writer, node: FlatNode) -> dict | None:
    """The outputs of ``node`` that Cycles baked (``w.baked``: (node, output) -> image key): the
    bake sampled at the UV map's coordinate as an Image Texture of a float image (Linear,
    Extend: glsl/node_texture_image.glsl), a float from its red channel, a vector or colour from
    its RGB (Cycles' colours have no alpha). None where none of its outputs was baked."""
    outputs = {}
    for socket, type_ in node.outputs.items():
        key = w.baked.get((node.name, socket))
        read = _BAKED_READS.get(type_)
        if key is None or read is None:
            continue
        image = w.image(key)
        if image is None:
            w.over_limit(node, 1)
            continue
        texel = w.once("vec4", f"node_tex_image_flat({image}, g.uv, TEX_IMAGE_LINEAR, TEX_IMAGE_EXTEND, "
                               f"TEX_IMAGE_TEXELS_FLOAT)")
        outputs[socket] = read.format(t=texel)
    return outputs or None


def _emit(w: _Writer, node: FlatNode) -> tuple[dict | None, bool]:
    """A node's outputs as GLSL: its emitter's, else its bakes' (``_baked``); None where neither;
    and whether they are its bakes'."""
    emit = None if node.kind in FORCE_BAKE else EMITTERS.get(node.kind)
    outputs = emit(w, node) if emit is not None else None
    if outputs is not None or not w.baked:
        return outputs, False
    outputs = _baked(w, node)
    return outputs, outputs is not None


def compile_graph(flat: FlatGraph, targets: dict[str, tuple[str, str]], name: str = "graph",
                  whole: FlatGraph | None = None,
                  baked: dict[tuple[str, str], str] | None = None) -> Compiled:
    """The GLSL function ``name`` computing each target (a name -> (flat node, input socket)):
    ``void name(GraphInputs g, out T target ...)`` in the order ``targets`` lists them. ``whole``:
    the material's whole flat graph where ``flat`` is part of it (what a node's outputs feed
    there decides, as Cycles compiles the surface and the AOV Outputs as one graph: an Image
    Texture's Alpha read anywhere unassociates its Color). ``baked``: the outputs of nodes that
    did not compile which Cycles baked, (flat node, output) -> the image's key."""
    w = _Writer(flat, whole)
    w.baked = dict(baked or {})
    for node in flat.nodes.values():
        if node.kind in SINKS:
            continue  # outputs: what reads their inputs is the caller's
        outputs, from_bakes = _emit(w, node)
        if from_bakes:
            w.from_bakes.append(node.name)
        if outputs is None:
            w.missing.append(f"{node.name} ({node.kind})")
            w.missing_nodes.append(node.name)
            if "SHADER" not in node.outputs.values():
                w.silent.append(node.name)
                continue
            outputs = _unknown_closure(w, node)
        w.define(node, outputs)
    types, assigns = {}, []
    for target, (node_name, socket) in targets.items():
        node = flat.nodes[node_name]
        types[target] = GLSL_TYPES.get(node.inputs[socket].type, "float")
        assigns.append(f"  {target} = {w.arg(node, socket)};")
    params = ", ".join(["GraphInputs g", *(f"out {t} {n}" for n, t in types.items())])
    # the tables' reader the library declares (glsl/node_ramp.glsl; the linker wants it defined
    # whether or not the graph reads a table): one compiled graph per program
    prelude = ["vec4 graph_table(int i) { return GRAPH_CONST(i); }", ""]
    source = "\n".join([*prelude, f"void {name}({params})", "{", *w.lines, *assigns, "}", ""])
    constants = np.array(w.constants or [(0.0, 0.0, 0.0, 0.0)], np.float32).reshape(-1, 4)
    return Compiled(name, source, constants, types, w.missing, tuple(w.images), tuple(w.attributes),
                    notes=tuple(w.notes), uniform_attributes=tuple(w.uniform_attributes),
                    bake_targets=_bake_targets(w, targets), baked=tuple(w.from_bakes),
                    missing_nodes=tuple(w.missing_nodes))


def _bake_targets(w: _Writer, targets: dict[str, tuple[str, str]]) -> tuple[tuple[str, str], ...]:
    """The outputs of nodes that did not compile (``w.silent``) read by a target, or by a node that
    compiled and reaches one without passing through a node that did not (a compiled node that
    only feeds those is part of their bake): what a bake could stand in for, in the flat graph's
    order."""
    silent, found = set(w.silent), set()
    pending = [w.flat.nodes[n].inputs[s] for n, s in targets.values()]
    seen: set[str] = set()
    while pending:
        source = pending.pop().source
        if not isinstance(source, Ref) or source.node not in w.flat.nodes:
            continue
        if source.node in silent:
            if source.type in _BAKED_READS:
                found.add((source.node, source.socket))
        elif source.node not in seen:
            seen.add(source.node)
            pending += w.flat.nodes[source.node].inputs.values()
    order = list(w.flat.nodes)
    return tuple(sorted(found, key=lambda t: (order.index(t[0]), t[1])))
