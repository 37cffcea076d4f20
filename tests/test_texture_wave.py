"""The Wave Texture (glsl/node_tex_wave.glsl) against Cycles evaluating the same graph into AOVs,
and its numpy twin (addon/reference/wave.py) against Cycles too: bands along X, Y, Z and the
diagonal, rings about X, Y, Z and a point, sine, saw and triangle profiles, Phase Offset, and
Distortion by the fBM noise (Detail, Detail Scale, Detail Roughness).

Coordinates as tests/test_texture_noise.py's: the UV through one product, written to AOVs; small
(|x| < 8), large (|x| to 1e4) and huge (|x| to 5e6, phases to 2e8) sets. Without distortion every
operation but the sine is the same float operation in both renderers; the sine is wave_sin (exact
range reduction) against C's sinf, and a distorted wave carries the noise's rounding
(tests/test_texture_noise.py). A saw's jump (its value 0 just past a whole period, 1 before it)
makes a rounding a whole unit of difference: a distorted saw's pixels carried across it are left
out (counted: none measured)."""

from __future__ import annotations

import numpy as np
import pytest
from glsl_harness import evaluate
from test_material_nodes import SIZE, _aov, _plane_scene
from test_texture_noise import COORDINATES, _coordinates, against_cycles_per_aov, assert_engine_matches_cycles

from addon.blender import nodes as reader
from addon.materials import codegen
from addon.reference import wave

#: Cases: type, direction, profile, and the node's inputs beside Vector (Scale 1 but where named).
CASES = {f"{kind.lower()}_{d.lower()}_{p.lower()}": (kind, d, p, {})
         for kind, directions in (("BANDS", wave.BANDS_DIRECTIONS), ("RINGS", wave.RINGS_DIRECTIONS))
         for d in directions for p in wave.PROFILES}
CASES.update({
    "phase": ("BANDS", "X", "SIN", {"Phase Offset": 1.3, "Scale": 2.3}),
    "distorted": ("BANDS", "X", "SIN", {"Distortion": 3.1, "Detail": 2.37, "Detail Scale": 1.7,
                                        "Detail Roughness": 0.61, "Phase Offset": 0.4}),
    "distorted_rings": ("RINGS", "SPHERICAL", "SAW", {"Distortion": 3.1, "Detail": 2.37, "Detail Scale": 1.7,
                                                      "Detail Roughness": 0.61, "Phase Offset": 0.4}),
    "distorted_flat": ("BANDS", "DIAGONAL", "TRI", {"Distortion": -2.3, "Detail": 0.0, "Detail Scale": 0.9}),
})


def _wave_node(tree, kind, direction, profile, values, co):
    node = tree.nodes.new("ShaderNodeTexWave")
    node.wave_type, node.wave_profile = kind, profile
    if kind == "BANDS":
        node.bands_direction = direction
    else:
        node.rings_direction = direction
    values = {"Scale": 1.0, "Distortion": 0.0, **values}
    for socket in node.inputs:
        if socket.name in values:
            socket.default_value = values[socket.name]
    tree.links.new(co, node.inputs["Vector"])
    return node


@pytest.fixture(scope="module", params=list(COORDINATES))
def wave_results(request, tmp_path_factory):
    label = request.param
    scene, mat, tree, u, v = _plane_scene()
    co, _ = _coordinates(tree, u, v, label)
    _aov(scene, tree, "co", co, "COLOR")
    for case, (kind, direction, profile, values) in CASES.items():
        node = _wave_node(tree, kind, direction, profile, values, co)
        _aov(scene, tree, f"fac_{case}", node.outputs["Fac"])
        _aov(scene, tree, f"color_{case}", node.outputs["Color"], "COLOR")
    return label, against_cycles_per_aov(scene, mat, tmp_path_factory.mktemp(f"wave_{label}"))


def _flipped(case, ours, cycles):
    """Pixels of a distorted saw that a rounding carried across its jump: Cycles' value within 1e-4
    of 0 or 1 and ours a whole period off."""
    kind, direction, profile, values = CASES[case]
    if profile != "SAW" or not values.get("Distortion"):
        return np.zeros(len(cycles), bool)
    near = (cycles[:, 0] < 1e-4) | (cycles[:, 0] > 1 - 1e-4)
    return near & (np.abs(ours - cycles)[:, 0] > 0.5)


#: How this Blender's Cycles takes the saw's and triangle's phase over 2 pi (the reader's wave_phase:
#: 4.2 divides, 4.5 and 5.0 multiply by the reciprocal), which the engine and the twin follow. Taken
#: the other way, 4.2's saws were a float step of the phase apart (3.8e-6 on the small set, 3.9e-3 on
#: the large) and unrelated on the huge one (phases to 1e8, a float step of 8).
PHASE_RULE = reader.wave_phase()


def _measured(case, label) -> float:
    """The GPU against Cycles 5.0 (llvmpipe), the largest difference: undistorted saws and
    triangles 0 (the same float operations); sines 6e-8 (wave_sin within 2 ulps of C's sinf);
    Scale 2.3 and distortion carry llvmpipe's fma() as two roundings (3.8e-6 to 1.5e-5 on the
    small set)."""
    kind, direction, profile, values = CASES[case]
    if label == "small" and (values.get("Distortion") or values.get("Scale")):
        return 1.5e-5 if case == "phase" else 3.8e-6
    return 6e-8 if profile == "SIN" else 0.0


