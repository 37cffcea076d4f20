"""Shader node trees read from Blender (blender/nodes.py) and flattened as Blender evaluates them
(materials/graph.py): node groups inlined at any depth and a group used twice, reroutes, muted
nodes and links, unavailable sockets, the output Blender picks, Blender's implicit conversions.

Expected values are Blender's semantics written here from its documentation and behaviour: a
muted node passes on its internal links, a muted link or one into an unavailable socket carries
nothing, a colour read as a float is its luminance, a vector read as a float the mean of
its components, a float read as a colour grey with alpha 1."""

from __future__ import annotations

import bpy
import numpy as np
import pytest
import scenes

from addon.blender import nodes as reader
from addon.materials import convert, graph
from addon.materials.graph import Const, Ref
from addon.scene import nodes as N


def _material(name="M"):
    scenes.reset(size=8)
    mat = bpy.data.materials.new(name)
    tree = scenes.node_tree(mat)
    tree.nodes.clear()
    return mat, tree


def _principled(tree):
    bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return bsdf, out


def _socket(sockets, identifier):
    """A socket by identifier (a bpy collection indexes by name, which Mix's sockets share)."""
    return next(s for s in sockets if s.identifier == identifier)


def _flat(mat):
    g, groups = reader.read_material(mat)
    return graph.flatten(g, groups)


def _input(flat, node, socket):
    return flat.nodes[node].inputs[socket].source


def test_sockets_by_identifier_and_unavailable_ones_left_out():
    mat, tree = _material()
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    node = reader.read_node(mix)
    assert {"Factor_Float", "A_Color", "B_Color"} <= set(node.inputs)
    assert not {"A_Float", "B_Float", "A_Vector"} & set(node.inputs), sorted(node.inputs)
    assert node.outputs == {"Result_Color": "RGBA"}
    assert node.props["data_type"] == "RGBA" and node.props["blend_type"] == "MIX"
    assert "location" not in node.props and "name" not in node.props


def test_a_chain_into_the_principled_bsdf_with_conversions_and_dead_nodes_dropped():
    """Value -> Math (ADD 0.25) -> Base Color (a float read as a colour: grey, alpha 1); an RGB
    node -> Roughness (a colour read as a float: its luminance); a node nothing reads is dropped;
    unlinked inputs keep their values."""
    mat, tree = _material()
    bsdf, out = _principled(tree)
    value = tree.nodes.new("ShaderNodeValue")
    value.outputs[0].default_value = 0.5
    math = tree.nodes.new("ShaderNodeMath")
    math.operation = "ADD"
    math.inputs[1].default_value = 0.25
    rgb = tree.nodes.new("ShaderNodeRGB")
    rgb.outputs[0].default_value = (0.2, 0.4, 0.6, 1.0)
    tree.nodes.new("ShaderNodeMath").name = "Unused"
    tree.links.new(value.outputs[0], math.inputs[0])
    tree.links.new(math.outputs[0], bsdf.inputs["Base Color"])
    tree.links.new(rgb.outputs[0], bsdf.inputs["Roughness"])
    flat = _flat(mat)
    assert flat.output == out.name
    order = list(flat.nodes)
    assert "Unused" not in order and order[-1] == out.name
    assert order.index(value.name) < order.index(math.name) < order.index(bsdf.name)
    base = _input(flat, bsdf.name, "Base Color")
    assert isinstance(base, Ref) and base.type == "RGBA"
    conversion = flat.nodes[base.node]
    assert conversion.kind == graph.CONVERT and conversion.props == {"from": "VALUE", "to": "RGBA"}
    assert conversion.inputs["Value"].source == Ref(math.name, "Value", "VALUE")
    assert _input(flat, math.name, "Value_001") == Const("VALUE", pytest.approx(0.25))
    rough = _input(flat, bsdf.name, "Roughness")
    assert flat.nodes[rough.node].props == {"from": "RGBA", "to": "VALUE"}
    metallic = _input(flat, bsdf.name, "Metallic")
    assert metallic == Const("VALUE", pytest.approx(bsdf.inputs["Metallic"].default_value))


