"""The Voronoi Texture (glsl/node_tex_voronoi.glsl) against Cycles evaluating the same graphs into
AOVs, and its numpy twin (addon/reference/voronoi.py) against Cycles too.

Coordinates come from the UV by one float product each (Vector Math MULTIPLY, Math MULTIPLY),
written to AOVs as well: both renderers evaluate the same bits, the twin too. Two coordinate
sets: the UV times ~1 (about 6 cells across the image at Scale 5, negative y and W) and times
up to 1e4 (every pixel its own cell, where the float grid is 1/256 of a cell). Cycles' SVM has
room for some ten Voronoi nodes a material: each group of cases is rendered in chunks.

A Voronoi texture jumps at cell borders: where a nudge of the coordinate by one float step
(either way, along any axis) changes the twin's result by more than such a step can move a
continuous output, a last-bit difference in the arithmetic may pick the other cell. Those
pixels are counted apart (each case bounds their number) and the rest compared tightly."""

from __future__ import annotations

import numpy as np
import OpenEXR
import pytest
import scenes
from glsl_harness import evaluate
from test_cycles import _cycles
from test_material_nodes import FRAGMENT_AOVS, SIZE, _aov, _plane_scene
from test_texture_white_noise import _channels, coordinates

from addon.blender import nodes as reader
from addon.materials import codegen, graph
from addon.reference import voronoi

DIMENSIONS = ("1D", "2D", "3D", "4D")
#: Coordinate sets: the vector's scale per axis (z: 0.37 times it) and W's scale (W: v times it).
COORDINATES = {"unit": ((1.3, -1.1, 1.0), -0.9), "large": ((7919.0, -6007.3, 1.0e4), -9973.1)}
#: The node's values the cases set (socket -> value); the rest keep Blender's defaults (Scale 5,
#: Detail 0, Roughness 0.5, Lacunarity 2, Smoothness 1, Exponent 0.5, Randomness 1).
DEFAULTS = {"Scale": 5.0, "Detail": 0.0, "Roughness": 0.5, "Lacunarity": 2.0, "Smoothness": 1.0,
            "Exponent": 0.5, "Randomness": 1.0}
#: Features whose result does not depend on the metric (and 1D: |b - a| whatever the metric).
METRIC_FREE = ("DISTANCE_TO_EDGE", "N_SPHERE_RADIUS")
CHUNK = 10  # Voronoi nodes per Cycles render (its SVM stack holds about ten with their AOVs)


def _case(dims, feature, metric="EUCLIDEAN", coords="unit", normalize=False, **values):
    """A Voronoi node's settings, coordinates and values."""
    return {"dims": dims, "feature": feature, "metric": metric, "coords": coords, "normalize": normalize,
            "values": values}


def _metric_free(dims, feature):
    return dims == "1D" or feature in METRIC_FREE


#: Every feature x metric x dimension at Blender's defaults; where the metric changes nothing
#: (1D, Distance to Edge, N-Sphere Radius), a metric other than Euclidean (the engine compiles
#: the same source for every metric there: test_metric_free_variants_compile_one_source).
BASE = {f"{d}_{f}_{m}".lower(): _case(d, f, m) for d in DIMENSIONS for f in voronoi.FEATURES
        for m in voronoi.METRICS if not _metric_free(d, f) or m == "CHEBYCHEV"}
BASE.update({f"{d}_f1_minkowski_exponent_3".lower(): _case(d, "F1", "MINKOWSKI", Exponent=3.0)
             for d in ("2D", "3D", "4D")})
#: |x| to 1e4 (5e4 at Scale 5): each feature and dimension, and F1 by every metric.
LARGE = {f"large_{d}_{f}".lower(): _case(d, f, coords="large") for d in DIMENSIONS for f in voronoi.FEATURES}
LARGE.update({f"large_3d_f1_{m}".lower(): _case("3D", "F1", m, coords="large") for m in voronoi.METRICS[1:3]})
LARGE["large_3d_f1_minkowski"] = _case("3D", "F1", "MINKOWSKI", coords="large", Exponent=1.5)
#: Detail > 0 (the fractal Voronoi) for each feature that has it, every dimension: 2.5 octaves
#: (the last one blended by the fraction), Roughness 0.6, Lacunarity 2.3, Normalize in 2D and 4D;
#: then whole octaves, Roughness 0 (one octave), other metrics and Smoothness, large coordinates.
FRACTAL = {f"fractal_{d}_{f}".lower(): _case(d, f, normalize=d in ("2D", "4D"), Detail=2.5, Roughness=0.6,
                                             Lacunarity=2.3)
           for d in DIMENSIONS for f in voronoi.FEATURES if f != "N_SPHERE_RADIUS"}
