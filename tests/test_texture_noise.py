"""The Noise Texture (glsl/node_tex_noise.glsl) against Cycles evaluating the same graph into AOVs,
and its numpy twin (addon/reference/noise.py) against Cycles too: 1D to 4D, every type (fBM,
Multifractal, Hybrid and Ridged Multifractal, Hetero Terrain: an old file's Musgrave Texture
arrives as one of the last four), fractional Detail, Detail beyond the clamp, Roughness,
Lacunarity, Offset, Gain, Distortion, Normalize, the Fac and Color outputs.

The node's coordinates come from the UV through one product (Vector Math MULTIPLY, W a Math
MULTIPLY: the same bits in both renderers), written to AOVs so that the twin evaluates at exactly
Cycles' coordinates. Three coordinate sets: small (|x| < 8, about 50 lattice cells across the
plane), large (|x| to 1e4, where the float grid is 1e-3 coarse) and huge (|x| to 5e6: the noise's
wrap every 1e5 and its half-cell shift beyond 1e6). The twin is Cycles' to the bit (it fuses the
products Cycles' CPU kernel fuses); the GPU (Mesa's llvmpipe, whose fma() rounds twice) differs
by float rounding, bounds within 3x of what was measured."""

from __future__ import annotations

import subprocess
from pathlib import Path

import bpy
import numpy as np
import pytest
import scenes
from glsl_harness import evaluate
from test_cycles import _cycles
from test_material_nodes import FRAGMENT_AOVS, SIZE, _aov, _combine, _plane_scene, cycles_aovs_and_graph
from test_texture_white_noise import _channels, texture_node

from addon.blender import nodes as reader
from addon.materials import codegen, graph
from addon.reference import noise
from addon.scene.snapshot import ImageData

DIMENSIONS = ("1D", "2D", "3D", "4D")
#: Coordinate sets: the vector's scale per axis and W's scale (each a single float product).
COORDINATES = {"small": ((7.3, -5.1, 3.7), 6.1), "large": ((7919.0, -6007.3, 1.0e4), -9973.1),
               "huge": ((3.1e6, -2.3e6, 4.1e6), -5.3e6)}
#: Cases: type and the node's inputs beside its coordinates; Scale 1 but where named (Cycles and
#: ours multiply the coordinates by it alike).
FRACTAL = {"Detail": 2.37, "Roughness": 0.62, "Lacunarity": 2.3}
CASES = {
    "perlin": ("FBM", {"Detail": 0.0}, False),
    "fbm": ("FBM", FRACTAL, True),
    "fbm_raw": ("FBM", {"Detail": 3.0, "Roughness": 0.5, "Lacunarity": 2.0, "Scale": 1.7}, False),
    "multifractal": ("MULTIFRACTAL", FRACTAL, False),
    "hybrid": ("HYBRID_MULTIFRACTAL", {**FRACTAL, "Offset": 0.3, "Gain": 1.7}, False),
    "ridged": ("RIDGED_MULTIFRACTAL", {**FRACTAL, "Offset": 0.9, "Gain": 1.3}, False),
    "hetero": ("HETERO_TERRAIN", {**FRACTAL, "Offset": 0.6}, False),
    "distorted": ("FBM", {"Detail": 1.0, "Distortion": 0.7}, True),
    "clamped": ("FBM", {"Detail": 17.5, "Roughness": 1.3, "Lacunarity": 1.9}, True),  # -> 15, 1.3
}


#: AOVs evaluated by one program: a shader compiler's time grows faster than the program's size.
CHUNK = 8