def test_reroutes_muted_nodes_and_muted_links_pass_as_blender_passes_them():
    """RGB -> reroute -> reroute -> a muted Invert (passes its Color input on) -> Base Color; a
    muted link from a Value into Roughness carries nothing (the socket's own value); a link into a
    Math node's unused second input of a one-input operation is not followed."""
    mat, tree = _material()
    bsdf, _ = _principled(tree)
    rgb = tree.nodes.new("ShaderNodeRGB")
    r1, r2 = tree.nodes.new("NodeReroute"), tree.nodes.new("NodeReroute")
    invert = tree.nodes.new("ShaderNodeInvert")
    invert.mute = True
    tree.links.new(rgb.outputs[0], r1.inputs[0])
    tree.links.new(r1.outputs[0], r2.inputs[0])
    tree.links.new(r2.outputs[0], invert.inputs["Color"])
    tree.links.new(invert.outputs[0], bsdf.inputs["Base Color"])
    value = tree.nodes.new("ShaderNodeValue")
    link = tree.links.new(value.outputs[0], bsdf.inputs["Roughness"])
    link.is_muted = True
    sqrt = tree.nodes.new("ShaderNodeMath")
    sqrt.operation = "SQRT"
    tree.links.new(value.outputs[0], sqrt.inputs[1])  # Value_001: unused by SQRT
    tree.links.new(sqrt.outputs[0], bsdf.inputs["Metallic"])
    flat = _flat(mat)
    assert _input(flat, bsdf.name, "Base Color") == Ref(rgb.name, "Color", "RGBA")
    assert invert.name not in flat.nodes and r1.name not in flat.nodes
    roughness = bsdf.inputs["Roughness"].default_value
    assert _input(flat, bsdf.name, "Roughness") == Const("VALUE", pytest.approx(roughness))
    assert "Value_001" not in flat.nodes[sqrt.name].inputs and value.name not in flat.nodes


def test_a_muted_node_passes_what_it_passes_unconverted():
    """A muted Math node fed a colour passes the colour itself to a colour input in Blender 5 (not
    through its own float output, as Blender 4 does: Cycles' AOVs, tests/test_material_nodes.py)."""
    mat, tree = _material()
    bsdf, _ = _principled(tree)
    rgb = tree.nodes.new("ShaderNodeRGB")
    rgb.outputs[0].default_value = (0.2, 0.4, 0.6, 1.0)
    math = tree.nodes.new("ShaderNodeMath")
    math.mute = True
    tree.links.new(rgb.outputs[0], math.inputs[0])
    tree.links.new(math.outputs[0], bsdf.inputs["Base Color"])
    flat = _flat(mat)
    if bpy.app.version >= (5, 0, 0):
        assert _input(flat, bsdf.name, "Base Color") == Ref(rgb.name, "Color", "RGBA")
    else:  # Blender 4 passes it through the muted node's float output: grey
        to_color = flat.nodes[_input(flat, bsdf.name, "Base Color").node]
        assert to_color.props == {"from": "VALUE", "to": "RGBA"}
    assert math.name not in flat.nodes


def _group(name, inner=None):
    """A group: Fac (float, default 0.3) and Color (colour) in; Out = Color x Fac, or through the
    nested group ``inner`` first when given."""
    g = bpy.data.node_groups.new(name, "ShaderNodeTree")
    g.interface.new_socket("Fac", in_out="INPUT", socket_type="NodeSocketFloat").default_value = 0.3
    g.interface.new_socket("Color", in_out="INPUT", socket_type="NodeSocketColor")
    g.interface.new_socket("Out", in_out="OUTPUT", socket_type="NodeSocketColor")
    gin, gout = g.nodes.new("NodeGroupInput"), g.nodes.new("NodeGroupOutput")
    mix = g.nodes.new("ShaderNodeMix")
    mix.data_type, mix.blend_type = "RGBA", "MULTIPLY"
    _socket(mix.inputs, "Factor_Float").default_value = 1.0
    g.links.new(gin.outputs["Color"], _socket(mix.inputs, "A_Color"))
    g.links.new(gin.outputs["Fac"], _socket(mix.inputs, "B_Color"))
    result = _socket(mix.outputs, "Result_Color")
    if inner is not None:
        node = g.nodes.new("ShaderNodeGroup")
        node.node_tree = inner
        g.links.new(result, node.inputs["Color"])
        g.links.new(gin.outputs["Fac"], node.inputs["Fac"])
        result = node.outputs["Out"]
    g.links.new(result, gout.inputs["Out"])
    return g