FRACTAL.update({
    "fractal_3d_f1_minkowski_whole": _case("3D", "F1", "MINKOWSKI", normalize=True, Detail=2.0, Exponent=1.5),
    "fractal_2d_smooth_chebychev": _case("2D", "SMOOTH_F1", "CHEBYCHEV", Detail=3.0, Smoothness=0.3,
                                         Lacunarity=1.7),
    "fractal_4d_f2_manhattan": _case("4D", "F2", "MANHATTAN", normalize=True, Detail=1.7, Roughness=0.8),
    "fractal_3d_edge_rough0": _case("3D", "DISTANCE_TO_EDGE", normalize=True, Detail=2.0, Roughness=0.0),
    "fractal_large_3d_f1": _case("3D", "F1", coords="large", normalize=True, Detail=2.5, Lacunarity=2.3),
    "fractal_large_2d_edge": _case("2D", "DISTANCE_TO_EDGE", coords="large", Detail=1.5, Roughness=0.7),
})
#: Randomness 0 (every point on its cell's corner; the largest distance Normalize divides by is
#: the least) for each feature in 1D and 3D, F1 in 2D and 4D; out-of-range values clamped;
#: Smoothness 0 (Smooth F1 is F1 then).
RANDOMNESS = {f"random0_{d}_{f}".lower(): _case(d, f, normalize=True, Randomness=0.0)
              for d in ("1D", "3D") for f in voronoi.FEATURES}
RANDOMNESS.update({
    "random0_2d_f1": _case("2D", "F1", normalize=True, Randomness=0.0),
    "random0_4d_f1": _case("4D", "F1", normalize=True, Randomness=0.0),
    "random_0_37_2d_f2": _case("2D", "F2", Randomness=0.37),
    "random_above_1_3d_f1": _case("3D", "F1", normalize=True, Randomness=1.6, Detail=-1.0, Roughness=1.4),
    "random_below_0_2d_smooth": _case("2D", "SMOOTH_F1", Randomness=-0.5, Smoothness=3.0),
    "smoothness0_3d_smooth": _case("3D", "SMOOTH_F1", Smoothness=0.0),
})
GROUPS = {"base": BASE, "large": LARGE, "fractal": FRACTAL, "randomness": RANDOMNESS}


def _outputs(case) -> dict[str, tuple[str, str]]:
    """The node's outputs a case reads, those Blender shows for its feature and dimensions: AOV
    suffix -> (output socket, AOV type)."""
    if case["feature"] == "N_SPHERE_RADIUS":
        return {"d": ("Radius", "VALUE")}
    if case["feature"] == "DISTANCE_TO_EDGE":
        return {"d": ("Distance", "VALUE")}
    out = {"d": ("Distance", "VALUE"), "c": ("Color", "COLOR")}
    if case["dims"] != "1D":  # (Blender hides the outputs a dimension count has not)
        out["p"] = ("Position", "COLOR")
    if case["dims"] in ("1D", "4D"):
        out["w"] = ("W", "VALUE")
    return out


def _scene(cases):
    """A plane whose material evaluates ``cases`` (name -> case) into AOVs, with the coordinates."""
    scene, mat, tree, u, v = _plane_scene()
    sockets = {}
    for label, (scale, w_scale) in COORDINATES.items():
        sockets[label] = coordinates(scene, tree, (u, v), label, scale, w_scale, v)
    for name, case in cases.items():
        node = tree.nodes.new("ShaderNodeTexVoronoi")
        node.name = name
        node.voronoi_dimensions, node.feature, node.distance = case["dims"], case["feature"], case["metric"]
        node.normalize = case["normalize"]
        co, w = sockets[case["coords"]]
        if case["dims"] != "1D":  # (a socket the node hides cannot be found by name)
            tree.links.new(co, node.inputs["Vector"])
        if case["dims"] in ("1D", "4D"):
            tree.links.new(w, node.inputs["W"])
        for socket, value in case["values"].items():
            node.inputs[socket].default_value = value
        for suffix, (output, kind) in _outputs(case).items():
            _aov(scene, tree, f"{name}_{suffix}", node.outputs[output], kind)
    return scene, mat


def _upstream(flat: graph.FlatGraph, names) -> graph.FlatGraph:
    """The part of ``flat`` that computes nodes ``names``: a compiled graph of one Voronoi node."""
    keep, pending = set(), list(names)
    while pending:
        name = pending.pop()
        if name not in keep:
            keep.add(name)
            inputs = flat.nodes[name].inputs.values()
            pending += [i.source.node for i in inputs if isinstance(i.source, graph.Ref)]
    return graph.FlatGraph({k: v for k, v in flat.nodes.items() if k in keep}, flat.output, luma=flat.luma)


