"""The White Noise Texture and the hashes under every procedural texture (glsl/node_hash.glsl,
glsl/node_tex_white_noise.glsl) against Cycles evaluating the same graph into AOVs, and their numpy
twin (addon/reference/hashing.py) against Cycles too.

A hash of the coordinate's bits equals Cycles' only where the coordinates are the same bits and
the arithmetic the same integer arithmetic: any slip gives an unrelated value, so the cases
compare exactly (up to the EXR's float32, which holds both). Coordinates: the UV (0..1) and the
UV scaled to |x| up to 1e4, where the float grid is coarse."""

from __future__ import annotations

import numpy as np
import OpenEXR
import pytest
import scenes
from test_cycles import _cycles
from test_material_nodes import SIZE, _against_cycles, _aov, _combine, _plane_scene

from addon.materials import codegen
from addon.reference import hashing

DIMENSIONS = ("1D", "2D", "3D", "4D")
#: Coordinate sets: the vector's scale per axis and W's scale (each a single float product).
COORDINATES = {"unit": ((1.0, 1.0, 1.0), 1.0), "large": ((7919.0, -6007.3, 1.0e4), -9973.1)}


def coordinates(scene, tree, uv, label, scale, w_scale, w_from):
    """A texture's coordinates from the UV (u, v sockets) by single float products (the same bits
    in Cycles and on the GPU): the vector (u, v, 0.37) times ``scale`` per axis, W ``w_from``
    times ``w_scale``; both written to AOVs (``co_<label>``, ``w_<label>``) for the twins. The
    vector and W sockets."""
    co = tree.nodes.new("ShaderNodeVectorMath")
    co.operation = "MULTIPLY"
    tree.links.new(_combine(tree, *uv, 0.37), co.inputs[0])
    co.inputs[1].default_value = scale
    w = tree.nodes.new("ShaderNodeMath")
    w.operation = "MULTIPLY"
    tree.links.new(w_from, w.inputs[0])
    w.inputs[1].default_value = w_scale
    _aov(scene, tree, f"co_{label}", co.outputs["Vector"], "COLOR")
    _aov(scene, tree, f"w_{label}", w.outputs["Value"])
    return co.outputs["Vector"], w.outputs["Value"]


def texture_node(tree, kind: str, props: dict, values: dict):
    """A node of ``kind`` with its properties and its inputs' values set."""
    node = tree.nodes.new(kind)
    for key, value in props.items():
        setattr(node, key, value)
    for socket, value in values.items():
        node.inputs[socket].default_value = value
    return node


@pytest.fixture(scope="module")
def white_noise_results(tmp_path_factory):
    scene, mat, tree, u, v = _plane_scene()
    for label, (scale, w_scale) in COORDINATES.items():
        co, w = coordinates(scene, tree, (u, v), label, scale, w_scale, u)
        for dims in DIMENSIONS:
            node = tree.nodes.new("ShaderNodeTexWhiteNoise")
            node.noise_dimensions = dims
            if dims != "1D":  # (a socket the node hides cannot be found by name)
                tree.links.new(co, node.inputs["Vector"])
            if dims in ("1D", "4D"):
                tree.links.new(w, node.inputs["W"])
            _aov(scene, tree, f"value_{dims}_{label}", node.outputs["Value"])
            _aov(scene, tree, f"color_{dims}_{label}", node.outputs["Color"], "COLOR")
    return _against_cycles(scene, mat, tmp_path_factory.mktemp("white_noise"))


CASES = [(dims, label) for dims in DIMENSIONS for label in COORDINATES]


@pytest.mark.parametrize("dims,label", CASES)
def test_white_noise_matches_cycles(white_noise_results, dims, label):
    # measured: 0 (bit for bit) for every dimension, coordinate set and output
    for output in ("value", "color"):
        ours, cycles = white_noise_results[f"{output}_{dims}_{label}"]
        worst = float(np.abs(ours - cycles).max())
        assert len(ours) > 0.9 * SIZE * SIZE
        assert worst == 0.0, f"{output} {dims} {label}: largest difference {worst:.3g} (measured 0)"


