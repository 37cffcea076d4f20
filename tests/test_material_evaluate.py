"""A graph's values in numpy (addon/materials/evaluate.py: what the Auto term set reads of a
procedural texture feeding a Principled input) against Cycles evaluating the same graph into AOVs:
procedurals at Generated (a texture's unlinked Vector), Object and UV coordinates, through Mapping,
Vector Math, Math, Map Range, Color Ramp, Mix, Separate Color and the implicit conversions.

The points are Cycles' own: its AOVs of Generated, Object and UV at each pixel centre."""

from __future__ import annotations

import numpy as np
import pytest
from test_material_nodes import SIZE, _aov, _plane_scene, cycles_aovs_and_graph

from addon.blender import nodes as reader
from addon.materials import evaluate, graph
from addon.materials.graph import Ref

#: AOV -> (AOV type, the largest difference measured against Cycles)
#: (the twins equal Cycles bit for bit, or to an ulp; Mapping's rotation through float32 sin/cos)
MEASURED = {"noise": ("COLOR", 0.0), "ranged": ("VALUE", 1.4e-6), "ramp": ("COLOR", 6.0e-8),
            "mixed": ("COLOR", 1.5e-8), "math": ("VALUE", 6.0e-8), "white": ("VALUE", 0.0)}


def _graph(scene, tree):
    """The cases, each to an AOV (a Diffuse BSDF at the output: the graph's surface is opaque)."""
    coord = tree.nodes.new("ShaderNodeTexCoord")
    _aov(scene, tree, "generated", coord.outputs["Generated"], "COLOR")
    _aov(scene, tree, "object", coord.outputs["Object"], "COLOR")
    noise = tree.nodes.new("ShaderNodeTexNoise")  # Vector unlinked: Generated
    noise.inputs["Scale"].default_value = 4.0
    _aov(scene, tree, "noise", noise.outputs["Color"], "COLOR")
    mapping = tree.nodes.new("ShaderNodeMapping")
    mapping.inputs["Location"].default_value = (0.3, -0.2, 0.1)
    mapping.inputs["Rotation"].default_value = (0.4, 0.2, -0.7)
    mapping.inputs["Scale"].default_value = (3.0, 2.0, 1.5)
    tree.links.new(coord.outputs["UV"], mapping.inputs["Vector"])
    cells = tree.nodes.new("ShaderNodeTexVoronoi")
    tree.links.new(mapping.outputs["Vector"], cells.inputs["Vector"])
    ranged = tree.nodes.new("ShaderNodeMapRange")
    ranged.inputs["To Min"].default_value, ranged.inputs["To Max"].default_value = 0.2, 0.9
    tree.links.new(cells.outputs["Distance"], ranged.inputs["Value"])
    _aov(scene, tree, "ranged", ranged.outputs["Result"])
    scale = tree.nodes.new("ShaderNodeVectorMath")
    scale.operation, scale.inputs["Scale"].default_value = "SCALE", 4.0
    tree.links.new(coord.outputs["Object"], scale.inputs["Vector"])
    bands = tree.nodes.new("ShaderNodeTexWave")
    tree.links.new(scale.outputs["Vector"], bands.inputs["Vector"])
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (0.9, 0.3, 0.1, 1.0)
    ramp.color_ramp.elements[1].position, ramp.color_ramp.elements[1].color = 0.7, (0.1, 0.4, 0.8, 1.0)
    tree.links.new(bands.outputs["Fac"], ramp.inputs["Fac"])
    _aov(scene, tree, "ramp", ramp.outputs["Color"], "COLOR")
    checker = tree.nodes.new("ShaderNodeTexChecker")
    checker.inputs["Scale"].default_value = 3.0
    gradient = tree.nodes.new("ShaderNodeTexGradient")
    gradient.gradient_type = "SPHERICAL"
    tree.links.new(coord.outputs["Object"], gradient.inputs["Vector"])
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    tree.links.new(checker.outputs["Fac"], mix.inputs["Factor"])
    tree.links.new(gradient.outputs["Color"], mix.inputs["A"])
    mix.inputs["B"].default_value = (0.2, 0.7, 0.3, 1.0)
    _aov(scene, tree, "mixed", mix.outputs["Result"], "COLOR")
    separate = tree.nodes.new("ShaderNodeSeparateColor")
    tree.links.new(noise.outputs["Color"], separate.inputs["Color"])
    math = tree.nodes.new("ShaderNodeMath")
    math.operation = "MULTIPLY_ADD"
    tree.links.new(separate.outputs["Green"], math.inputs[0])
    math.inputs[1].default_value, math.inputs[2].default_value = 1.7, -0.3
    _aov(scene, tree, "math", math.outputs["Value"])
    white = tree.nodes.new("ShaderNodeTexWhiteNoise")
    tree.links.new(scale.outputs["Vector"], white.inputs["Vector"])
    _aov(scene, tree, "white", white.outputs["Value"])


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    scene, mat, tree, _, _ = _plane_scene()
    _graph(scene, tree)
    cycles, _ = cycles_aovs_and_graph(scene, mat, tmp_path_factory.mktemp("evaluate"))
    flat = graph.flatten(*reader.read_material(mat, "ALL"))
    n = SIZE * SIZE

    def aov(name, width):
        found = cycles.get(f"ViewLayer.{name}.X", cycles.get(f"ViewLayer.{name}"))
        return found.reshape(n, -1)[:, :width]

    covered = np.linalg.norm(aov("g_normal", 3), axis=1) > 0.5
    points = evaluate.Points(*(aov(name, 3)[covered].astype(np.float32)
                               for name in ("generated", "object", "uv")))
    out = {}
    for node in flat.nodes.values():
        name = node.props.get("aov_name")
        if node.kind != "ShaderNodeOutputAOV" or name not in MEASURED:
            continue
        socket = "Color" if MEASURED[name][0] == "COLOR" else "Value"
        source = node.inputs[socket].source
        assert isinstance(source, Ref) and evaluate.evaluable(flat, source), name
        values = evaluate.evaluate(flat, source, points)
        width = 3 if socket == "Color" else 1
        ours = np.asarray(values, np.float64).reshape(len(points), -1)[:, :width]
        out[name] = (ours, aov(name, width)[covered])
    return out