def _evaluate_packed(compiled: codegen.Compiled, fragment: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Every target of ``compiled`` at each fragment in one draw: the fragments repeated once per
    vec4 of results (a colour's RGB with a float beside it, or four floats), the copy chosen by
    the row. The constants are read from a texture, as the engine reads them from a buffer: a
    compiler that saw them as literals could fold a Math node's product into the texture's Scale
    product (reassociation GLSL allows), which the engine's program cannot. (N, 1) floats, (N, 3)
    colours."""
    n = len(next(iter(fragment.values())))
    assert len(compiled.constants) <= min(n, 256)  # the first texel row holds them
    source = f"#define GRAPH_CONST(i) texelFetch(in_graph_constants, ivec2(i, 0), 0)\n{compiled.source}"
    floats = [n for n, t in compiled.targets.items() if t == "float"]
    packs = [(n, [floats.pop()] if floats else []) for n, t in compiled.targets.items() if t != "float"]
    packs += [(None, floats[i:i + 4]) for i in range(0, len(floats), 4)]
    slots = [f"vec4({c}.rgb, {(f or ['0.0'])[0]})" if c else f"vec4({', '.join(f + ['0.0'] * (4 - len(f)))})"
             for c, f in packs]
    inputs = {name: np.tile(rows, (len(packs), 1)) for name, rows in fragment.items()}
    inputs["graph_constants"] = np.zeros((n * len(packs), 4), np.float32)
    inputs["graph_constants"][:len(compiled.constants)] = compiled.constants
    inputs["pack"] = np.repeat(np.arange(len(packs), dtype=np.float32), n)[:, None].repeat(4, 1)
    names = list(compiled.targets)
    choice = "".join(f"k == {i} ? {slot} : " for i, slot in enumerate(slots[:-1])) + slots[-1]
    body = ("GraphInputs g; g.uv = vec3(uv.xy, 0.0); g.position = g_position.xyz; g.n = g_normal.xyz; "
            "g.ng = g_normal.xyz; g.i = g_incoming.xyz; g.backfacing = false; "
            + " ".join(f"{compiled.targets[t]} {t};" for t in names)
            + f" {compiled.name}(g, {', '.join(names)}); int k = int(pack.x); result = {choice};")
    values = evaluate(body, inputs, extra=codegen.library(source), source=source).reshape(len(packs), n, 4)
    out = {}
    for i, (color, rest) in enumerate(packs):
        if color:
            out[color] = values[i, :, :3]
        for j, name in enumerate(rest):
            out[name] = values[i, :, 3 if color else j:(3 if color else j) + 1]
    return out


def _render(cases: dict, tmp) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Cycles' AOVs of ``cases`` (and of the coordinates) and ours, each Voronoi node compiled on
    its own: by AOV name, (ours, Cycles') over the covered pixels; the coordinates (Cycles', Cycles')."""
    names = list(cases)
    results = {}
    for start in range(0, len(names), CHUNK):
        chunk = {n: cases[n] for n in names[start:start + CHUNK]}
        scene, mat = _scene(chunk)
        folder = tmp / f"chunk{start}"
        folder.mkdir()
        _cycles(scene, folder / "cycles.exr", samples=1)
        path = scenes.save_result(scene, folder / "aovs.exr", "MULTILAYER")
        with OpenEXR.File(str(path)) as f:
            cycles = {name.removeprefix("ViewLayer.").removesuffix(".X"): np.asarray(ch.pixels, np.float64)
                      for part in f.parts for name, ch in part.channels.items()}
        cycles = {k: v.reshape(SIZE * SIZE, -1) for k, v in cycles.items()}
        fragment = {name: np.concatenate([cycles[name][:, :3], np.zeros((SIZE * SIZE, 1))], 1)
                    for name in FRAGMENT_AOVS}
        covered = np.linalg.norm(fragment["g_normal"][:, :3], axis=1) > 0.5  # the plane, not the world
        g, groups = reader.read_material(mat, "ALL")
        flat = graph.flatten(g, groups)
        aovs = {n.props["aov_name"]: n.name for n in flat.nodes.values() if n.kind == "ShaderNodeOutputAOV"}
        for name, case in chunk.items():
            kinds = _outputs(case)
            targets = {f"r_{name}_{s}": (aovs[f"{name}_{s}"], "Color" if kind == "COLOR" else "Value")
                       for s, (_, kind) in kinds.items()}
            compiled = codegen.compile_graph(_upstream(flat, [t[0] for t in targets.values()]), targets)
            assert not compiled.missing, compiled.missing
            ours = _evaluate_packed(compiled, fragment)
            for target, value in ours.items():
                aov = target[2:]
                results[aov] = (value[covered].astype(np.float64), cycles[aov][covered, :value.shape[1]])
        for label in COORDINATES:
            for key in (f"co_{label}", f"w_{label}"):
                results[key] = (cycles[key][covered, :3], cycles[key][covered, :3])
    return results


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """Each group's results, rendered the first time a test asks for them."""
    done = {}

    def get(name):
        if name not in done:
            done[name] = _render(GROUPS[name], tmp_path_factory.mktemp(f"voronoi_{name}"))
        return done[name]
    return get


def _coordinates(results, case):
    """The coordinates Cycles evaluated (its own AOVs of them): (N, 3) and (N,) float32."""
    co = results[f"co_{case['coords']}"][1].astype(np.float32)
    return co, results[f"w_{case['coords']}"][1][:, 0].astype(np.float32)


def _twin_at(case, co, w) -> dict[str, np.ndarray]:
    """The twin's outputs of ``case`` at ``co``, ``w``, by AOV suffix."""
    values = {**DEFAULTS, **case["values"]}
    out = voronoi.voronoi(int(case["dims"][0]), case["feature"], case["metric"], co, w,
                          **{k.lower(): v for k, v in values.items()}, normalize=case["normalize"],
                          cells=reader.voronoi_cells())
    named = {"d": out["radius" if case["feature"] == "N_SPHERE_RADIUS" else "distance"], "c": out["color"],
             "p": out["position"], "w": out["w"]}
    return {s: named[s].reshape(len(co), -1).astype(np.float64) for s in _outputs(case)}


#: The outputs constant over a cell (F1's and F2's Color and Position, and their octaves' sums;
#: N-Sphere Radius), which jump at its borders; the rest (distances, Smooth F1) are continuous.
def _jumping(case) -> tuple[str, ...]:
    if case["feature"] == "N_SPHERE_RADIUS":
        return ("d",)
    cells = case["feature"] in ("F1", "F2") or case["values"].get("Smoothness") == 0.0  # (Smooth F1 is F1)
    return ("c", "p", "w") if cells else ()


def _twin(results, name) -> dict[str, np.ndarray]:
    """The twin's outputs of case ``name`` at the coordinates Cycles evaluated (kept with the
    results: three tests read them)."""
    key = ("twin", name)
    if key not in results:
        case = _case_of(name)
        results[key] = _twin_at(case, *_coordinates(results, case))
    return results[key]


def _borderline(results, name) -> np.ndarray:
    """Pixels at a cell border: where a nudge of the coordinate by one float step (either way,
    along any axis the dimension count reads) changes the twin's jumping outputs."""
    key = ("border", name)
    if key not in results:
        case = _case_of(name)
        results[key] = _jumps(case, *_coordinates(results, case), _twin(results, name),
                              lambda x, toward: np.nextafter(x, np.float32(toward)))
    return results[key]


def _jumps(case, co, w, here, nudge) -> np.ndarray:
    """Where ``nudge(x, -inf or +inf)`` of a coordinate changes ``here``'s jumping outputs by
    more than the last bits of a value computed from another cell."""
    jumping = [s for s in _jumping(case) if s in _outputs(case)]
    border = np.zeros(len(co), bool)
    axes = {"1D": ("w",), "2D": (0, 1), "3D": (0, 1, 2), "4D": (0, 1, 2, "w")}[case["dims"]]
    for axis in axes if jumping else ():
        for toward in (-np.inf, np.inf):
            c, x = co.copy(), w.copy()
            if axis == "w":
                x = nudge(x, toward)
            else:
                c[:, axis] = nudge(c[:, axis], toward)
            there = _twin_at(case, c, x)
            for s in jumping:
                border |= (np.abs(there[s] - here[s]) > 1e-6 * np.maximum(np.abs(here[s]), 1.0)).any(axis=1)
    return border


def _differences(results, name, values=None) -> dict[str, tuple[float, int, int]]:
    """Per output of case ``name``: the largest |difference| from Cycles off the cell borders,
    the border pixels, and the border pixels whose difference exceeds that (where the two picked
    different cells); ``values``: the twin's outputs instead of the GLSL's."""
    case = _case_of(name)
    border = _borderline(results, name)
    out = {}
    for s in _outputs(case):
        ours, cycles = results[f"{name}_{s}"]
        ours = values[s] if values is not None else ours
        assert np.isfinite(ours).all()
        err = np.abs(ours - cycles).max(axis=1)
        apart = border if s in _jumping(case) else np.zeros(len(err), bool)
        worst = float(err[~apart].max())
        out[s] = (worst, int(apart.sum()), int((err[apart] > worst).sum()))
    return out


CASES = [(g, name) for g, cases in GROUPS.items() for name in cases]


def _case_of(name):
    return next(cases[name] for cases in GROUPS.values() if name in cases)


#: What was measured where not 0 (bit for bit), per case and output: (GLSL vs Cycles, twin vs
#: Cycles), the larger of bpy 5.0.1's and 4.5.15's measurements (each hashes its own cells; they
#: differ by at most 2.2 times). Cycles' x86-64 AVX2 kernel fuses a * b + c (its compiler's
#: contraction); ours computes Cycles' source order unfused, as Cycles' SSE4.2 kernel does: a few
#: float steps in continuous outputs. The twin reproduces Cycles exactly where the same products
#: are fused (1D Smooth F1 with Cycles' mix as one fma: 1089 of 1089 pixels; 2D F1's Euclidean
#: distance with dot = fma(x, x, y * y): 1089 of 1089). Minkowski: pow rounds otherwise than C's
#: powf, on the GPU (llvmpipe) more than in numpy.
MEASURED = {
    "1d_smooth_f1_chebychev": {"d": (3e-8, 3e-8), "c": (3e-8, 3e-8), "w": (6e-8, 6e-8)},
    "2d_f1_euclidean": {"d": (6e-8, 6e-8)},
    "2d_f1_minkowski": {"d": (9.6e-7, 7.2e-7)},
    "2d_f2_euclidean": {"d": (1.2e-7, 1.2e-7)},
    "2d_f2_minkowski": {"d": (1.2e-6, 7.2e-7)},
    "2d_smooth_f1_euclidean": {"d": (1.8e-7, 1.8e-7), "c": (2.7e-7, 2.7e-7), "p": (1.2e-7, 1.2e-7)},
    "2d_smooth_f1_manhattan": {"d": (1.8e-7, 1.8e-7), "c": (3.3e-7, 3.3e-7), "p": (1.2e-7, 1.2e-7)},
    "2d_smooth_f1_chebychev": {"d": (1.2e-7, 1.2e-7), "c": (1.8e-7, 1.8e-7), "p": (1.2e-7, 1.2e-7)},
    "2d_smooth_f1_minkowski": {"d": (9.6e-7, 6e-7), "c": (9.6e-7, 9.6e-7), "p": (3.9e-7, 4.2e-7)},
    "2d_distance_to_edge_chebychev": {"d": (6e-8, 6e-8)},
    "2d_n_sphere_radius_chebychev": {"d": (3e-8, 3e-8)},
    "3d_f1_minkowski": {"d": (2e-6, 9.6e-7)},
    "3d_f2_minkowski": {"d": (2.9e-6, 9.6e-7)},
    "3d_smooth_f1_euclidean": {"d": (1.8e-7, 1.8e-7), "c": (1.8e-7, 1.8e-7), "p": (1.2e-7, 1.2e-7)},
    "3d_smooth_f1_manhattan": {"d": (1.8e-7, 1.8e-7), "c": (2.4e-7, 2.4e-7), "p": (1.2e-7, 1.2e-7)},
    "3d_smooth_f1_chebychev": {"d": (1.8e-7, 1.8e-7), "c": (1.8e-7, 1.8e-7), "p": (1.2e-7, 1.2e-7)},
    "3d_smooth_f1_minkowski": {"d": (1.7e-6, 9.6e-7), "c": (2.4e-6, 1.7e-6), "p": (9.3e-7, 5.7e-7)},
    "4d_f1_minkowski": {"d": (2.9e-6, 1.5e-6)},
    "4d_f2_minkowski": {"d": (3.4e-6, 2.4e-6)},
    "4d_smooth_f1_euclidean": {"d": (1.8e-7, 1.8e-7), "c": (2.4e-7, 2.4e-7), "p": (1.2e-7, 1.2e-7),
                               "w": (1.2e-7, 1.2e-7)},
    "4d_smooth_f1_manhattan": {"d": (3.6e-7, 3.6e-7), "c": (4.5e-7, 4.5e-7), "p": (1.2e-7, 1.2e-7),
                               "w": (1.2e-7, 1.2e-7)},
    "4d_smooth_f1_chebychev": {"d": (1.2e-7, 1.2e-7), "c": (2.4e-7, 2.4e-7), "p": (1.2e-7, 1.2e-7),
                               "w": (1.2e-7, 1.2e-7)},
    "4d_smooth_f1_minkowski": {"d": (2.9e-6, 1.5e-6), "c": (2.6e-6, 1.6e-6), "p": (1.9e-6, 8.4e-7),
                               "w": (1.6e-6, 7.8e-7)},
    "2d_f1_minkowski_exponent_3": {"d": (1.8e-7, 6e-8)},
    "3d_f1_minkowski_exponent_3": {"d": (1.8e-7, 6e-8)},
    "4d_f1_minkowski_exponent_3": {"d": (1.8e-7, 6e-8)},
    "large_1d_smooth_f1": {"d": (3e-8, 3e-8), "c": (6e-8, 6e-8)},
    "large_2d_f1": {"d": (6e-8, 6e-8)},
    "large_2d_f2": {"d": (1.2e-7, 1.2e-7)},
    "large_2d_smooth_f1": {"d": (1.2e-7, 1.2e-7), "c": (2.4e-7, 2.4e-7)},
    "large_2d_distance_to_edge": {"d": (6e-8, 6e-8)},
    "large_2d_n_sphere_radius": {"d": (6e-8, 6e-8)},
    "large_3d_smooth_f1": {"d": (1.2e-7, 1.2e-7), "c": (1.8e-7, 1.8e-7)},
    "large_4d_smooth_f1": {"d": (1.8e-7, 1.8e-7), "c": (2.4e-7, 2.4e-7)},
    "large_3d_f1_minkowski": {"d": (3.6e-7, 2.4e-7)},
    "fractal_1d_f1": {"d": (1.2e-7, 1.2e-7), "c": (2.4e-7, 2.4e-7), "w": (1.2e-7, 1.2e-7)},
    "fractal_1d_f2": {"d": (2.4e-7, 2.4e-7), "c": (1.2e-7, 1.2e-7), "w": (6e-8, 6e-8)},
    "fractal_1d_smooth_f1": {"d": (1.2e-7, 1.2e-7), "c": (2.4e-7, 2.4e-7), "w": (1.2e-7, 1.2e-7)},
    "fractal_1d_distance_to_edge": {"d": (3e-8, 3e-8)},
    "fractal_2d_f1": {"d": (1.2e-7, 1.2e-7), "c": (1.2e-7, 1.2e-7), "p": (2.4e-7, 2.4e-7)},
    "fractal_2d_f2": {"d": (6e-8, 6e-8), "c": (1.2e-7, 1.2e-7), "p": (2.4e-7, 2.4e-7)},
    "fractal_2d_smooth_f1": {"d": (9e-8, 9e-8), "c": (1.5e-7, 1.5e-7), "p": (2.4e-7, 2.4e-7)},
    "fractal_2d_distance_to_edge": {"d": (1.1e-6, 1.1e-6)},
    "fractal_3d_f1": {"d": (2.4e-7, 2.4e-7), "c": (2.4e-7, 2.4e-7), "p": (2.4e-7, 2.4e-7)},
    "fractal_3d_f2": {"d": (2.4e-7, 2.4e-7), "c": (2.4e-7, 2.4e-7), "p": (2.4e-7, 2.4e-7)},
    "fractal_3d_smooth_f1": {"d": (2.4e-7, 2.4e-7), "c": (2.4e-7, 2.4e-7), "p": (2.4e-7, 2.4e-7)},
    "fractal_3d_distance_to_edge": {"d": (3e-8, 3e-8)},
    "fractal_4d_f1": {"d": (6e-8, 6e-8), "c": (1.2e-7, 1.2e-7), "p": (2.4e-7, 2.4e-7), "w": (2.4e-7, 2.4e-7)},
    "fractal_4d_f2": {"d": (3e-8, 3e-8), "c": (1.2e-7, 1.2e-7), "p": (2.4e-7, 2.4e-7), "w": (2.4e-7, 2.4e-7)},
    "fractal_4d_smooth_f1": {"d": (6e-8, 6e-8), "c": (1.2e-7, 1.2e-7), "p": (2.4e-7, 2.4e-7),
                             "w": (1.8e-7, 1.8e-7)},
    "fractal_4d_distance_to_edge": {"d": (6e-8, 6e-8)},
    "fractal_3d_f1_minkowski_whole": {"d": (9e-8, 6e-8)},
    "fractal_2d_smooth_chebychev": {"d": (2.4e-7, 2.4e-7), "c": (3.6e-7, 3.6e-7), "p": (1.2e-7, 1.2e-7)},
    "fractal_4d_f2_manhattan": {"d": (3e-8, 3e-8), "c": (1.2e-7, 1.2e-7), "p": (1.2e-7, 1.2e-7),
                                "w": (1.2e-7, 1.2e-7)},
    "fractal_large_3d_f1": {"p": (0.0015, 0.0015)},
    "fractal_large_2d_edge": {"d": (3.7e-7, 3.7e-7)},
    "random0_1d_smooth_f1": {"d": (6e-8, 6e-8), "c": (6e-8, 6e-8)},
    "random0_3d_smooth_f1": {"d": (1.2e-7, 1.2e-7), "c": (2.4e-7, 2.4e-7), "p": (1.2e-7, 1.2e-7)},
    "random0_2d_f1": {"d": (1.2e-7, 1.2e-7)},
    "random_0_37_2d_f2": {"d": (1.8e-7, 1.8e-7), "p": (6e-8, 6e-8)},
    "random_below_0_2d_smooth": {"d": (1.2e-7, 1.2e-7), "c": (1.8e-7, 1.8e-7), "p": (1.2e-7, 1.2e-7)},
}
#: GLSL vs twin where not 0: only GLSL's pow (Minkowski) rounds otherwise.
POW_MEASURED = {
    "2d_f1_minkowski": {"d": 1.1e-6},
    "2d_f2_minkowski": {"d": 1.5e-6},
    "2d_smooth_f1_minkowski": {"d": 1.1e-6, "c": 1.1e-6, "p": 5.1e-7},
    "3d_f1_minkowski": {"d": 2e-6},
    "3d_f2_minkowski": {"d": 2.9e-6},
    "3d_smooth_f1_minkowski": {"d": 2.2e-6, "c": 2.6e-6, "p": 1.1e-6},
    "4d_f1_minkowski": {"d": 2.9e-6},
    "4d_f2_minkowski": {"d": 3.4e-6},
    "4d_smooth_f1_minkowski": {"d": 2.9e-6, "c": 2.9e-6, "p": 2.3e-6, "w": 1.5e-6},
    "2d_f1_minkowski_exponent_3": {"d": 1.8e-7},
    "3d_f1_minkowski_exponent_3": {"d": 1.8e-7},
    "4d_f1_minkowski_exponent_3": {"d": 2.4e-7},
    "large_3d_f1_minkowski": {"d": 3.6e-7},
    "fractal_3d_f1_minkowski_whole": {"d": 9e-8},
}
#: The pixels at cell borders (where a jumping output changes within one float step of the
#: coordinate), the larger of the two versions' counts: only at |x| to 1e4, with Randomness 0 (F2's
#: ties) and in 4D F2's octaves. Measured in either version: none where the renderers picked
#: different cells.
BORDERS = {
    "large_2d_f1": 8, "large_2d_f2": 20, "large_2d_n_sphere_radius": 4, "large_3d_f1": 9, "large_3d_f2": 26,
    "large_3d_n_sphere_radius": 9, "large_4d_f1": 20, "large_4d_f2": 45, "large_4d_n_sphere_radius": 18,
    "large_3d_f1_manhattan": 12, "large_3d_f1_chebychev": 11, "large_3d_f1_minkowski": 13,
    "fractal_4d_f2_manhattan": 5, "fractal_large_3d_f1": 174, "random0_3d_f2": 11,
}


def _check(name, diffs, measured, what):
    """Each output's largest difference off the borders within 3x what was measured, the border
    pixels within 3x their measured count, and none of them in another cell (measured: none)."""
    for s, (worst, border, flipped) in diffs.items():
        bound = 3 * measured.get(s, 0.0)
        print(f"{what} {name} {s}: {worst:.3g} (bound {bound:.3g}); {border} border pixels, {flipped} apart")
        assert worst <= bound, f"{what} {name} {s}: largest difference {worst:.3g} (measured {bound / 3:.3g})"
        assert border <= 3 * BORDERS.get(name, 0), f"{name} {s}: {border} pixels at cell borders"
        assert flipped == 0, f"{what} {name} {s}: {flipped} of {border} border pixels in another cell"


@pytest.mark.parametrize("group_name,name", CASES)
def test_voronoi_matches_cycles(rendered, group_name, name):
    results = rendered(group_name)
    _check(name, _differences(results, name), {s: m[0] for s, m in MEASURED.get(name, {}).items()}, "GLSL")


@pytest.mark.parametrize("group_name,name", CASES)
def test_voronoi_twin_matches_cycles(rendered, group_name, name):
    """The twin at the coordinates Cycles evaluated."""
    results = rendered(group_name)
    twin = _twin(results, name)
    measured = {s: m[1] for s, m in MEASURED.get(name, {}).items()}
    _check(name, _differences(results, name, twin), measured, "twin")


@pytest.mark.parametrize("group_name,name", CASES)
def test_voronoi_matches_twin(rendered, group_name, name):
    """GLSL and twin compute the same float operations: equal but where GLSL's pow rounds
    otherwise than C's (Minkowski)."""
    results = rendered(group_name)
    twin = _twin(results, name)
    for s, values in twin.items():
        worst = float(np.abs(results[f"{name}_{s}"][0] - values).max())
        measured = POW_MEASURED.get(name, {}).get(s, 0.0)
        print(f"GLSL-twin {name} {s}: {worst:.3g}")
        assert worst <= 3 * measured, f"{name} {s}: GLSL vs twin {worst:.3g} (measured {measured:.3g})"


def _compiled_voronoi(dims, feature, metric) -> str:
    """The source of a graph of one Voronoi node of these settings (its values unlinked)."""
    values = {"Scale": 5.0, "Detail": 0.0, "Randomness": 1.0, "Exponent": 0.5}
    inputs = {s: graph.FlatInput("VALUE", graph.Const("VALUE", v), v) for s, v in values.items()}
    node = graph.FlatNode("Voronoi", "ShaderNodeTexVoronoi", inputs, {"Distance": "VALUE", "Radius": "VALUE"},
                          {"voronoi_dimensions": dims, "feature": feature, "distance": metric})
    flat = graph.FlatGraph({node.name: node})
    output = "Radius" if feature == "N_SPHERE_RADIUS" else "Distance"
    return codegen.compile_graph(flat, {}, whole=flat).source + str(node.outputs) + output


@pytest.mark.parametrize("dims,feature", [("1D", f) for f in voronoi.FEATURES]
                         + [(d, f) for d in DIMENSIONS[1:] for f in METRIC_FREE])
def test_metric_free_variants_compile_one_source(dims, feature):
    """Where the metric changes nothing (1D; Distance to Edge and N-Sphere Radius measure
    Euclidean), every metric compiles to one source: one program, and the GPU comparison of one
    metric (BASE, Chebychev) stands for all four; Cycles' own results are the same for them
    (the twin, which ignores the metric there, matches Cycles for each)."""
    sources = {metric: _compiled_voronoi(dims, feature, metric) for metric in voronoi.METRICS}
    assert len(set(sources.values())) == 1, sources
    assert "node_tex_voronoi_" in sources["EUCLIDEAN"] and "VORONOI_EUCLIDEAN" in sources["CHEBYCHEV"]


def test_metric_chooses_the_source_where_it_counts():
    """A 3D F1 names its metric (a test that cannot fail otherwise: the sources differ)."""
    sources = {_compiled_voronoi("3D", "F1", metric) for metric in voronoi.METRICS}
    assert len(sources) == 4


def test_only_graphs_with_voronoi_compile_its_library():
    """codegen.library: the hash and Voronoi files only for a source calling the texture."""
    assert "node_tex_voronoi.glsl" not in codegen.library("x = node_white_noise_value_3d(co, w);")
    needed = codegen.library("VoronoiTexture t = node_tex_voronoi_f1_3d(co, w, a, b, 0, 0, false);")
    assert needed == codegen.LIBRARY + ("node_hash.glsl", "node_tex_voronoi.glsl")


def test_engine_draws_voronoi_as_cycles(tmp_path):
    """The engine's program holds the Voronoi library where a material's graph calls it: a 3D F1
    Voronoi at Blender's defaults of the plane's Generated coordinates (its Vector unlinked) to
    AOVs; Cycles' AOVs of the same graph. The engine's Generated differs from Cycles' by < 1e-6
    (5e-6 at Scale 5): distances (continuous) within that, colours equal but at the pixels within
    1e-5 of a cell border (the twin at Cycles' Generated, nudged by 1e-5 along each axis, changes
    colour). Measured: distance 1.01e-6; colours: all 1089 equal, no pixel at a border."""
    scene, mat, tree, u, v = _plane_scene()
    node = tree.nodes.new("ShaderNodeTexVoronoi")
    generated = tree.nodes.new("ShaderNodeTexCoord").outputs["Generated"]
    _aov(scene, tree, "distance", node.outputs["Distance"])
    _aov(scene, tree, "color", node.outputs["Color"], "COLOR")
    _aov(scene, tree, "generated", generated, "COLOR")
    scenes.render(scene, tmp_path / "ours_beauty.exr")
    ours = _channels(scenes.save_result(scene, tmp_path / "ours.exr", "MULTILAYER"))
    _cycles(scene, tmp_path / "cycles_beauty.exr", samples=1)
    theirs = _channels(scenes.save_result(scene, tmp_path / "cycles.exr", "MULTILAYER"))
    rows = {k: v.reshape(SIZE * SIZE, -1) for k, v in theirs.items()}
    co = rows["ViewLayer.generated"][:, :3].astype(np.float32)
    w = np.zeros(len(co), np.float32)
    case = _case("3D", "F1")
    steps = {-np.inf: np.float32(-1e-5), np.inf: np.float32(1e-5)}
    border = _jumps(case, co, w, _twin_at(case, co, w), lambda x, toward: x + steps[toward])
    distance = np.abs(ours["ViewLayer.distance.X"] - theirs["ViewLayer.distance.X"]).reshape(-1)
    color_ours = ours["ViewLayer.color"].reshape(SIZE * SIZE, -1)[:, :3]
    differ = (color_ours != rows["ViewLayer.color"][:, :3]).any(axis=1)
    print(f"distance {distance.max():.3g}; colours differ: {int(differ.sum())}; borders: {int(border.sum())}")
    assert len(np.unique(rows["ViewLayer.color"][:, 0])) > 20, "the plane spans cells"
    assert distance.max() < 3e-6, f"distance: largest difference {distance.max():.3g} (measured 1.01e-6)"
    assert not (differ & ~border).any(), f"{int((differ & ~border).sum())} colours differ off the borders"
    assert border.sum() <= 5, f"{int(border.sum())} pixels within 1e-5 of a border (measured 0)"