@pytest.mark.parametrize("dims,label", CASES)
def test_white_noise_twin_matches_cycles(white_noise_results, dims, label):
    """The twin at the coordinates Cycles evaluated (its own AOVs of them)."""
    co = white_noise_results[f"co_{label}"][1].astype(np.float32)
    w = white_noise_results[f"w_{label}"][1][:, 0].astype(np.float32)
    value, color = hashing.white_noise(int(dims[0]), co, w)
    for output, twin in (("value", value[:, None]), ("color", color)):
        cycles = white_noise_results[f"{output}_{dims}_{label}"][1]
        worst = float(np.abs(twin - cycles).max())
        assert worst == 0.0, f"twin {output} {dims} {label}: largest difference {worst:.3g} (measured 0)"


def test_hashes_spread_over_the_unit_interval():
    """The twin's hash of 2^16 consecutive integers: uniform on [0, 1] (mean 1/2, variance 1/12
    within the sampling error of 65,536 draws), none outside it; the integers all distinct
    (measured: 65,536 of 65,536; mean 0.49977, variance 0.083292)."""
    hashes = hashing.hash_uint(np.arange(1 << 16, dtype=np.uint32))
    assert len(np.unique(hashes)) == len(hashes)
    values = hashing.to_unit(hashes)
    assert values.min() >= 0.0 and values.max() <= 1.0
    assert abs(values.mean() - 0.5) < 4 * (1 / 12) ** 0.5 / 256, values.mean()
    assert abs(values.var() - 1 / 12) < 0.004, values.var()


def test_only_graphs_with_procedurals_compile_their_library():
    """codegen.library: the hash and White Noise files only for a source calling them."""
    assert codegen.library("void f() { float x = 1.0; }") == codegen.LIBRARY
    needed = codegen.library("x = node_white_noise_value_3d(co, w);")
    assert needed == codegen.LIBRARY + ("node_hash.glsl", "node_tex_white_noise.glsl")


def _channels(path):
    with OpenEXR.File(str(path)) as f:
        return {name: np.asarray(ch.pixels) for part in f.parts for name, ch in part.channels.items()}


def test_engine_draws_white_noise_as_cycles(tmp_path):
    """The engine's program holds the hash library where a material's graph calls it: White Noise
    of the plane's Generated coordinate in 8 x 8 cells (floor: a cell is the same bits in both
    renderers; no pixel centre near a border), to an AOV; Cycles' AOV of the same graph, whose
    Generated coordinate differs from ours by < 1e-6. Measured: 1089 of 1089 pixels equal."""
    scene, mat, tree, u, v = _plane_scene()
    coord = tree.nodes.new("ShaderNodeTexCoord")
    cells = tree.nodes.new("ShaderNodeVectorMath")
    cells.operation = "SNAP"
    tree.links.new(coord.outputs["Generated"], cells.inputs[0])
    cells.inputs[1].default_value = (0.12, 0.12, 0.12)  # no pixel centre within 5e-3 of a border
    noise = tree.nodes.new("ShaderNodeTexWhiteNoise")
    tree.links.new(cells.outputs["Vector"], noise.inputs["Vector"])
    _aov(scene, tree, "cells", noise.outputs["Value"])
    scenes.render(scene, tmp_path / "ours_beauty.exr")
    ours = _channels(scenes.save_result(scene, tmp_path / "ours.exr", "MULTILAYER"))
    _cycles(scene, tmp_path / "cycles_beauty.exr", samples=1)
    theirs = _channels(scenes.save_result(scene, tmp_path / "cycles.exr", "MULTILAYER"))
    a, b = ours["ViewLayer.cells.X"], theirs["ViewLayer.cells.X"]
    equal = int((a == b).sum())
    assert len(np.unique(b)) == 81, "the plane spans 9 x 9 cells"
    assert equal == a.size, f"{equal} of {a.size} pixels equal (measured all)"