@pytest.mark.parametrize("case", CASES)
def test_wave_matches_cycles(wave_results, case):
    label, results = wave_results
    measured = _measured(case, label)
    for output in ("fac", "color"):
        ours, cycles = results[f"{output}_{case}"]
        assert len(ours) > 0.9 * SIZE * SIZE and np.isfinite(ours).all()
        flipped = _flipped(case, ours, cycles)
        worst = float(np.abs(ours - cycles)[~flipped].max())
        print(f"{output} {case} {label}: {worst:.3g} ({int(flipped.sum())} across the jump)")
        assert flipped.sum() <= 0.002 * len(flipped), f"{case} {label}: {int(flipped.sum())} across the jump"
        assert worst <= 3 * measured, (f"{output} {case} {label}: largest difference {worst:.3g} "
                                       f"(measured {measured:.2g})")


@pytest.mark.parametrize("case", CASES)
def test_wave_twin_matches_cycles(wave_results, case):
    """The twin at the coordinates Cycles evaluated: bit for bit but for the sine (the twin's is
    correctly rounded; Cycles' sinf is an ulp off at 0.5 % of the points: measured 6e-8 at most)."""
    label, results = wave_results
    kind, direction, profile, values = CASES[case]
    co = results["co"][1].astype(np.float32)
    args = {k.lower().replace(" ", "_"): x for k, x in {"Scale": 1.0, **values}.items()}
    fac = wave.wave(co, kind=kind, direction=direction, profile=profile, **args, phase_rule=PHASE_RULE)
    cycles = results[f"fac_{case}"][1][:, 0]
    worst = float(np.abs(fac - cycles).max())
    bound = 6e-8 if profile == "SIN" else 0.0
    assert worst <= 3 * bound, f"twin {case} {label}: largest difference {worst:.3g} (measured {bound:.3g})"


def test_engine_draws_wave_as_cycles(tmp_path):
    """The engine's program holds the wave library where a material's graph calls it: the Wave
    Texture as a file has it by default (bands along X, sine, Scale 5) and spherical rings
    distorted by the fBM noise (Distortion 4, Detail 2.5), their Vector unlinked; Cycles' AOVs of
    the same graph. The engine's Generated coordinate differs from Cycles' by < 1e-6 (x 5 x 20
    along the phase). Measured: 7.6e-6, 1.5e-5 at most."""
    rings = {"wave_type": "RINGS", "rings_direction": "SPHERICAL"}
    assert_engine_matches_cycles(tmp_path, "ShaderNodeTexWave", {
        "bands": ({}, {}, "Fac", 7.6e-6),
        "rings": (rings, {"Distortion": 4.0, "Detail": 2.5}, "Fac", 1.5e-5)}, spread=0.9)


def test_wave_compiles_the_noise_it_calls():
    """codegen.library: a graph calling the Wave Texture alone compiles the hash and noise files it
    calls, in order; one calling the Noise Texture not the wave's."""
    wave_call = "x = node_tex_wave(co, 1.0, 0.0, 2.0, 1.0, 0.5, 0.0, WAVE_BANDS, WAVE_X, WAVE_SIN, 0);"
    noise_call = "x = node_noise_value(p, 3, NOISE_FBM, 2.0, 0.5, 2.0, 0.0, 1.0, 1.0);"
    noise_files = ("node_hash.glsl", "node_tex_noise.glsl")
    # (4.2's division by 2 pi calls node_float.glsl's float_fma)
    assert codegen.library(wave_call) == codegen.LIBRARY + ("node_hash.glsl", "node_float.glsl",
                                                            "node_tex_noise.glsl", "node_tex_wave.glsl")
    assert codegen.library(noise_call) == codegen.LIBRARY + noise_files


def test_divide_by_two_pi_rounds_once():
    """Blender 4.2's phase over 2 pi (node_tex_wave.glsl's wave_divide_two_pi, a corrected product with
    the reciprocal) against numpy's float32 division, correctly rounded as 4.2's Cycles divides, phases
    from 1e-30 to 3e38 of either sign: every quotient equal up to |n| 1e34 (beyond 2^115 float_fma's
    split overflows and it rounds twice: 64 of the 8192 quotients, from 5.4e35, an ulp off), the saw
    of each (n / 2 pi less its floor: 0 for every float beyond 2^23) equal everywhere; and the
    reciprocal's product not the quotient at many (counted: the test tells the two apart)."""
    rng = np.random.default_rng(5)
    magnitude = np.exp(rng.uniform(np.log(1e-30), np.log(3e38), 8192))
    n = (magnitude * rng.choice([-1.0, 1.0], 8192)).astype(np.float32)
    n[:4] = (0.0, 1.0, 6.2831855, 1e8)
    gpu = evaluate("result = vec4(wave_divide_two_pi(a.x), 0.0, 0.0, 0.0);",
                   {"a": np.stack([n, 0 * n, 0 * n, 0 * n], -1)}, extra=codegen.library("node_tex_wave();"),
                   source="vec4 graph_table(int i) { return vec4(0.0); }")[:, 0]
    divided = n / np.float32(2 * np.pi)
    apart = int((n * (np.float32(1) / np.float32(2 * np.pi)) != divided).sum())
    wrong = int((gpu != divided)[np.abs(n) < 1e34].sum())
    saws = int(((gpu - np.floor(gpu)) != (divided - np.floor(divided))).sum())
    print(f"divided by 2 pi: {wrong} of {int((np.abs(n) < 1e34).sum())} quotients off, {saws} saws; the "
          f"reciprocal's product off at {apart}")
    assert wrong == 0 and saws == 0 and apart > 100, (wrong, saws, apart)