def against_cycles_per_aov(scene, mat, tmp) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """As test_material_nodes._against_cycles: every AOV but the fragment's, (ours, Cycles') by
    name, (N, 1) or (N, 3). But the AOVs are compiled CHUNK at a time (the nodes they read) into
    one program each, evaluated once over every pixel of every AOV of the chunk (one shader compile
    per chunk; a compile per four AOVs of the whole graph, as _against_cycles does, inlines every
    node before the unread ones are dropped: hours for dozens of noise nodes on llvmpipe). The
    constants are read at run time, as the engine reads its uniform block (compiled in, a shader
    compiler may reassociate float arithmetic with them). The same graph structure of other values
    is the same program (Blender's shader cache)."""
    cycles, _ = cycles_aovs_and_graph(scene, mat, tmp)
    g, groups = reader.read_material(mat, "ALL")
    flat = graph.flatten(g, groups)
    aovs = scene.view_layers[0].aovs
    targets = [(node.props["aov_name"], node.name) for node in flat.nodes.values()
               if node.kind == "ShaderNodeOutputAOV" and node.props.get("aov_name") not in FRAGMENT_AOVS]
    n = SIZE * SIZE
    fragment = {}
    for name in FRAGMENT_AOVS:
        rows = cycles[f"ViewLayer.{name}"].reshape(n, -1)[:, :3]
        fragment[name] = np.concatenate([rows, np.zeros((n, 1))], axis=1)
    covered = np.linalg.norm(fragment["g_normal"][:, :3], axis=1) > 0.5  # the surface, not the world
    out = {}
    for first in range(0, len(targets), CHUNK):
        chunk = targets[first:first + CHUNK]
        needed = {m for _, node_name in chunk for m in codegen.upstream(flat, node_name)}
        sub = graph.FlatGraph(nodes={m: node for m, node in flat.nodes.items() if m in needed})
        sockets = {f"r{j}": (node_name, "Color" if aovs[name].type == "COLOR" else "Value")
                   for j, (name, node_name) in enumerate(chunk)}
        compiled = codegen.compile_graph(sub, sockets)
        assert not compiled.missing, compiled.missing
        cases = " ".join(f"case {j}: result = vec4(vec3(r{j}), 0.0); break;" for j in range(len(chunk)))
        body = ("GraphInputs g; g.uv = vec3(uv.xy, 0.0); g.position = g_position.xyz; g.n = g_normal.xyz; "
                "g.ng = g_normal.xyz; g.i = g_incoming.xyz; g.backfacing = false; "
                f"{' '.join(f'{t} r{j};' for j, t in enumerate(compiled.targets.values()))} "
                f"{compiled.name}(g, {', '.join(compiled.targets)}); switch (int(aov.x)) {{ {cases} }}")
        source = ("#define GRAPH_CONST(i) texelFetch(graph_constants, ivec2(i, 0), 0)\n" + compiled.source)
        inputs = {name: np.tile(rows, (len(chunk), 1)) for name, rows in fragment.items()}
        index = np.repeat(np.arange(len(chunk), dtype=np.float32), n)
        inputs["aov"] = np.stack([index, 0 * index, 0 * index, 0 * index], axis=1)
        table = ImageData("graph_constants", np.asarray(compiled.constants, np.float32).reshape(1, -1, 4))
        values = evaluate(body, inputs, extra=codegen.library(source), source=source,
                          samplers={"graph_constants": table}).astype(np.float64)
        for j, (name, _) in enumerate(chunk):
            ref = cycles.get(f"ViewLayer.{name}.X", cycles.get(f"ViewLayer.{name}")).reshape(n, -1)
            width = 3 if aovs[name].type == "COLOR" else 1
            out[name] = (values[j * n:(j + 1) * n, :width][covered], ref[covered, :width])
    return out


def _coordinates(tree, u, v, label):
    scale, w_scale = COORDINATES[label]
    co = tree.nodes.new("ShaderNodeVectorMath")
    co.operation = "MULTIPLY"
    tree.links.new(_combine(tree, u, v, 0.37), co.inputs[0])
    co.inputs[1].default_value = scale
    w = tree.nodes.new("ShaderNodeMath")
    w.operation = "MULTIPLY"
    tree.links.new(u, w.inputs[0])
    w.inputs[1].default_value = w_scale
    return co.outputs["Vector"], w.outputs["Value"]


