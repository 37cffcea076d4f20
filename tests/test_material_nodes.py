"""Compiled node graphs (materials/codegen.py) against Cycles evaluating the same graph into AOVs.

Cycles renders a plane whose graph writes each node's result into an AOV Output (and the plane's
UV into one more); our compiled function is evaluated on the GPU (glsl_harness) at the very UVs
Cycles wrote, so the two differ only by the nodes' own arithmetic. Inputs span the functions'
domains: a = 8 u - 4 and b = 8 v - 4 from the UV, c a constant, on a 33 x 33 grid of pixel
centres (u = 0.5 lands on a = 0)."""

from __future__ import annotations

import bpy
import numpy as np
import pytest
import scenes
from glsl_harness import evaluate
from test_cycles import _cycles

from addon.blender import nodes as reader
from addon.materials import codegen, graph

SIZE = 33


def _socket(sockets, identifier):
    return next(s for s in sockets if s.identifier == identifier)


def _plane_scene():
    scene = scenes.reset(size=SIZE)
    scenes.ortho_camera(scene, scale=2.0)
    bpy.ops.mesh.primitive_plane_add(size=2.0)  # UVs 0..1 across it
    plane = bpy.context.active_object
    mat = bpy.data.materials.new("Graph")
    tree = scenes.node_tree(mat)
    tree.nodes.clear()
    plane.data.materials.append(mat)
    return scene, mat, tree


def _aov(scene, tree, name, socket, kind="VALUE"):
    aov = scene.view_layers[0].aovs.add()
    aov.name, aov.type = name, kind
    node = tree.nodes.new("ShaderNodeOutputAOV")
    node.aov_name = name
    tree.links.new(socket, node.inputs["Color" if kind == "COLOR" else "Value"])
    return node


def _cycles_aovs(scene, tmp_path) -> dict[str, np.ndarray]:
    _cycles(scene, tmp_path / "cycles.exr", samples=1)
    path = scenes.save_result(scene, tmp_path / "aovs.exr", "MULTILAYER")
    import OpenEXR

    out = {}
    with OpenEXR.File(str(path)) as f:
        for part in f.parts:
            for name, channel in part.channels.items():
                out[name] = np.asarray(channel.pixels, np.float64)
    return out


def _ours(compiled: codegen.Compiled, uv: np.ndarray) -> dict[str, np.ndarray]:
    consts = ", ".join(f"vec4({', '.join(repr(float(x)) for x in row)})" for row in compiled.constants)
    source = (f"const vec4 graph_constants[{len(compiled.constants)}] = vec4[]({consts});\n"
              f"#define GRAPH_CONST(i) graph_constants[i]\n{compiled.source}")
    names = list(compiled.targets)
    out = {}
    for start in range(0, len(names), 4):  # four floats a pass
        chunk = names[start:start + 4]
        decls = " ".join(f"{compiled.targets[n]} {n};" for n in names)
        call = f"{compiled.name}(g, {', '.join(names)});"
        body = (f"GraphInputs g; g.uv = vec3(uv.xy, 0.0); {decls} {call} "
                f"result = vec4({', '.join(chunk + ['0.0'] * (4 - len(chunk)))});")
        values = evaluate(body, {"uv": uv}, extra=codegen.LIBRARY, source=source)
        for i, n in enumerate(chunk):
            out[n] = values[:, i].astype(np.float64)
    return out


@pytest.fixture(scope="module")
def math_results(tmp_path_factory):
    """Every Math operation, a = 8u - 4, b = 8v - 4, c = 0.75, against Cycles; and with Clamp."""
    tmp = tmp_path_factory.mktemp("math")
    scene, mat, tree = _plane_scene()
    coord = tree.nodes.new("ShaderNodeTexCoord")
    sep = tree.nodes.new("ShaderNodeSeparateXYZ")
    tree.links.new(coord.outputs["UV"], sep.inputs["Vector"])
    ab = []
    for axis in ("X", "Y"):
        scale = tree.nodes.new("ShaderNodeMath")
        scale.operation = "MULTIPLY_ADD"
        tree.links.new(sep.outputs[axis], scale.inputs[0])
        scale.inputs[1].default_value, scale.inputs[2].default_value = 8.0, -4.0
        ab.append(scale)
    _aov(scene, tree, "uv", coord.outputs["UV"], "COLOR")
    ops = [(op.lower(), op, False, 0.75) for op in codegen.MATH_OPERATIONS]
    ops += [(f"{op.lower()}_clamped", op, True, 0.75) for op in ("ADD", "SINE", "MULTIPLY")]
    ops += [("compare_exact", "COMPARE", False, 0.0), ("smooth_min_zero", "SMOOTH_MIN", False, 0.0),
            ("wrap_empty", "WRAP", False, -4.0)]  # c = 0: equality within FLT_EPSILON; min; a range of 0
    for name, op, clamp, c in ops:
        node = tree.nodes.new("ShaderNodeMath")
        node.operation, node.use_clamp = op, clamp
        tree.links.new(ab[0].outputs[0], node.inputs[0])
        tree.links.new(ab[1].outputs[0], node.inputs[1])
        node.inputs[2].default_value = c
        _aov(scene, tree, name, node.outputs[0])
    cycles = _cycles_aovs(scene, tmp)
    g, groups = reader.read_material(mat, "ALL")
    flat = graph.flatten(g, groups)
    targets = {}
    for node in flat.nodes.values():
        if node.kind == "ShaderNodeOutputAOV" and node.props["aov_name"] != "uv":
            targets["r_" + node.props["aov_name"]] = (node.name, "Value")
    compiled = codegen.compile_graph(flat, targets)
    assert not compiled.missing, compiled.missing
    uv = cycles["ViewLayer.uv"].reshape(-1, cycles["ViewLayer.uv"].shape[-1])[:, :2]
    uv = np.concatenate([uv, np.zeros((len(uv), 2))], axis=1)
    ours = _ours(compiled, uv)
    out = {}
    for name in targets:
        out[name[2:]] = (ours[name], cycles[f"ViewLayer.{name[2:]}.X"].reshape(-1))
    return out


CLAMPED = ("add_clamped", "sine_clamped", "multiply_clamped", "compare_exact", "smooth_min_zero",
           "wrap_empty")


@pytest.mark.parametrize("op", [op.lower() for op in codegen.MATH_OPERATIONS] + list(CLAMPED))
def test_math_node_matches_cycles(math_results, op):
    ours, ref = math_results[op]
    scale = max(float(np.abs(ref).max()), 1.0)
    err = np.abs(ours - ref)
    worst = float(err.max() / scale)
    off = float(np.mean(err > 1e-4 * scale))
    print(f"{op}: largest difference {worst:.2e} of {scale:.3g}, {off:.2%} of the pixels off by > 1e-4")
    assert np.isfinite(ours).all()
    # measured: 0 for most, at most 1.7e-6 (logarithm; exp, sin ... 1e-7 to 1e-6: GPU and C libm)
    assert worst < 5e-6, f"{op}: {worst:.2e} of the range {scale:.3g} (measured <= 1.7e-6)"
