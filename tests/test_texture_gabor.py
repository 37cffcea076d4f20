"""The Gabor Texture (glsl/node_tex_gabor.glsl) against Cycles evaluating the same graph into
AOVs, and its numpy twin (addon/reference/gabor.py) against Cycles too.

Each node's (Value, Phase, Intensity) go to one Color AOV (a Combine XYZ: exact). Coordinates:
the UV at z = 0.37, times a constant per axis (one float product: the same bits in both
renderers, written to AOVs for the twin), unit and large (|x| to 1e4, times the node's Scale: to
5e4, where a float's step is 4e-3). Both types, anisotropy 0 (random orientations), 1 (the given
one) and between, several orientations, frequencies and scales, out-of-range values Cycles
clamps. The hashes are exact, so a wrong key or order gives unrelated values; what remains is the
GPU's (and numpy's) sin, cos and exp against C's. The phase is compared as the phasor's angular
error (the circular phase difference times the intensity): where the intensity is near zero the
angle alone is ill-conditioned in any float arithmetic."""

from __future__ import annotations

import math

import bpy
import numpy as np
import pytest
import scenes
from test_cycles import _cycles
from test_material_nodes import SIZE, _against_cycles, _aov, _combine, _plane_scene
from test_texture_white_noise import _channels

from addon.materials import codegen
from addon.reference import gabor

pytestmark = pytest.mark.skipif(not hasattr(bpy.types, "ShaderNodeTexGabor"),
                                reason=f"Blender {bpy.app.version_string} has no Gabor Texture (4.3+)")

#: Coordinate sets: the UV's (u, v, 0.37) scaled per axis (one float product each).
COORDINATES = {"unit": (1.0, 1.0, 1.0), "large": (7919.0, -6007.3, 1.0e4)}
#: Per type, cases: (Scale, Frequency, Anisotropy, Orientation).
CASES = {
    "2D": {
        "isotropic": (5.0, 2.0, 0.0, math.pi / 4),
        "anisotropic": (5.0, 2.0, 1.0, math.pi / 4),
        "steep": (3.3, 7.5, 1.0, -1.3),
        "blend": (4.0, 0.5, 0.5, 2.9),
        "clamped": (6.0, 0.0, 1.7, 0.3),  # frequency floored at 0.001, anisotropy clamped to 1
    },
    "3D": {
        "isotropic": (5.0, 2.0, 0.0, (1.0, 1.0, 0.0)),
        "anisotropic": (5.0, 2.0, 1.0, (1.0, 1.0, 0.0)),
        "tilted": (3.3, 6.0, 1.0, (0.3, -0.8, 0.5)),
        "blend": (4.0, 0.5, 0.4, (-0.2, 0.1, -0.9)),
        "clamped": (2.5, -1.0, -0.5, (0.6, -0.2, 0.4)),  # frequency 0.001, anisotropy 0 (isotropic)
    },
}


#: Orientations along which Cycles' 3D texture is NaN everywhere (a 0 / 0), each with the
#: anisotropy and the orientation whose Cycles output ours must equal there: along +-z (isotropy
#: above 0): azimuth 0, Cycles' own for a direction leaning the least towards +x; zero: the x axis.
DEGENERATE = {
    "along_z": (0.3, (0.0, 0.0, 1.0), (1e-4, 0.0, 1.0)),
    "along_minus_z": (0.0, (0.0, 0.0, -2.0), (1e-4, 0.0, -2.0)),
    "zero": (0.5, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0)),
}


def _gabor_node(tree, gabor_type, co, size, frequency, anisotropy, orientation):
    node = tree.nodes.new("ShaderNodeTexGabor")
    node.gabor_type = gabor_type
    if co is not None:
        tree.links.new(co, node.inputs["Vector"])
    node.inputs["Scale"].default_value = size
    node.inputs["Frequency"].default_value = frequency
    node.inputs["Anisotropy"].default_value = anisotropy
    node.inputs[f"Orientation {gabor_type}"].default_value = orientation
    return _combine(tree, *[node.outputs[name] for name in ("Value", "Phase", "Intensity")])