def _noise_node(tree, dims, kind, values, normalize, co, w):
    node = tree.nodes.new("ShaderNodeTexNoise")
    node.noise_dimensions, node.noise_type, node.normalize = dims, kind, normalize
    values = {"Scale": 1.0, **values}
    for socket in node.inputs:  # (a socket the node hides cannot be found by name)
        if socket.name in values:
            socket.default_value = values[socket.name]
    if dims != "1D":
        tree.links.new(co, node.inputs["Vector"])
    if dims in ("1D", "4D"):
        tree.links.new(w, node.inputs["W"])
    return node


@pytest.fixture(scope="module", params=list(COORDINATES))
def noise_results(request, tmp_path_factory):
    """One Cycles render per coordinate set (a graph of every case would outgrow Cycles' SVM
    stack): ours and Cycles' AOVs by name, and the label."""
    label = request.param
    scene, mat, tree, u, v = _plane_scene()
    co, w = _coordinates(tree, u, v, label)
    _aov(scene, tree, "co", co, "COLOR")
    _aov(scene, tree, "w", w)
    for dims in DIMENSIONS:
        for case, (kind, values, normalize) in CASES.items():
            node = _noise_node(tree, dims, kind, values, normalize, co, w)
            _aov(scene, tree, f"fac_{case}_{dims}", node.outputs["Fac"])
            _aov(scene, tree, f"color_{case}_{dims}", node.outputs["Color"], "COLOR")
    return label, against_cycles_per_aov(scene, mat, tmp_path_factory.mktemp(f"noise_{label}"))


#: The GPU (llvmpipe: fma() rounds twice) against Cycles 5.0: the largest difference per case over
#: the dimensions and outputs, per coordinate set (small, large, huge). A distorted noise moves its
#: coordinates by the noise's own rounding: at |x| = 1e4 that is a float step of the coordinate
#: (1e-3) where the sum rounds the other way.
MEASURED = {
    "perlin": (8.3e-07, 1.2e-06, 1.4e-07),
    "fbm": (2.4e-07, 2.7e-07, 1.2e-07),
    "fbm_raw": (8.9e-07, 1.4e-06, 1.2e-07),
    "multifractal": (1.4e-06, 1.3e-06, 3.6e-07),
    "hybrid": (1.4e-06, 1.8e-06, 2.4e-07),
    "ridged": (1.9e-06, 2.3e-06, 3.6e-07),
    "hetero": (2e-06, 2.2e-06, 4.8e-07),
    "distorted": (1.2e-05, 4.4e-05, 1.2e-07),
    "clamped": (1.2e-07, 6e-08, 6e-08),
}
PAIRS = [(case, dims) for case in CASES for dims in DIMENSIONS]
#: Blender 4.2's Cycles wraps 3D and 4D coordinates with C's fmodf (4.5 and 5.0: their SSE formula,
#: which the compiled code follows): they part beyond |x| = 5e8, which the huge set's 16 octaves
#: reach (measured 0.1); everything else is bit for bit 4.2's too.
OLD_WRAP = bpy.app.version < (4, 5, 0)


def _skip_old_wrap(case, dims, label):
    if OLD_WRAP and case == "clamped" and label == "huge" and dims in ("3D", "4D"):
        pytest.skip(f"Blender {bpy.app.version_string}'s Cycles wraps 3D/4D coordinates beyond 5e8 otherwise")


@pytest.mark.parametrize("case,dims", PAIRS)
def test_noise_matches_cycles(noise_results, case, dims):
    label, results = noise_results
    _skip_old_wrap(case, dims, label)
    for output in ("fac", "color"):
        ours, cycles = results[f"{output}_{case}_{dims}"]
        worst = float(np.abs(ours - cycles).max())
        assert len(ours) > 0.9 * SIZE * SIZE and np.isfinite(ours).all()
        measured = MEASURED[case][list(COORDINATES).index(label)]
        print(f"{output} {case} {dims} {label}: {worst:.3g}")
        assert worst <= 3 * measured, (f"{output} {case} {dims} {label}: largest difference {worst:.3g} "
                                       f"(measured {measured:.2g} at most)")