def test_nested_groups_used_twice_are_inlined_with_their_own_inputs():
    """Outer (containing Inner) used twice: once with Fac linked from a Value node, once with Fac
    left at 0.7 on the group node. Each use is its own set of nodes under its group node's path;
    the Group Inputs give what reaches the group node's sockets; the nested group's Fac is the
    outer's."""
    mat, tree = _material()
    bsdf, _ = _principled(tree)
    inner = _group("Inner")
    outer = _group("Outer", inner)
    a, b = tree.nodes.new("ShaderNodeGroup"), tree.nodes.new("ShaderNodeGroup")
    a.node_tree = b.node_tree = outer
    value = tree.nodes.new("ShaderNodeValue")
    rgb = tree.nodes.new("ShaderNodeRGB")
    tree.links.new(value.outputs[0], a.inputs["Fac"])
    b.inputs["Fac"].default_value = 0.7
    for node in (a, b):
        tree.links.new(rgb.outputs[0], node.inputs["Color"])
    add = tree.nodes.new("ShaderNodeMix")
    add.data_type, add.blend_type = "RGBA", "ADD"
    tree.links.new(a.outputs["Out"], _socket(add.inputs, "A_Color"))
    tree.links.new(b.outputs["Out"], _socket(add.inputs, "B_Color"))
    tree.links.new(_socket(add.outputs, "Result_Color"), bsdf.inputs["Base Color"])
    g, groups = reader.read_material(mat)
    assert set(groups) == {"Outer", "Inner"}
    flat = graph.flatten(g, groups)
    mixes = {name for name, node in flat.nodes.items() if node.kind == "ShaderNodeMix"}
    assert mixes == {add.name, f"{a.name}/Mix", f"{b.name}/Mix", f"{a.name}/Group/Mix", f"{b.name}/Group/Mix"}
    # the outer groups' Mix reads the group node's Color: the RGB node
    assert _input(flat, f"{a.name}/Mix", "A_Color") == Ref(rgb.name, "Color", "RGBA")
    # a's Fac comes from the Value node (float -> colour), b's is the group node's 0.7
    fac_a = _input(flat, f"{a.name}/Mix", "B_Color")
    assert flat.nodes[fac_a.node].inputs["Value"].source == Ref(value.name, "Value", "VALUE")
    assert _input(flat, f"{b.name}/Mix", "B_Color") == Const("RGBA", pytest.approx((0.7, 0.7, 0.7, 1.0)))
    # the nested group reads the outer group's Mix, and its Fac is the outer's
    nested = f"{b.name}/Group/Mix"
    assert _input(flat, nested, "A_Color") == Ref(f"{b.name}/Mix", "Result_Color", "RGBA")
    assert _input(flat, nested, "B_Color") == Const("RGBA", pytest.approx((0.7, 0.7, 0.7, 1.0)))
    assert _input(flat, add.name, "B_Color") == Ref(f"{b.name}/Group/Mix", "Result_Color", "RGBA")


def test_the_active_group_output_and_an_unlinked_group_input_default():
    """Of two Group Outputs the active one gives the group's result; a group input that nothing
    links takes the group node's own socket value."""
    mat, tree = _material()
    bsdf, _ = _principled(tree)
    g = _group("Two outputs")
    second = g.nodes.new("NodeGroupOutput")
    rgb = g.nodes.new("ShaderNodeRGB")
    g.links.new(rgb.outputs[0], second.inputs["Out"])
    second.is_active_output = True
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = g
    tree.links.new(node.outputs["Out"], bsdf.inputs["Base Color"])
    flat = _flat(mat)
    assert _input(flat, bsdf.name, "Base Color") == Ref(f"{node.name}/{rgb.name}", "Color", "RGBA")
    g.nodes["Group Output"].is_active_output = True
    flat = _flat(mat)
    mix = _input(flat, bsdf.name, "Base Color")
    assert mix.node == f"{node.name}/Mix"
    fac = node.inputs["Fac"].default_value
    assert _input(flat, mix.node, "B_Color") == Const("RGBA", pytest.approx((fac, fac, fac, 1.0)))


def test_the_output_blender_picks_for_eevee():
    """An EEVEE-target output is preferred to an All one; a Cycles-only output is not EEVEE's; a
    tree without an output flattens to nothing."""
    mat, tree = _material()
    bsdf, out_all = _principled(tree)
    emission = tree.nodes.new("ShaderNodeEmission")
    out_eevee = tree.nodes.new("ShaderNodeOutputMaterial")
    out_eevee.target = "EEVEE"
    tree.links.new(emission.outputs[0], out_eevee.inputs["Surface"])
    out_all.target = "ALL"
    assert _flat(mat).output == out_eevee.name
    out_eevee.target = "CYCLES"
    assert _flat(mat).output == out_all.name
    assert reader.read_material(mat, "CYCLES")[0].output == out_eevee.name
    tree.nodes.remove(out_all)
    tree.nodes.remove(out_eevee)
    flat = _flat(mat)
    assert flat.output is None and not flat.nodes