def _gabor_scene(gabor_type: str):
    scene, mat, tree, u, v = _plane_scene()
    for label, scale in COORDINATES.items():
        co = tree.nodes.new("ShaderNodeVectorMath")
        co.operation = "MULTIPLY"
        tree.links.new(_combine(tree, u, v, 0.37), co.inputs[0])
        co.inputs[1].default_value = scale
        _aov(scene, tree, f"co_{label}", co.outputs["Vector"], "COLOR")
        for case, values in CASES[gabor_type].items():
            _aov(scene, tree, f"{case}_{label}", _gabor_node(tree, gabor_type, co.outputs["Vector"], *values),
                 "COLOR")
        if gabor_type == "3D" and label == "unit":
            for case, (anisotropy, orientation, stand_in) in DEGENERATE.items():
                for name, vector in (("ours", orientation), ("stand_in", stand_in)):
                    out = _gabor_node(tree, "3D", co.outputs["Vector"], 5.0, 2.0, anisotropy, vector)
                    _aov(scene, tree, f"{case}_{name}", out, "COLOR")
    return scene, mat


def _results(scene_and_mat, tmp_path_factory, gabor_type):
    scene, mat = scene_and_mat
    return _against_cycles(scene, mat, tmp_path_factory.mktemp(f"gabor_{gabor_type}"))


@pytest.fixture(scope="module")
def results_2D(tmp_path_factory):  # noqa: N802 (named by the type it holds)
    """{AOV: (ours, Cycles')} of the 2D cases: one Cycles render, one compiled graph."""
    return _results(_gabor_scene("2D"), tmp_path_factory, "2D")


@pytest.fixture(scope="module")
def results_3D(tmp_path_factory):  # noqa: N802
    return _results(_gabor_scene("3D"), tmp_path_factory, "3D")


def _errors(ours: np.ndarray, cycles: np.ndarray) -> tuple[float, float, float]:
    """Largest |difference| of Value and Intensity, and the phasor's angular error: the circular
    phase difference (in turns) times Cycles' intensity."""
    turns = np.abs(ours[:, 1] - cycles[:, 1])
    turns = np.minimum(turns, 1.0 - turns)
    return (float(np.abs(ours[:, 0] - cycles[:, 0]).max()), float(np.abs(ours[:, 2] - cycles[:, 2]).max()),
            float((turns * cycles[:, 2]).max()))


def _check(name, errors, bounds, cycles):
    assert len(cycles) > 0.9 * SIZE * SIZE
    assert np.isfinite(cycles).all(), f"{name}: Cycles' output is not finite"
    # the noise is not constant: values spread over their range (a wrong case would still pass a
    # comparison of two constants)
    assert float(np.ptp(cycles[:, 2])) > 0.1, f"{name}: Cycles' Intensity spans {np.ptp(cycles[:, 2]):.3g}"
    for what, error, bound in zip(("Value", "Intensity", "Phase x Intensity"), errors, bounds):
        assert error < bound, f"{name} {what}: largest difference {error:.3g} (bound {bound:.3g})"


CASE_IDS = [(t, case, label) for t in CASES for case in CASES[t] for label in COORDINATES]


#: Bounds (Value, Intensity, Phase x Intensity) per type, about 3x the largest measured over the
#: type's cases, unit and large coordinates alike (the GPU's sin, cos, exp against C's; numpy's
#: against C's for the twin). Measured, GLSL: 2D 1.8e-7, 3.6e-7, 1.1e-7; 3D 3.0e-7, 5.2e-7,
#: 1.1e-7. Twin: 2D 3.6e-7, 6.9e-7, 1.3e-7; 3D 1.8e-7, 3.3e-7, 9.2e-8.
BOUNDS = {"2D": (5e-7, 1e-6, 3e-7), "3D": (9e-7, 1.5e-6, 3.3e-7)}
TWIN_BOUNDS = {"2D": (1e-6, 2e-6, 4e-7), "3D": (5e-7, 1e-6, 3e-7)}


@pytest.mark.parametrize("gabor_type,case,label", CASE_IDS)
def test_gabor_matches_cycles(request, gabor_type, case, label):
    results = request.getfixturevalue(f"results_{gabor_type}")
    ours, cycles = results[f"{case}_{label}"]
    errors = _errors(ours, cycles)
    print(f"{gabor_type} {case} {label}: " + ", ".join(f"{e:.3g}" for e in errors))
    _check(f"{gabor_type} {case} {label}", errors, BOUNDS[gabor_type], cycles)