@pytest.mark.parametrize("case,dims", PAIRS)
def test_noise_twin_matches_cycles(noise_results, case, dims):
    """The twin at the coordinates Cycles evaluated (its own AOVs of them): bit for bit."""
    label, results = noise_results
    _skip_old_wrap(case, dims, label)
    co = results["co"][1].astype(np.float32)
    w = results["w"][1][:, 0].astype(np.float32)
    kind, values, normalize = CASES[case]
    args = {"scale": 1.0, **{k.lower(): x for k, x in values.items()}}
    fac, color = noise.noise_texture(int(dims[0]), kind, co, w, normalize=normalize, **args)
    for output, twin in (("fac", fac[:, None]), ("color", color)):
        cycles = results[f"{output}_{case}_{dims}"][1]
        worst = float(np.abs(twin - cycles).max())
        assert worst == 0.0, (f"twin {output} {case} {dims} {label}: "
                              f"largest difference {worst:.3g} (measured 0)")


# --- a file of Blender 4.2 holding the Musgrave types ---------------------------------------------

ROOT = Path(__file__).resolve().parent.parent
BLENDER_42 = ROOT / ".venv-bpy-4.2.23" / "bin" / "python"
#: The Musgrave Texture's types as a 4.2 file holds them (its Noise Texture's since 4.1, Normalize
#: off as the versioning leaves it), with Musgrave-like settings: name -> (type, dimensions, inputs).
MUSGRAVE = {
    "multifractal": ("MULTIFRACTAL", "3D", {"Detail": 4.5, "Roughness": 0.25, "Lacunarity": 2.0}),
    "ridged": ("RIDGED_MULTIFRACTAL", "3D", {"Detail": 4.5, "Roughness": 0.25, "Lacunarity": 2.0,
                                             "Offset": 1.0, "Gain": 2.0}),
    "hybrid": ("HYBRID_MULTIFRACTAL", "4D", {"Detail": 3.2, "Roughness": 0.35, "Lacunarity": 2.2,
                                             "Offset": 0.7, "Gain": 1.0}),
    "hetero": ("HETERO_TERRAIN", "2D", {"Detail": 2.7, "Roughness": 0.4, "Lacunarity": 1.9, "Offset": 1.1}),
    "fbm": ("FBM", "1D", {"Detail": 6.0, "Roughness": 0.5, "Lacunarity": 2.0}),
}
#: Run by Blender 4.2: a node group "Musgrave" (inputs Vector and W, a Fac output per case), saved.
_WRITE_MUSGRAVE = """
import sys, bpy
cases = eval(sys.argv[-2])
group = bpy.data.node_groups.new("Musgrave", "ShaderNodeTree")
group.interface.new_socket("Vector", in_out="INPUT", socket_type="NodeSocketVector")
group.interface.new_socket("W", in_out="INPUT", socket_type="NodeSocketFloat")
inputs, outputs = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
for name, (kind, dims, values) in cases.items():
    group.interface.new_socket(name, in_out="OUTPUT", socket_type="NodeSocketFloat")
    node = group.nodes.new("ShaderNodeTexNoise")
    node.noise_dimensions, node.noise_type, node.normalize = dims, kind, False
    for socket in node.inputs:
        if socket.name in values or socket.name == "Scale":
            socket.default_value = values.get(socket.name, 1.0)
    if dims != "1D":  # (a socket the node hides cannot be found by name)
        group.links.new(inputs.outputs["Vector"], node.inputs["Vector"])
    if dims in ("1D", "4D"):
        group.links.new(inputs.outputs["W"], node.inputs["W"])
    group.links.new(node.outputs["Fac"], outputs.inputs[name])
group.use_fake_user = True
bpy.data.libraries.write(sys.argv[-1], {group}, fake_user=True)
print("written by", bpy.app.version_string)
"""


