"""The pattern textures (Gradient, Checker, Magic, Brick; Radial Tiling on Blender 5) against
Cycles evaluating the same graph into AOVs: our GLSL (glsl/node_tex_gradient.glsl ...) on the
GPU, and the numpy twin (addon/reference/patterns.py) at the coordinates Cycles wrote.

Coordinates come from the UV through an addition and a product by powers of two (exact, so that
a GPU fusing that product into a later sum changes nothing): ``unit`` spans [-1, 1]; ``large``
|x| to 8192 and negative, where the float grid is coarse; ``integer`` puts every pixel on whole
numbers, the borders of Checker's cells and Brick's rows.

The twin equals Cycles bit for bit (the same float operations, C's sinf ...; NaN where Cycles
gives NaN). Our GLSL rounds as Cycles does but for the GPU's sin, cos, tan and atan (llvmpipe:
within an ulp of C's): differences of an ulp, which Magic's folds and Radial Tiling's tangents
grow. Where an ulp moves a pixel across an edge (a segment's border, Magic's chaos at high
distortion) the pixel is counted apart: ``flips``, pixels off by more than ``EDGE`` of the value's
scale, bounded; the others are compared tightly. Bounds: 3 x the measured largest difference,
0 where it measured 0."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import bpy
import numpy as np
import pytest
import scenes
from test_cycles import _cycles
from test_material_converters import _compiled
from test_material_images import _against_cycles
from test_material_nodes import SIZE, _aov, _combine, _plane_scene
from test_texture_white_noise import _channels, texture_node

from addon.materials import codegen
from addon.reference import patterns

#: Coordinate sets: (offset added to (u, v, 0.37), then the product by powers of two).
COORDINATES = {"unit": ((-0.5, -0.5, -0.2), (2.0, 2.0, 2.0)),
               "large": ((-0.5, -0.5, 0.0), (16384.0, -8192.0, 16384.0))}
#: A difference beyond this fraction of a pixel's scale (1, or its largest value where larger) is a
#: pixel on the other side of an edge, not an ulp of arithmetic.
EDGE = 1e-3


def _vector_math(tree, op, socket, value):
    node = tree.nodes.new("ShaderNodeVectorMath")
    node.operation = op
    tree.links.new(socket, node.inputs[0])
    node.inputs[1].default_value = value
    return node.outputs["Vector"]


def _coordinates(tree, u, v) -> dict:
    unit = _combine(tree, u, v, 0.37)
    out = {label: _vector_math(tree, "MULTIPLY", _vector_math(tree, "ADD", unit, offset), scale)
           for label, (offset, scale) in COORDINATES.items()}
    # whole numbers -16 .. 16: floor(33 uv) - 16 (pixel centres sit half a pixel inside)
    cells = _vector_math(tree, "MULTIPLY", _combine(tree, u, v, 0.0), (33.0, 33.0, 33.0))
    floor = tree.nodes.new("ShaderNodeVectorMath")
    floor.operation = "FLOOR"
    tree.links.new(cells, floor.inputs[0])
    out["integer"] = _vector_math(tree, "ADD", floor.outputs["Vector"], (-16.0, -16.0, 3.0))
    return out


def _render(cases: dict, outputs: tuple, tmp) -> dict:
    """Cycles' AOVs and ours of ``cases`` (name -> (node kind, properties, input values,
    coordinate set)), each node's ``outputs`` ((socket, AOV kind) ...), and the coordinates;
    our graph evaluated in one pass (test_material_images._against_cycles)."""
    scene, mat, tree, u, v = _plane_scene()
    coordinates = _coordinates(tree, u, v)
    for label in {case[3] for case in cases.values()}:
        _aov(scene, tree, f"co_{label}", coordinates[label], "COLOR")
    for name, (kind, props, inputs, label) in cases.items():
        node = texture_node(tree, kind, props, inputs)
        tree.links.new(coordinates[label], node.inputs["Vector"])
        for socket, aov_kind in outputs:
            _aov(scene, tree, f"{name}_{socket.split()[-1].lower()}", node.outputs[socket], aov_kind)
    plane = next(o for o in scene.objects if o.type == "MESH")
    return _against_cycles(scene, mat, plane, tmp)


def _errors(ours, cycles):
    """Each pixel's largest difference over its channels, relative to the pixel's scale (1, or
    its largest channel of Cycles' where larger: a coordinate's ulp grows with its distance); 0
    where both are NaN (Cycles' NaN, ours too), infinite where one alone is."""
    nan_a, nan_b = np.isnan(ours), np.isnan(cycles)
    scale = np.maximum(1.0, np.abs(np.nan_to_num(cycles)).max(axis=1, keepdims=True))
    diff = np.where(nan_a & nan_b, 0.0, np.where(nan_a | nan_b, np.inf, np.abs(ours - cycles) / scale))
    return diff.max(axis=1)


def _check(name, pairs, measured: tuple[float, int]):
    """GLSL against Cycles: the pixels across an edge (error > EDGE) at most 3x the measured
    count (0 where none was), the others within 3x the measured largest error (0 where it was 0)."""
    largest, flips = 0.0, 0
    for ours, cycles in pairs:
        assert len(ours) > 0.9 * SIZE * SIZE
        err = _errors(ours, cycles)
        flips += int((err > EDGE).sum())
        largest = max(largest, float(err[err <= EDGE].max(initial=0.0)))
    print(f"\n{name}: largest {largest:.3g}, across an edge {flips}")
    expected_error, expected_flips = measured
    assert flips <= 3 * expected_flips, f"{name}: {flips} pixels across an edge (measured {expected_flips})"
    assert largest <= 3 * expected_error, \
        f"{name}: largest difference {largest:.3g} (measured {expected_error:.3g})"


def _exact(name, pairs):
    """The twin against Cycles: bit for bit, NaN where Cycles' is NaN."""
    for twin, cycles in pairs:
        err = _errors(np.asarray(twin, np.float64).reshape(len(cycles), -1), cycles)
        worst, count = float(err.max()), int((err > 0).sum())
        assert worst == 0.0, f"twin {name}: {count} pixels differ, largest {worst:.3g} (measured 0)"


# --- the cases, family by family --------------------------------------------------------------

COLOR_AND_FAC = (("Color", "COLOR"), ("Fac", "VALUE"))

GRADIENT_TYPES = ("LINEAR", "QUADRATIC", "EASING", "DIAGONAL", "SPHERICAL", "QUADRATIC_SPHERE", "RADIAL")
GRADIENT_CASES = {f"{kind.lower()}_{label}": ("ShaderNodeTexGradient", {"gradient_type": kind}, {}, label)
                  for kind in GRADIENT_TYPES for label in COORDINATES}
#: GLSL against Cycles (largest difference, pixels across an edge): equal but for Radial's atan2
#: (node_float.glsl's, within 2 ulp of C's: an ulp of the result).
GRADIENT_MEASURED = {"radial_unit": (6.0e-8, 0), "radial_large": (6.0e-8, 0)}


#: Cycles 4.5 and 5.0 divide by a constant, or by one divisor thrice, through its reciprocal;
#: 4.2's divides (measured: an ulp apart). Our GLSL follows 5.0.
RECIPROCAL = bpy.app.version >= (4, 5, 0)


def _gradient_twin(co, props, inputs):
    fac = patterns.gradient(props["gradient_type"], co, RECIPROCAL)
    return np.repeat(fac[:, None], 3, 1), fac


_COLORS = {"Color1": (0.9, 0.5, 0.1, 1.0), "Color2": (0.1, 0.4, 0.8, 1.0)}
#: Scales 7.3 (cells of 0.14), 1.37 at |x| to 8192 (hundreds of cells a pixel), and whole-number
#: coordinates at scales 1, 0.5 and 0.2: every pixel on a border, where Cycles' nudge decides the
#: cell (at 0.2, for 5 and 15, whether co x scale is rounded before the nudge: Cycles' is).
#: GLSL measured equal, every pixel.
CHECKER_CASES = {"unit": ("ShaderNodeTexChecker", {}, {**_COLORS, "Scale": 7.3}, "unit"),
                 "large": ("ShaderNodeTexChecker", {}, {**_COLORS, "Scale": 1.37}, "large"),
                 "integer": ("ShaderNodeTexChecker", {}, {**_COLORS, "Scale": 1.0}, "integer"),
                 "half": ("ShaderNodeTexChecker", {}, {**_COLORS, "Scale": 0.5}, "integer"),
                 "fifth": ("ShaderNodeTexChecker", {}, {**_COLORS, "Scale": 0.2}, "integer")}


def _checker_twin(co, props, inputs):
    fac = patterns.checker(co, inputs["Scale"])
    colors = np.float32(inputs["Color1"][:3]), np.float32(inputs["Color2"][:3])
    return np.where(fac[:, None] == 1.0, *colors), fac


MAGIC_CASES = {f"depth{depth}_{label}": ("ShaderNodeTexMagic", {"turbulence_depth": depth},
                                         {"Scale": 1.7, "Distortion": 1.3}, label)
               for depth in range(11) for label in COORDINATES}
MAGIC_CASES.update({
    "undistorted": ("ShaderNodeTexMagic", {"turbulence_depth": 3}, {"Scale": 5.0, "Distortion": 0.0}, "unit"),
    "wild": ("ShaderNodeTexMagic", {"turbulence_depth": 10}, {"Scale": 5.0, "Distortion": 4.0}, "unit"),
})
#: GLSL against Cycles: the GPU's sin and cos (an ulp off C's in 15 % of calls, llvmpipe) grown
#: by each fold (depth); at distortion 4 the folds are chaotic: an ulp becomes any value (52 px
#: beyond EDGE, the others up to it). Undistorted: equal.
MAGIC_MEASURED = {
    "depth0_unit": (6.0e-8, 0), "depth0_large": (1.2e-7, 0), "depth1_unit": (1.5e-7, 0),
    "depth1_large": (1.2e-7, 0), "depth2_unit": (2.4e-7, 0), "depth2_large": (1.8e-7, 0),
    "depth3_unit": (3.6e-7, 0), "depth3_large": (2.4e-7, 0), "depth4_unit": (4.2e-7, 0),
    "depth4_large": (4.2e-7, 0), "depth5_unit": (4.8e-7, 0), "depth5_large": (4.2e-7, 0),
    "depth6_unit": (4.2e-7, 0), "depth6_large": (4.2e-7, 0), "depth7_unit": (9.0e-7, 0),
    "depth7_large": (7.2e-7, 0), "depth8_unit": (1.4e-6, 0), "depth8_large": (1.3e-6, 0),
    "depth9_unit": (1.4e-6, 0), "depth9_large": (1.3e-6, 0), "depth10_unit": (1.4e-6, 0),
    "depth10_large": (1.3e-6, 0), "undistorted": (0.0, 0), "wild": (1.0e-3, 52),
}


def _magic_twin(co, props, inputs):
    return patterns.magic(co, inputs["Scale"], inputs["Distortion"], props["turbulence_depth"], RECIPROCAL)


_BRICK = {"Color1": (0.9, 0.5, 0.1, 1.0), "Color2": (0.1, 0.4, 0.8, 1.0), "Mortar": (0.3, 0.25, 0.2, 1.0)}
_SHIFTED = {"offset": 0.3, "offset_frequency": 3, "squash": 1.7, "squash_frequency": 2}
#: The defaults; offset and squash on other rows, bias, widths not powers of two; a hard mortar
#: (Smooth 0) with every row offset; |x| to 8192 (rows and bricks beyond 16 bits); whole numbers
#: (every pixel on a row's border). GLSL measured equal, every pixel (the mortar's borders too).
BRICK_CASES = {
    "default": ("ShaderNodeTexBrick", {}, {**_BRICK, "Scale": 5.0}, "unit"),
    "shifted": ("ShaderNodeTexBrick", _SHIFTED,
                {**_BRICK, "Scale": 3.1, "Mortar Size": 0.05, "Mortar Smooth": 0.7, "Bias": -0.3,
                 "Brick Width": 0.37, "Row Height": 0.21}, "unit"),
    "hard": ("ShaderNodeTexBrick", {"offset": 0.7, "offset_frequency": 1, "squash": 0.6,
                                    "squash_frequency": 3},
             {**_BRICK, "Scale": 2.3, "Mortar Size": 0.06, "Mortar Smooth": 0.0, "Bias": 0.4,
              "Brick Width": 0.43, "Row Height": 0.17}, "unit"),
    "large": ("ShaderNodeTexBrick", _SHIFTED,
              {**_BRICK, "Scale": 1.0, "Mortar Size": 0.05, "Mortar Smooth": 0.3, "Brick Width": 0.37,
               "Row Height": 0.21}, "large"),
    "integer": ("ShaderNodeTexBrick", {}, {**_BRICK, "Scale": 1.0, "Mortar Size": 0.1, "Brick Width": 2.0,
                                           "Row Height": 1.0}, "integer"),
}
#: The twin's arguments after the coordinate, and the node's defaults where a case leaves them.
_BRICK_ARGS = {"Color1": None, "Color2": None, "Mortar": None, "Scale": None, "Mortar Size": 0.02,
               "Mortar Smooth": 0.1, "Bias": 0.0, "Brick Width": 0.5, "Row Height": 0.25, "offset": 0.5,
               "offset_frequency": 2, "squash": 1.0, "squash_frequency": 2}


def _brick_twin(co, props, inputs):
    values = _BRICK_ARGS | props | inputs
    return patterns.brick(co, *(values[k] for k in _BRICK_ARGS))


#: (Sides, Roundness, Normalize; GLSL's largest difference from Cycles' measured at the unit and
#: the large coordinates): whole sides (straight, rounded corners, round; 2, a degenerate polygon:
#: NaN in Cycles where rounded, equal), sides not whole (the last, narrower segment). The GPU's
#: tan, sin and cos and node_float.glsl's atan, each within 2 ulp of C's, grown a few times by the
#: segment geometry; no pixel changed segment.
RADIAL = [
    (5.0, 0.0, False, 5.7e-7, 5.1e-7), (5.0, 0.0, True, 4.8e-7, 2.5e-7), (5.0, 0.4, False, 5.7e-7, 5.1e-7),
    (5.0, 0.4, True, 5.1e-7, 3.4e-7), (5.0, 1.0, False, 4.8e-7, 4.3e-10), (5.0, 1.0, True, 4.2e-7, 3.5e-10),
    (2.0, 0.0, True, 3.6e-7, 9.9e-7), (2.0, 0.4, False, 4.8e-7, 0.0), (2.0, 0.4, True, 0.0, 0.0),
    (3.6, 0.0, False, 5.1e-7, 5.2e-7), (3.6, 0.0, True, 5.1e-7, 5.7e-7), (3.6, 0.4, False, 5.1e-7, 5.0e-7),
    (3.6, 0.4, True, 3.6e-7, 2.2e-7), (3.6, 1.0, False, 4.8e-7, 1.8e-7), (3.6, 1.0, True, 3.0e-7, 1.8e-7),
    (7.3, 0.0, True, 6.6e-7, 3.3e-7), (7.3, 0.4, False, 5.6e-7, 5.0e-7), (7.3, 0.4, True, 7.2e-7, 1.9e-7),
]
RADIAL_CASES, RADIAL_MEASURED = {}, {}
for _sides, _roundness, _normalize, *_measured in RADIAL:
    for _label, _largest in zip(("unit", "large"), _measured):
        _name = f"{_sides:g}_{_roundness:g}{'_normalized' * _normalize}_{_label}".replace(".", "p")
        RADIAL_CASES[_name] = ("ShaderNodeRadialTiling", {"normalize": _normalize},
                               {"Sides": _sides, "Roundness": _roundness}, _label)
        RADIAL_MEASURED[_name] = (_largest, 0)


def _radial_twin(co, props, inputs):
    return patterns.radial_tiling(co, inputs["Sides"], inputs["Roundness"], props["normalize"])


@dataclass(frozen=True)
class Family:
    cases: dict
    outputs: tuple  # (socket, AOV kind) of each node, in the twin's order
    measured: dict  # case -> (largest difference, pixels across an edge); (0, 0) where absent
    twin: Callable  # (co, properties, inputs) -> the outputs
    renders: int = 1  # Cycles' SVM stack holds this many sets' nodes in one material: one each


FAMILIES = {
    "gradient": Family(GRADIENT_CASES, COLOR_AND_FAC, GRADIENT_MEASURED, _gradient_twin),
    "checker": Family(CHECKER_CASES, COLOR_AND_FAC, {}, _checker_twin),
    "magic": Family(MAGIC_CASES, COLOR_AND_FAC, MAGIC_MEASURED, _magic_twin),
    "brick": Family(BRICK_CASES, COLOR_AND_FAC, {}, _brick_twin),
    "radial_tiling": Family(RADIAL_CASES, (("Segment Coordinates", "COLOR"), ("Segment ID", "VALUE"),
                                           ("Segment Width", "VALUE"), ("Segment Rotation", "VALUE")),
                            RADIAL_MEASURED, _radial_twin, renders=2),
}
#: Radial Tiling is a Blender 5 node: skipped on 4.x.
HAS_RADIAL_TILING = hasattr(bpy.types, "ShaderNodeRadialTiling")
CASES = [pytest.param(family, name, id=f"{family}-{name}",
                      marks=[pytest.mark.skipif(family == "radial_tiling" and not HAS_RADIAL_TILING,
                                                reason="Radial Tiling is a Blender 5 node")])
         for family, spec in FAMILIES.items() for name in spec.cases]


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """A family's (ours, Cycles') by AOV name, rendered the first time a test asks for it."""
    rendered: dict[str, dict] = {}

    def of(family: str) -> dict:
        if family not in rendered:
            spec, out = FAMILIES[family], {}
            labels = sorted({case[3] for case in spec.cases.values()})
            for part in range(spec.renders):
                chosen = labels[part::spec.renders]
                cases = {name: case for name, case in spec.cases.items() if case[3] in chosen}
                out.update(_render(cases, spec.outputs, tmp_path_factory.mktemp(f"{family}{part}")))
            rendered[family] = out
        return rendered[family]
    return of


def _pairs(results, family, name, values=None):
    """(ours or the twin's ``values``, Cycles') of each output of case ``name``."""
    out = []
    for k, (socket, _) in enumerate(FAMILIES[family].outputs):
        ours, cycles = results(family)[f"{name}_{socket.split()[-1].lower()}"]
        out.append((ours if values is None else values[k], cycles))
    return out


@pytest.mark.parametrize("family,name", CASES)
def test_pattern_matches_cycles(results, family, name):
    _check(name, _pairs(results, family, name), FAMILIES[family].measured.get(name, (0.0, 0)))


@pytest.mark.parametrize("family,name", CASES)
def test_pattern_twin_matches_cycles(results, family, name):
    _, props, inputs, label = FAMILIES[family].cases[name]
    twin = FAMILIES[family].twin(results(family)[f"co_{label}"][1].astype(np.float32), props, inputs)
    _exact(name, _pairs(results, family, name, twin))


def test_checker_cells_alternate():
    """Cycles' parity rule in the twin: neighbouring cells differ, one cell's inside is constant,
    and a coordinate of 2 (a border) falls in the cell below it (Cycles' nudge: (2 + 1e-6) x
    0.999999 < 2)."""
    co = np.array([[0.5, 0.5, 0.5], [1.5, 0.5, 0.5], [0.1, 0.9, 0.2], [2.0, 0.5, 0.5], [1.9, 0.5, 0.5]])
    fac = patterns.checker(co, 1.0)
    assert fac[0] != fac[1] and fac[0] == fac[2] and fac[3] == fac[4], fac


# --- the library ------------------------------------------------------------------------------

def test_pattern_library_compiled_where_called():
    """A graph calling Brick compiles its file and the float arithmetic it calls, before it."""
    needed = codegen.library("x = node_tex_brick(co, a, b, c, s, size, smooth, bias, w, h, o, of, q, qf);")
    assert needed == codegen.LIBRARY + ("node_float.glsl", "node_tex_brick.glsl")


def test_float_fma_rounds_once_and_stays_finite():
    """node_float.glsl's float_fma against a fused multiply-add (the twin's noise.fma: the product
    exact in float64, one rounding to float32): equal at random operands whose sum cancels to
    various depths (measured: every one of 4,096); where the split overflows (|a| >= 2^115) or the
    product does, the plain product and sum, finite where the fused result is (before: NaN)."""
    from glsl_harness import evaluate

    from addon.reference import noise

    rng = np.random.default_rng(52)
    a = (rng.uniform(1, 2, 4096) * 2.0 ** rng.integers(-30, 30, 4096) * rng.choice([-1, 1], 4096))
    b = (rng.uniform(1, 2, 4096) * 2.0 ** rng.integers(-30, 30, 4096)).astype(np.float32)
    a = a.astype(np.float32)
    product = a.astype(np.float64) * b
    c = (-product * (1.0 + rng.choice([0.0, 1e-7, 1e-4, 0.5, -3.0], 4096))).astype(np.float32)
    extremes = np.array([[1e35, 1e-35, 0.5], [3e38, 1.0, 0.0], [-3e38, 0.5, 1.0], [1e20, 1e20, 0.0],
                         [np.inf, 1.0, 0.0], [2.0, 3.0, 1.0]], np.float32)
    rows = np.concatenate([np.stack([a, b, c], 1), extremes])
    rows = np.concatenate([rows, np.zeros((len(rows), 1), np.float32)], 1)
    ours = evaluate("result = vec4(float_fma(a.x, a.y, a.z));", {"a": rows},
                    extra=codegen.library("float_fma();"),
                    source="vec4 graph_table(int i) { return vec4(0.0); }")[:, 0]
    with np.errstate(over="ignore"):  # (1e20 x 1e20 is infinite in float32, as fused)
        fused = noise.fma(rows[:, 0], rows[:, 1], rows[:, 2])
    random, tail = slice(0, 4096), slice(4096, None)
    differ = int((ours[random] != fused[random]).sum())
    assert differ == 0, f"{differ} of 4096 differ from one rounding (measured 0)"
    assert np.isfinite(ours[tail]).tolist() == np.isfinite(fused[tail]).tolist(), (ours[tail], fused[tail])
    finite = np.isfinite(fused[tail])
    assert np.allclose(ours[tail][finite], fused[tail][finite], rtol=2.0 ** -22, atol=0.0), ours[tail]


def test_settings_are_constants():
    """A pattern's numbers (Brick's offset, squash and frequencies, Magic's Depth, Radial Tiling's
    Sides) are constants of the compiled graph: editing them keeps the source (one program); a
    type or Normalize chooses another function."""
    scene, mat, tree, u, v = _plane_scene()
    co = _combine(tree, u, v, 0.37)
    nodes = {kind: tree.nodes.new(kind) for kind in ("ShaderNodeTexBrick", "ShaderNodeTexMagic",
                                                     "ShaderNodeTexGradient")}
    if HAS_RADIAL_TILING:
        nodes["ShaderNodeRadialTiling"] = tree.nodes.new("ShaderNodeRadialTiling")
    for k, node in enumerate(nodes.values()):
        tree.links.new(co, node.inputs["Vector"])
        _aov(scene, tree, f"out{k}", node.outputs[1])
    before = _compiled(mat)
    brick, magic = nodes["ShaderNodeTexBrick"], nodes["ShaderNodeTexMagic"]
    brick.offset, brick.offset_frequency, brick.squash, brick.squash_frequency = 0.2, 3, 1.5, 4
    magic.turbulence_depth = 7
    if HAS_RADIAL_TILING:
        nodes["ShaderNodeRadialTiling"].inputs["Sides"].default_value = 3.5
    after = _compiled(mat)
    assert after.source == before.source
    assert np.abs(after.constants - before.constants).max() > 0.2
    nodes["ShaderNodeTexGradient"].gradient_type = "RADIAL"
    assert _compiled(mat).source != before.source


# --- the engine -------------------------------------------------------------------------------

def test_engine_draws_patterns_as_cycles(tmp_path):
    """The engine's program holds the pattern library where a material calls it: Magic and
    Checker of the plane's Generated coordinate (their Vector unlinked), Brick of its UV, to AOVs;
    Cycles' AOVs of the same graph. Our Generated and UV differ from Cycles' by < 1e-6: Magic
    (smooth) and Brick's smoothed mortar by as much times their slopes; Checker (scale 5: no pixel
    centre within 0.01 of a border) equal. Measured: Magic 5.2e-6, Brick 7.1e-5 (no pixel across
    a brick's border), Checker equal."""
    scene, mat, tree, u, v = _plane_scene()
    magic = tree.nodes.new("ShaderNodeTexMagic")
    magic.turbulence_depth = 2
    checker = tree.nodes.new("ShaderNodeTexChecker")
    brick = tree.nodes.new("ShaderNodeTexBrick")
    brick.inputs["Mortar Size"].default_value = 0.05
    tree.links.new(tree.nodes["Texture Coordinate"].outputs["UV"], brick.inputs["Vector"])
    for name, node in (("magic", magic), ("checker", checker), ("brick", brick)):
        _aov(scene, tree, name, node.outputs["Fac"])
    scenes.render(scene, tmp_path / "ours_beauty.exr")
    ours = _channels(scenes.save_result(scene, tmp_path / "ours.exr", "MULTILAYER"))
    _cycles(scene, tmp_path / "cycles_beauty.exr", samples=1)
    theirs = _channels(scenes.save_result(scene, tmp_path / "cycles.exr", "MULTILAYER"))
    diff = {name: np.abs(ours[f"ViewLayer.{name}.X"] - theirs[f"ViewLayer.{name}.X"])
            for name in ("magic", "checker", "brick")}
    for name in diff:
        assert np.ptp(theirs[f"ViewLayer.{name}.X"]) > 0.5, f"{name} varies across the plane"
    for name, bound, measured in (("magic", 1.5e-5, "5.2e-6"), ("brick", 2e-4, "7.1e-5")):
        worst = float(diff[name].max())
        assert worst < bound, f"{name}: largest difference {worst:.3g} (measured {measured})"
    differ = int((diff["checker"] > 0).sum())
    assert differ == 0, f"Checker: {differ} of {diff['checker'].size} pixels differ (measured 0)"
