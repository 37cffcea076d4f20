"""A shader node tree as plain data: what ``blender.nodes`` reads from a material's node tree and
the material compiler (``materials``) works from, with no ``bpy`` past the reading.

Sockets are named by their *identifier* (``A_Color``, ``Socket_2``), never by index or label:
Blender renames and reorders sockets between versions and gives several of one name to nodes such
as Mix. Socket types are Blender's ``NodeSocket.type`` strings: ``VALUE`` (float), ``INT``,
``BOOLEAN``, ``VECTOR``, ``RGBA`` (colour), ``SHADER``, ``ROTATION``, ``STRING``, ``MENU`` ...

A group node names the group's tree (``Node.group``, a key of the reader's ``groups``); the
material compiler inlines it (``materials.graph.flatten``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

#: Node kinds (``bl_idname``) with a meaning of their own to the flattening.
GROUP = "ShaderNodeGroup"
GROUP_INPUT = "NodeGroupInput"
GROUP_OUTPUT = "NodeGroupOutput"
REROUTE = "NodeReroute"
MATERIAL_OUTPUT = "ShaderNodeOutputMaterial"

#: Ramps and curves are read as Cycles bakes them (its RAMP_TABLE_SIZE): a table of
#: RAMP_TABLE_SIZE + 1 entries at i / RAMP_TABLE_SIZE of their range (``Node.props["table"]``).
RAMP_TABLE_SIZE = 256


@dataclass(frozen=True)
class Socket:
    """An input socket: its type and the value it holds where nothing is linked to it (a float,
    or a tuple of 3 (vector) or 4 (colour) floats; None for types without a value: shaders)."""

    identifier: str
    type: str
    default: float | tuple | None = None


@dataclass(frozen=True)
class Link:
    """A link from an output socket to an input socket, both by node name and identifier."""

    from_node: str
    from_socket: str
    to_node: str
    to_socket: str


@dataclass(frozen=True)
class Node:
    """A node: its kind (``bl_idname``), the settings that choose what it computes (``props``:
    operation, data type, blend mode ... as Blender's enum identifiers, bools, numbers), its
    available inputs and outputs (identifier -> ``Socket`` / type), whether it is muted and, if
    so, which input each output passes on (Blender's ``internal_links``), and for a group node
    the key of its tree (``group``); for a Group Output, whether it is the active one."""

    name: str
    kind: str
    inputs: dict[str, Socket] = field(default_factory=dict)
    outputs: dict[str, str] = field(default_factory=dict)
    props: dict = field(default_factory=dict)
    muted: bool = False
    passes: tuple[tuple[str, str], ...] = ()  # (input, output) identifiers a muted node passes on
    group: str | None = None
    active_output: bool = False
    values: dict = field(default_factory=dict)  # outputs that hold a value: a Value or RGB node's


@dataclass(frozen=True)
class Graph:
    """A node tree: its nodes by name, its links (only those Blender evaluates: not muted, valid,
    between available sockets), and the name of the output node in use (the material's active
    Material Output for the chosen target; None in a group's tree or without one)."""

    nodes: dict[str, Node]
    links: tuple[Link, ...]
    output: str | None = None
    luma: tuple[float, float, float] | None = None  # colour -> float weights (None: convert.LUMA)
    mute_converts: bool = False  # a muted node's input converted to its output's type (Blender 4)
    #: the Blender that read it (major, minor): where Cycles' rules changed between versions (a bent
    #: normal's light, ``materials.surface.bump_shadowing``), its Cycles' rule is followed
    version: tuple[int, int] = (5, 0)