@pytest.fixture(scope="module")
def musgrave_results(tmp_path_factory):
    """Blender 4.2 writes the group (a subprocess of its own bpy), this Blender appends it from the
    file, as an artist's old file is opened; ours and Cycles' AOVs of its outputs."""
    if not BLENDER_42.exists():
        pytest.skip(f"no Blender 4.2 to write the file with ({BLENDER_42})")
    tmp = tmp_path_factory.mktemp("musgrave")
    path = tmp / "musgrave_42.blend"
    run = subprocess.run([str(BLENDER_42), "-c", _WRITE_MUSGRAVE, repr(MUSGRAVE), str(path)],
                         capture_output=True, text=True, timeout=300)
    assert path.exists(), run.stdout[-2000:] + run.stderr[-2000:]
    scene, mat, tree, u, v = _plane_scene()
    with bpy.data.libraries.load(str(path)) as (source, target):
        target.node_groups = ["Musgrave"]
    group = tree.nodes.new("ShaderNodeGroup")
    group.node_tree = target.node_groups[0]
    co, w = _coordinates(tree, u, v, "small")
    tree.links.new(co, group.inputs["Vector"])
    tree.links.new(w, group.inputs["W"])
    _aov(scene, tree, "co", co, "COLOR")
    _aov(scene, tree, "w", w)
    for name in MUSGRAVE:
        _aov(scene, tree, f"musgrave_{name}", group.outputs[name])
    return against_cycles_per_aov(scene, mat, tmp)


@pytest.mark.parametrize("name", MUSGRAVE)
def test_musgrave_types_from_a_blender_42_file(musgrave_results, name):
    """The group Blender 4.2 saved reads as Cycles reads it: ours and the twin against Cycles."""
    ours, cycles = musgrave_results[f"musgrave_{name}"]
    worst = float(np.abs(ours - cycles).max())
    print(f"musgrave {name}: {worst:.3g}")
    assert len(ours) > 0.9 * SIZE * SIZE and np.isfinite(ours).all()
    # measured (llvmpipe): 6.0e-7, 1.1e-6, 6.3e-7, 1.4e-6, 4.6e-7
    assert worst <= 4.5e-6, f"{name}: largest difference {worst:.3g} (measured 1.4e-6 at most)"
    kind, dims, values = MUSGRAVE[name]
    co = musgrave_results["co"][1].astype(np.float32)
    w = musgrave_results["w"][1][:, 0].astype(np.float32)
    args = {"scale": 1.0, **{k.lower(): x for k, x in values.items()}}
    fac, _ = noise.noise_texture(int(dims[0]), kind, co, w, normalize=False, **args)
    twin = float(np.abs(fac - cycles[:, 0]).max())
    assert twin == 0.0, f"twin {name}: largest difference {twin:.3g} (measured 0)"


# --- the engine ----------------------------------------------------------------------------------

def assert_engine_matches_cycles(tmp, kind: str, cases: dict, spread: float):
    """Nodes of ``kind`` on a plane, their Vector unlinked (the object's Generated coordinates),
    each case (AOV name -> (node properties, input values, output, the largest difference
    measured)) to an AOV: the engine's render and Cycles' (1 sample), each AOV within 3x of what
    was measured, its pixels spanning at least ``spread`` (the texture is not flat)."""
    scene, mat, tree, u, v = _plane_scene()
    for name, (props, values, output, _) in cases.items():
        node = texture_node(tree, kind, props, values)
        _aov(scene, tree, name, node.outputs[output])
    scenes.render(scene, tmp / "ours_beauty.exr")
    ours = _channels(scenes.save_result(scene, tmp / "ours.exr", "MULTILAYER"))
    _cycles(scene, tmp / "cycles_beauty.exr", samples=1)
    theirs = _channels(scenes.save_result(scene, tmp / "cycles.exr", "MULTILAYER"))
    for name, (*_, bound) in cases.items():
        a, b = ours[f"ViewLayer.{name}.X"], theirs[f"ViewLayer.{name}.X"]
        worst = float(np.abs(a - b).max())
        print(f"engine {name}: {worst:.3g} (spread {np.ptp(b):.3g})")
        assert np.ptp(b) > spread, f"{name}: the plane's values span {np.ptp(b):.3g}"
        assert worst <= 3 * bound, f"{name}: largest difference {worst:.3g} (measured {bound:.2g})"