@pytest.mark.parametrize("name", MEASURED)
def test_evaluated_graph_matches_cycles(results, name):
    ours, cycles = results[name]
    worst = float(np.abs(ours - cycles).max())
    measured = MEASURED[name][1]
    print(f"{name}: {worst:.3g} (spread {np.ptp(cycles):.3g})")
    assert len(ours) > 0.9 * SIZE * SIZE and np.ptp(cycles) > 0.1, (len(ours), np.ptp(cycles))
    # (a measured 0: a float step of the value allowed)
    assert worst <= 3 * measured + 1e-7, f"{name}: largest difference {worst:.3g} (measured {measured:.2g})"


def test_what_cannot_be_evaluated_is_said():
    """A graph reading a node the evaluator has not (a Magic Texture here), or none that varies
    per point, is not evaluable: its input keeps its socket's value in the prediction."""
    scene, mat, tree, _, _ = _plane_scene()
    magic = tree.nodes.new("ShaderNodeTexMagic")
    value = tree.nodes.new("ShaderNodeValue")
    _aov(scene, tree, "magic", magic.outputs["Fac"])
    _aov(scene, tree, "value", value.outputs["Value"])
    flat = graph.flatten(*reader.read_material(mat, "ALL"))
    sources = {n.props["aov_name"]: n.inputs["Value"].source for n in flat.nodes.values()
               if n.kind == "ShaderNodeOutputAOV" and n.props.get("aov_name") in ("magic", "value")}
    assert not evaluate.evaluable(flat, sources["magic"]) and not evaluate.evaluable(flat, sources["value"])