def test_a_group_containing_itself_is_cut():
    g = graph.flatten(N.Graph({"G": N.Node("G", N.GROUP, outputs={"Out": "RGBA"}, group="loop"),
                               "O": N.Node("O", N.MATERIAL_OUTPUT,
                                           inputs={"Surface": N.Socket("Surface", "RGBA", None)})},
                              (N.Link("G", "Out", "O", "Surface"),), "O"),
                      {"loop": N.Graph({"G": N.Node("G", N.GROUP, outputs={"Out": "RGBA"}, group="loop"),
                                        "GO": N.Node("GO", N.GROUP_OUTPUT,
                                                     inputs={"Out": N.Socket("Out", "RGBA", (0, 0, 0, 1))},
                                                     active_output=True)},
                                       (N.Link("G", "Out", "GO", "Out"),))})
    assert g.cut == ["G/G"] and g.nodes["O"].inputs["Surface"].source == Const("RGBA", (0.0, 0.0, 0.0, 1.0))


@pytest.mark.parametrize("value,from_type,to_type,want", [
    (0.25, "VALUE", "RGBA", (0.25, 0.25, 0.25, 1.0)),
    (0.25, "VALUE", "VECTOR", (0.25, 0.25, 0.25)),
    ((0.2, 0.4, 0.6, 0.5), "RGBA", "VALUE", 0.2126390 * 0.2 + 0.7151687 * 0.4 + 0.0721923 * 0.6),
    ((0.3, 0.6, 1.5), "VECTOR", "VALUE", 0.8),
    ((0.2, 0.4, 0.6, 0.5), "RGBA", "VECTOR", (0.2, 0.4, 0.6)),
    ((1.0, -2.0, 3.0), "VECTOR", "RGBA", (1.0, -2.0, 3.0, 1.0)),
    (None, "SHADER", "VALUE", 0.0),
])
def test_conversions_of_constants(value, from_type, to_type, want):
    assert convert.value(value, from_type, to_type) == pytest.approx(want)


def test_a_muted_output_with_nothing_passed_reads_zero():
    """A muted node's output that none of its inputs is linked through reads the type's zero."""
    muted = N.Node("M", "ShaderNodeSeparateColor", inputs={"Color": N.Socket("Color", "RGBA", (1, 1, 1, 1))},
                   outputs={"Red": "VALUE", "Green": "VALUE"}, muted=True, passes=(("Color", "Red"),))
    out = N.Node("O", N.MATERIAL_OUTPUT, inputs={s: N.Socket(s, "VALUE", 0.5) for s in "AB"})
    flat = graph.flatten(N.Graph({"M": muted, "O": out}, (N.Link("M", "Green", "O", "A"),
                                                         N.Link("M", "Red", "O", "B")), "O"))
    assert flat.nodes["O"].inputs["A"].source == Const("VALUE", 0.0)
    assert flat.nodes["O"].inputs["B"].source == Const("VALUE", pytest.approx(1.0))  # white's luminance
    assert list(flat.nodes) == ["O"]


def test_graphs_of_one_structure_share_their_source_and_differ_in_constants():
    """Two materials wired alike with other values (a Math node's second value, an RGB colour)
    compile to one GLSL source (one program) and differ only in their constants; a different
    operation is another source; an unknown node is named, and what reads it its socket's value."""
    from addon.materials import codegen

    def build(name, value, color, operation="ADD", unknown=False):
        mat, tree = _material(name) if name == "A" else (bpy.data.materials.new(name), None)
        tree = scenes.node_tree(mat) if tree is None else tree
        tree.nodes.clear()
        bsdf, _ = _principled(tree)
        rgb = tree.nodes.new("ShaderNodeRGB")
        rgb.outputs[0].default_value = color
        math = tree.nodes.new("ShaderNodeMath")
        math.operation = operation
        math.inputs[1].default_value = value
        tree.links.new(rgb.outputs[0], math.inputs[0])
        tree.links.new(math.outputs[0], bsdf.inputs["Roughness"])
        if unknown:
            tex = tree.nodes.new("ShaderNodeTexSky")
            tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
        flat = _flat(mat)
        return codegen.compile_graph(flat, {"roughness": (bsdf.name, "Roughness"),
                                            "base": (bsdf.name, "Base Color")})

    a = build("A", 0.25, (0.2, 0.4, 0.6, 1.0))
    b = build("B", 0.75, (0.9, 0.1, 0.3, 1.0))
    assert a.source == b.source and a.key == b.key
    assert not np.array_equal(a.constants, b.constants)
    c = build("C", 0.25, (0.2, 0.4, 0.6, 1.0), operation="MULTIPLY")
    assert c.key != a.key
    d = build("D", 0.25, (0.2, 0.4, 0.6, 1.0), unknown=True)
    assert d.missing == ["Sky Texture (ShaderNodeTexSky)"], d.missing
    base = bpy.data.materials["D"].node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value
    assert any(np.allclose(row, tuple(base)) for row in d.constants), "Base Color falls back to its socket"