def test_engine_draws_noise_as_cycles(tmp_path):
    """The engine's program holds the noise library where a material's graph calls it: the Noise
    Texture as a file has it by default (3D fBM, Scale 5, Detail 2, Roughness 0.5, Normalize) and
    a 4D Ridged one of Distortion 0.4 (its Color read as a value), their Vector unlinked; Cycles'
    AOVs of the same graph. The engine's Generated coordinate differs from Cycles' by < 1e-6 (x
    Scale 5 and the noise's slope). Measured: 8.6e-7, 1.5e-5 at most."""
    ridged = {"noise_dimensions": "4D", "noise_type": "RIDGED_MULTIFRACTAL"}
    assert_engine_matches_cycles(tmp_path, "ShaderNodeTexNoise", {
        "noise": ({}, {}, "Fac", 8.6e-7),
        "ridged": (ridged, {"W": 0.3, "Distortion": 0.4}, "Color", 1.5e-5)}, spread=0.2)


def test_extreme_inputs_end_and_stay_finite():
    """Noise and Wave at coordinates to 3e38, Detail from -1e9 to 1e9, NaN and infinities, odd
    Lacunarity and Scale (all read at run time, as the engine's uniforms): every loop ends (Noise's
    Detail clamped to 15, Wave's to 64 octaves, the wrap's long division bounded), and where every
    input and the scaled coordinate are finite so is the result."""
    inf, nan = float("inf"), float("nan")
    rows = []
    for co in (0.37, -3.0e38, 3.0e38, 1.0e9, inf, nan):
        for detail in (2.5, 1.0e9, -1.0e9, inf, nan):
            for lacunarity, scale in ((2.0, 5.0), (-2.0, 1.0e5), (0.0, 0.0), (inf, 1.0), (1.7, nan)):
                rows.append((co, detail, lacunarity, scale))
    rows = np.array(rows, np.float32)
    extra = codegen.library("node_noise_value(); node_tex_wave();")
    body = ("vec4 p = node_noise_coordinates(vec3(a.x, 0.5, -a.x), a.x, a.w, 0.3, 4); result = vec4("
            "node_noise_value(p, 4, NOISE_HETERO_TERRAIN, a.y, 0.5, a.z, 0.8, 1.0, 1.0), "
            "node_noise_value(p, 4, NOISE_FBM, a.y, 0.5, a.z, 0.0, 1.0, 1.0), "
            "node_tex_wave(vec3(a.x), a.w, 2.0, a.y, a.z, 0.5, 0.0, WAVE_RINGS, WAVE_SPHERICAL, WAVE_SIN, "
            "WAVE_PHASE_RECIPROCAL), 0.0);")
    values = evaluate(body, {"a": rows}, extra=extra, source="vec4 graph_table(int i) { return vec4(0.0); }")
    with np.errstate(over="ignore", invalid="ignore"):  # (a coordinate x Scale beyond 3.4e38 is infinite)
        finite = np.isfinite(rows).all(axis=1) & np.isfinite(rows[:, 0] * rows[:, 3])
    bad = finite & ~np.isfinite(values[:, :3]).all(axis=1)
    assert not bad.any(), np.concatenate([rows[bad], values[bad]], axis=1)[:12]
