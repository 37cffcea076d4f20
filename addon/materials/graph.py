"""A shader node tree flattened as Blender evaluates it (EEVEE's ``ntree_shader_groups_flatten``
and the muted-node and reroute handling before its code generation, learnt from, not copied).

``flatten(graph, groups)`` starts at the graph's output node and follows links backwards. Every
input of a node it reaches becomes a ``Const`` (the socket's value where nothing is linked) or a
``Ref`` to one output of one other node, with Blender's implicit conversion between the two types
(``convert``) where they differ: a constant is converted at once, a node's output through a
``Convert`` node of the flat graph. On the way:

* a **node group** is inlined: its nodes take the group node's name as a path prefix
  (``Group.001/Math``), so a group used twice is two sets of nodes; links into the group node's
  inputs stand for what the group's Group Input nodes give, and the group node's outputs are
  what reaches its *active* Group Output (the first one where none is marked). Groups nest to any
  depth; a group that contains itself is cut (Blender does not allow it);
* a **reroute** passes its input on;
* a **muted node** passes on the inputs Blender links through it (``Node.passes``) as they are,
  converted only to the type of what reads them (Cycles 5 does so: a colour through a muted Math
  node into a colour input stays the colour, measured against its AOVs; Cycles 4 converts it
  through the output's type first, ``Graph.mute_converts``); an output with nothing passed on
  reads a zero;
* nodes the output does not reach are dropped.

The flat graph lists its nodes dependencies first, each once however many inputs read it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..scene.nodes import GROUP, GROUP_INPUT, GROUP_OUTPUT, REROUTE, Graph, Link, Node
from . import convert

#: The kind of the nodes ``flatten`` adds to carry a conversion between two socket types.
CONVERT = "Convert"
#: Separates a node group's name from its nodes' in the flat graph's names.
PATH = "/"


@dataclass(frozen=True)
class Const:
    """A constant of a socket ``type``."""

    type: str
    value: object


@dataclass(frozen=True)
class Ref:
    """Output ``socket`` (an identifier) of flat node ``node``, of socket ``type``."""

    node: str
    socket: str
    type: str


Source = Const | Ref


@dataclass(frozen=True)
class FlatInput:
    """An input as the node reads it: its own socket type, where its value comes from (a ``Ref``
    of the same type: conversions are nodes of their own), and the socket's own value, which it
    falls back to where what is linked to it cannot be compiled."""

    type: str
    source: Source
    default: object = None


@dataclass(frozen=True)
class FlatNode:
    """A node of the flat graph: ``name`` is its path (group nodes' names, then its own)."""

    name: str
    kind: str
    inputs: dict[str, FlatInput]
    outputs: dict[str, str]
    props: dict = field(default_factory=dict)
    values: dict = field(default_factory=dict)  # outputs that hold their value (Value, RGB nodes)


@dataclass
class FlatGraph:
    """The nodes the output reaches, dependencies first, and the output node's name (None: the
    tree has no output in use). ``cut`` names the groups left out because they contain
    themselves (their outputs read zeros)."""

    nodes: dict[str, FlatNode] = field(default_factory=dict)
    output: str | None = None
    cut: list[str] = field(default_factory=list)
    luma: tuple[float, float, float] = convert.LUMA  # a colour's weights read as a float
    version: tuple[int, int] = (5, 0)  # the Blender that read the graph (Graph.version)


@dataclass(frozen=True)
class _Scope:
    """Where a node lives: its tree, the path prefix of its flat name, and for a group's tree the
    scope and the group node it was inlined from."""

    graph: Graph
    prefix: str = ""
    parent: _Scope | None = None
    group_node: Node | None = None
    trees: tuple[str, ...] = ()  # the group trees inlined on the way here (to cut recursion)


class _Flattener:
    def __init__(self, graph: Graph, groups: dict[str, Graph]):
        self.groups = groups
        self.flat = FlatGraph(luma=tuple(graph.luma) if graph.luma is not None else convert.LUMA,
                              version=tuple(graph.version))
        self.links: dict[int, dict[tuple[str, str], Link]] = {}
        self.visiting: set[str] = set()
        self.mute_converts = graph.mute_converts

    def link_into(self, scope: _Scope, node: str, socket: str) -> Link | None:
        table = self.links.get(id(scope.graph))
        if table is None:
            table = {}
            for link in scope.graph.links:
                table.setdefault((link.to_node, link.to_socket), link)  # a multi-input's first link
            self.links[id(scope.graph)] = table
        return table.get((node, socket))

    # -- sources --------------------------------------------------------------------------------

    def input_source(self, scope: _Scope, node: Node, socket: str, raw: bool = False) -> Source:
        """What ``node``'s input ``socket`` reads, converted to the input's type (``raw``: as
        linked, unconverted)."""
        want = node.inputs[socket].type if socket in node.inputs else "VALUE"
        link = self.link_into(scope, node.name, socket)
        if link is None:
            spec = node.inputs.get(socket)
            return Const(want, spec.default if spec is not None else convert.zero(want))
        source = self.output_source(scope, link.from_node, link.from_socket)
        return source if raw else self.converted(source, want)

    def output_source(self, scope: _Scope, name: str, socket: str) -> Source:
        """What output ``socket`` of the node ``name`` in ``scope`` gives."""
        node = scope.graph.nodes.get(name)
        if node is None:
            return Const("VALUE", 0.0)
        out_type = node.outputs.get(socket, "VALUE")
        if node.kind == REROUTE:
            if not node.inputs:
                return Const(out_type, convert.zero(out_type))
            return self.input_source(scope, node, next(iter(node.inputs)))
        if node.muted:
            passed = next((i for i, o in node.passes if o == socket), None)
            if passed is None:
                return Const(out_type, convert.zero(out_type))
            source = self.input_source(scope, node, passed, raw=True)
            return self.converted(source, out_type) if self.mute_converts else source
        if node.kind == GROUP_INPUT:
            if scope.group_node is None:  # a Group Input outside a group
                return Const(out_type, convert.zero(out_type))
            return self.converted(self.input_source(scope.parent, scope.group_node, socket), out_type)
        if node.kind == GROUP:
            return self.converted(self.group_output(scope, node, socket), out_type)
        self.add(scope, node)
        return Ref(scope.prefix + node.name, socket, out_type)

    def group_output(self, scope: _Scope, node: Node, socket: str) -> Source:
        tree = self.groups.get(node.group) if node.group is not None else None
        out_type = node.outputs.get(socket, "VALUE")
        if tree is None:
            return Const(out_type, convert.zero(out_type))
        if node.group in scope.trees:  # Blender refuses a group inside itself; a file can still hold one
            self.flat.cut.append(scope.prefix + node.name)
            return Const(out_type, convert.zero(out_type))
        outputs = [n for n in tree.nodes.values() if n.kind == GROUP_OUTPUT]
        active = next((n for n in outputs if n.active_output), outputs[0] if outputs else None)
        if active is None:
            return Const(out_type, convert.zero(out_type))
        inner = _Scope(tree, scope.prefix + node.name + PATH, scope, node, (*scope.trees, node.group))
        return self.input_source(inner, active, socket)

    def converted(self, source: Source, to_type: str) -> Source:
        """``source`` as a ``to_type`` socket reads it."""
        if source.type == to_type:
            return source
        if isinstance(source, Const):
            return Const(to_type, convert.value(source.value, source.type, to_type, self.flat.luma))
        if not convert.converts(source.type, to_type):
            return Const(to_type, convert.zero(to_type))
        name = f"{source.node}{PATH}{source.socket}>{to_type}"  # one per output and target type
        if name not in self.flat.nodes:
            self.flat.nodes[name] = FlatNode(name, CONVERT, {"Value": FlatInput(source.type, source, None)},
                                             {"Value": to_type}, {"from": source.type, "to": to_type})
        return Ref(name, "Value", to_type)

    # -- nodes --------------------------------------------------------------------------------

    def add(self, scope: _Scope, node: Node) -> None:
        """The node and, first, everything its inputs read."""
        name = scope.prefix + node.name
        if name in self.flat.nodes or name in self.visiting:
            return  # done, or a cycle (Blender marks such links invalid: the reader drops them)
        self.visiting.add(name)
        inputs = {socket: FlatInput(spec.type, self.input_source(scope, node, socket), spec.default)
                  for socket, spec in node.inputs.items()}
        self.visiting.discard(name)
        self.flat.nodes[name] = FlatNode(name, node.kind, inputs, dict(node.outputs), dict(node.props),
                                         dict(node.values))


#: Output nodes a tree evaluates besides its material output: AOV Outputs.
AOV_OUTPUT = "ShaderNodeOutputAOV"


def flatten(graph: Graph, groups: dict[str, Graph] | None = None, aovs: bool = True,
            output: bool = True) -> FlatGraph:
    """``graph`` flattened from its output node (``output``) and its AOV Outputs (``aovs``) (module
    docstring); ``groups`` holds the trees its group nodes name, nested ones too."""
    flattener = _Flattener(graph, groups or {})
    node = graph.nodes.get(graph.output) if graph.output is not None and output else None
    if node is not None:
        flattener.add(_Scope(graph), node)
        flattener.flat.output = node.name
    for node in graph.nodes.values():
        if aovs and node.kind == AOV_OUTPUT and not node.muted:
            flattener.add(_Scope(graph), node)
    return flattener.flat