@pytest.mark.parametrize("gabor_type,case,label", CASE_IDS)
def test_gabor_twin_matches_cycles(request, gabor_type, case, label):
    """The twin at the coordinates Cycles evaluated (its own AOV of them)."""
    results = request.getfixturevalue(f"results_{gabor_type}")
    co = results[f"co_{label}"][1]
    cycles = results[f"{case}_{label}"][1]
    twin = np.stack(gabor.gabor(gabor_type, co, *CASES[gabor_type][case]), -1)
    errors = _errors(twin, cycles)
    print(f"twin {gabor_type} {case} {label}: " + ", ".join(f"{e:.3g}" for e in errors))
    _check(f"twin {gabor_type} {case} {label}", errors, TWIN_BOUNDS[gabor_type], cycles)


@pytest.mark.parametrize("case", DEGENERATE)
def test_gabor_degenerate_orientations_are_finite(results_3D, case):  # noqa: N803
    """Where Cycles' 3D texture is NaN (its orientation along z with some isotropy, or zero),
    ours and the twin equal Cycles' output at the stand-in orientation (measured: Value 1.8e-7,
    Intensity 4.2e-7, Phase x Intensity 8.8e-8 at most, as the cases above)."""
    anisotropy, orientation, _ = DEGENERATE[case]
    ours, cycles_nan = results_3D[f"{case}_ours"]
    cycles = results_3D[f"{case}_stand_in"][1]
    assert np.isnan(cycles_nan).all(), f"{case}: Cycles' output is no longer NaN: compare with it"
    twin = np.stack(gabor.gabor("3D", results_3D["co_unit"][1], 5.0, 2.0, anisotropy, orientation), -1)
    for name, values, bounds in (("ours", ours, BOUNDS["3D"]), ("twin", twin, TWIN_BOUNDS["3D"])):
        errors = _errors(values, cycles)
        print(f"{case} {name}: " + ", ".join(f"{e:.3g}" for e in errors))
        _check(f"{case} {name}", errors, bounds, cycles)


def test_only_graphs_with_gabor_compile_its_library():
    """codegen.library: the Gabor file (and the hashes it calls) only for a source calling it."""
    assert "node_tex_gabor.glsl" not in codegen.library("x = node_white_noise_value_3d(co, w);")
    needed = codegen.library("vec3 s0 = node_tex_gabor_3d(co, 5.0, 2.0, 1.0, vec3(1.0));")
    assert needed == codegen.LIBRARY + ("node_hash.glsl", "node_tex_gabor.glsl")


def test_engine_draws_gabor_as_cycles(tmp_path):
    """The engine's program holds the Gabor library where a material's graph calls it: both types
    with the Vector unlinked (the object's Generated coordinates, which differ from Cycles' by
    < 1e-6) to AOVs, against Cycles' AOVs of the same graph. The noise is smooth (its slope here
    about 2 pi x frequency x scale / 12 per unit of Generated), so the difference is that
    slope times the coordinates' difference (measured: Value 2.7e-6, Intensity 3.8e-6, Phase x
    Intensity 9.0e-7)."""
    scene, mat, tree, u, v = _plane_scene()
    _aov(scene, tree, "gabor_2d", _gabor_node(tree, "2D", None, 5.0, 2.0, 0.0, 0.3), "COLOR")
    _aov(scene, tree, "gabor_3d", _gabor_node(tree, "3D", None, 4.0, 1.5, 0.5, (0.2, 0.5, 0.8)), "COLOR")
    scenes.render(scene, tmp_path / "ours_beauty.exr")
    ours = _channels(scenes.save_result(scene, tmp_path / "ours.exr", "MULTILAYER"))
    _cycles(scene, tmp_path / "cycles_beauty.exr", samples=1)
    theirs = _channels(scenes.save_result(scene, tmp_path / "cycles.exr", "MULTILAYER"))
    for name in ("gabor_2d", "gabor_3d"):
        a, b = (c[f"ViewLayer.{name}"].reshape(SIZE * SIZE, -1)[:, :3].astype(np.float64)
                for c in (ours, theirs))
        errors = _errors(a, b)
        print(f"engine {name}: " + ", ".join(f"{e:.3g}" for e in errors))
        _check(f"engine {name}", errors, (8e-6, 1.1e-5, 2.7e-6), b)
