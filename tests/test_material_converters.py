"""Color Ramp, the curve nodes, Blackbody, Wavelength, Mapping, Vector Rotate, Normal and the
legacy colour nodes compiled (materials/codegen.py) against Cycles evaluating the same graph into
AOVs, as tests/test_material_nodes.py does: a plane filling the view, inputs made from its UV (u, v
on a 33 x 33 grid of pixel centres), our function evaluated at the UVs Cycles wrote.

Ramps and curves are read as Cycles bakes them (a table of 257 entries Blender evaluates); their
tables are constants of the compiled graph, so a value edit (a stop's colour, a curve point)
compiles to the same source."""

from __future__ import annotations

import bpy
import numpy as np
import pytest
from test_material_nodes import _affine, _against_cycles, _aov, _combine, _compare, _node, _plane_scene

from addon.blender import nodes as reader
from addon.materials import codegen, graph

# --- Color Ramp -----------------------------------------------------------------------------------

RAMP_INTERPOLATIONS = ("CONSTANT", "LINEAR", "EASE", "CARDINAL", "B_SPLINE")
HUE_INTERPOLATIONS = ("NEAR", "FAR", "CW", "CCW")
#: name -> (interpolation, colour mode, hue interpolation)
RAMP_CASES = {f"rgb_{k.lower()}": (k, "RGB", "NEAR") for k in RAMP_INTERPOLATIONS}
RAMP_CASES.update({f"{mode.lower()}_{hue.lower()}": ("LINEAR", mode, hue)
                   for mode in ("HSV", "HSL") for hue in HUE_INTERPOLATIONS})
RAMP_CASES["hsv_b_spline"] = ("B_SPLINE", "HSV", "NEAR")
#: the ramps whose Alpha output is compared too
RAMP_ALPHAS = ("rgb_constant", "rgb_linear", "rgb_b_spline", "hsl_far")

#: stops (position, RGBA): hues far apart, alphas differing
RAMP_STOPS = ((0.1, (0.9, 0.1, 0.2, 1.0)), (0.45, (0.2, 0.9, 0.1, 0.7)), (0.6, (1.0, 0.8, 0.0, 0.2)),
              (0.85, (0.1, 0.3, 0.95, 0.4)))


def _ramp(tree, fac, interpolation="LINEAR", mode="RGB", hue="NEAR"):
    node = tree.nodes.new("ShaderNodeValToRGB")
    ramp = node.color_ramp
    ramp.interpolation, ramp.color_mode, ramp.hue_interpolation = interpolation, mode, hue
    (p0, c0), (p1, c1) = RAMP_STOPS[0], RAMP_STOPS[-1]
    ramp.elements[0].position, ramp.elements[0].color = p0, c0
    ramp.elements[1].position, ramp.elements[1].color = p1, c1
    for position, color in RAMP_STOPS[1:-1]:
        ramp.elements.new(position).color = color
    tree.links.new(fac, node.inputs["Fac"])
    return node


def _plane(tree, u, v, a, b, c):
    """a u + b v + c: every pixel its own value."""
    return _node(tree, "ShaderNodeMath", {"Value": v, "Value_001": b, "Value_002": _affine(tree, u, a, c)},
                 "Value", operation="MULTIPLY_ADD")


def _fac(tree, u, v):
    """1.4 u + 0.04 v - 0.2: past [0, 1] at the edges."""
    return _plane(tree, u, v, 1.4, 0.04, -0.2)


def _vector(tree, u, v, x, y, z):
    """A vector of three (scale, offset) of u, v, u."""
    return _combine(tree, _affine(tree, u, *x), _affine(tree, v, *y), _affine(tree, u, *z))


@pytest.fixture(scope="module")
def ramp_results(tmp_path_factory):
    """Every interpolation in RGB, and HSV and HSL with every hue interpolation, four stops: one
    render per colour mode (a graph's tables are constants of every program evaluating it, and
    the compiler's time grows with them)."""
    cache = {}

    def results(mode):
        if mode not in cache:
            scene, mat, tree, u, v = _plane_scene()
            fac = _fac(tree, u, v)
            for name, (interpolation, color_mode, hue) in RAMP_CASES.items():
                if color_mode != mode:
                    continue
                node = _ramp(tree, fac, interpolation, color_mode, hue)
                _aov(scene, tree, name, node.outputs["Color"], "COLOR")
                if name in RAMP_ALPHAS:
                    _aov(scene, tree, f"{name}_alpha", node.outputs["Alpha"])
            cache[mode] = _against_cycles(scene, mat, tmp_path_factory.mktemp(f"ramp_{mode.lower()}"))
        return cache[mode]
    return results


@pytest.mark.parametrize("case", [*RAMP_CASES, *(f"{n}_alpha" for n in RAMP_ALPHAS)])
def test_color_ramp_matches_cycles(ramp_results, case):
    mode = RAMP_CASES[case.removesuffix("_alpha")][1]
    # measured: RGB at most 3.6e-7 (Constant 0); HSV and HSL 1.9e-6 (Far and CW)
    if mode == "RGB" or case.endswith("_alpha"):
        _compare(ramp_results(mode), case, 1e-6, "<= 3.6e-7")
    else:
        _compare(ramp_results(mode), case, 6e-6, "<= 1.9e-6")


# --- curves ---------------------------------------------------------------------------------------

def _shape_rgb(mapping):
    """C, R, G, B curves each bent (the C curve composed under the others, as Cycles bakes it)."""
    r, g, b, c = mapping.curves
    c.points.new(0.5, 0.65)
    r.points[0].location = (0.0, 0.1)
    r.points.new(0.3, 0.5)
    g.points[1].location = (0.8, 1.0)
    g.points.new(0.4, 0.2)
    b.points.new(0.7, 0.3).handle_type = "VECTOR"


def _shape_vector(mapping):
    """X, Y, Z bent; Y starting at x = -1.2 (the range is all curves' -1.2 .. 1: clipping off, as with
    it on each update shifts points past the clipping box back, and Cycles updates too)."""
    mapping.use_clip = False
    x, y, z = mapping.curves
    x.points.new(0.0, 0.5)
    y.points[0].location = (-1.2, -0.5)
    z.points.new(0.5, -0.3).handle_type = "VECTOR"


def _shape_float(mapping):
    """Bent, and ending at x = 1.5 (the range 0 .. 1.5)."""
    curve = mapping.curves[0]
    curve.points.new(0.3, 0.8)
    curve.points[-1].location = (1.5, 0.2)


CURVE_CASES = [f"{kind}_{extend}" for kind in ("rgb", "rgb_fac", "vector", "float") for extend in
               ("horizontal", "extrapolated")]


def _curve_node(tree, kind, inputs, shape, extend):
    node = tree.nodes.new(kind)
    shape(node.mapping)
    node.mapping.extend = extend
    node.mapping.update()
    sockets = {s.identifier: s for s in node.inputs}
    for name, value in inputs.items():
        if isinstance(value, bpy.types.NodeSocket):
            tree.links.new(value, sockets[name])
        else:
            sockets[name].default_value = value
    return node.outputs[0]


@pytest.fixture(scope="module")
def curve_results(tmp_path_factory):
    """RGB Curves on a colour of -0.3 .. 1.3 (Fac 0.8, and from the UV), Vector Curves on a vector of
    -1.5 .. 1.5, Float Curve on -0.5 .. 1.9 (Factor 0.9): past their curves' ranges, each Extend."""
    scene, mat, tree, u, v = _plane_scene()
    color = _vector(tree, u, v, (1.6, -0.3), (1.4, -0.2), (-1.2, 1.1))
    vector = _vector(tree, u, v, (3.0, -1.5), (3.0, -1.5), (-2.0, 1.0))
    value = _affine(tree, u, 2.4, -0.5)
    for extend in ("HORIZONTAL", "EXTRAPOLATED"):
        suffix = extend.lower()
        out = _curve_node(tree, "ShaderNodeRGBCurve", {"Fac": 0.8, "Color": color}, _shape_rgb, extend)
        _aov(scene, tree, f"rgb_{suffix}", out, "COLOR")
        out = _curve_node(tree, "ShaderNodeRGBCurve", {"Fac": v, "Color": color}, _shape_rgb, extend)
        _aov(scene, tree, f"rgb_fac_{suffix}", out, "COLOR")
        inputs = {"Fac": 1.0, "Vector": vector}
        out = _curve_node(tree, "ShaderNodeVectorCurve", inputs, _shape_vector, extend)
        _aov(scene, tree, f"vector_{suffix}", out, "COLOR")
        out = _curve_node(tree, "ShaderNodeFloatCurve", {"Factor": 0.9, "Value": value}, _shape_float, extend)
        _aov(scene, tree, f"float_{suffix}", out)
    return _against_cycles(scene, mat, tmp_path_factory.mktemp("curves"))


@pytest.mark.parametrize("case", CURVE_CASES)
def test_curves_match_cycles(curve_results, case):
    # measured: at most 1.9e-7
    _compare(curve_results, case, 1e-6, "<= 1.9e-7")


# --- a value edit compiles to the same source -----------------------------------------------------

def _compiled(mat):
    g, groups = reader.read_material(mat, "ALL")
    flat = graph.flatten(g, groups)
    targets = {f"r{i}": (n.name, "Color" if "Color" in n.inputs else "Value")
               for i, n in enumerate(flat.nodes.values()) if n.kind == "ShaderNodeOutputAOV"}
    compiled = codegen.compile_graph(flat, targets)
    assert not compiled.missing, compiled.missing
    return compiled


@pytest.mark.parametrize("kind", ["ramp", "curve"])
def test_value_edits_keep_the_source(kind):
    """Moving a ramp stop's colour, or a curve point, changes constants only."""
    scene, mat, tree, u, v = _plane_scene()
    if kind == "ramp":
        node = _ramp(tree, _fac(tree, u, v))
        _aov(scene, tree, "out", node.outputs["Color"], "COLOR")
    else:
        node = tree.nodes.new("ShaderNodeRGBCurve")
        _shape_rgb(node.mapping)
        tree.links.new(_combine(tree, u, v, 0.5), node.inputs["Color"])
        _aov(scene, tree, "out", node.outputs["Color"], "COLOR")
    before = _compiled(mat)
    if kind == "ramp":
        node.color_ramp.elements[1].color = (0.3, 0.3, 0.9, 1.0)
    else:
        node.mapping.curves[0].points[1].location = (0.3, 0.9)
        node.mapping.update()
    after = _compiled(mat)
    assert after.source == before.source
    assert before.constants.shape == after.constants.shape
    changed = np.abs(after.constants - before.constants).max()
    assert changed > 0.05, changed


# --- Blackbody, Wavelength, the legacy Mix --------------------------------------------------------

LEGACY = bpy.app.version < (5, 0, 0)  # Separate / Combine RGB and HSV: Blender 4 has them, 5.0 not
MIX_RGB_CASES = {mode.lower(): (mode, False) for mode in codegen.MIX_BLEND_TYPES}
MIX_RGB_CASES.update({f"{mode.lower()}_clamped": (mode, True) for mode in ("ADD", "LINEAR_LIGHT", "DODGE")})
COLOR_CASES = ["blackbody", "wavelength", "mix_rgb_alpha", *(f"mix_rgb_{m}" for m in MIX_RGB_CASES)]
LEGACY_CASES = ["separate_rgb_r", "separate_rgb_g", "separate_rgb_b", "separate_hsv_h", "separate_hsv_s",
                "separate_hsv_v", "combine_rgb", "combine_hsv"]


@pytest.fixture(scope="module")
def color_results(tmp_path_factory):
    """Blackbody from 500 to 13900 K (both constant ends and every range of the fit), Wavelength
    from 360 to 800 nm (black on both sides), the legacy Mix (every blend mode, Fac past [0, 1],
    Clamp; Use Alpha with Color2's alpha 0.3), on Blender 4 the legacy Separate / Combine."""
    scene, mat, tree, u, v = _plane_scene()
    kelvin = _plane(tree, u, v, 13000.0, 400.0, 500.0)
    _aov(scene, tree, "blackbody", _node(tree, "ShaderNodeBlackbody", {"Temperature": kelvin}, "Color"),
         "COLOR")
    nm = _plane(tree, u, v, 430.0, 10.0, 360.0)
    _aov(scene, tree, "wavelength", _node(tree, "ShaderNodeWavelength", {"Wavelength": nm}, "Color"), "COLOR")
    color_a = _combine(tree, _affine(tree, u, 2.0, -0.5), _affine(tree, v, 1.5, 0.0), 0.3)
    color_b = _combine(tree, _affine(tree, v, -1.0, 0.8), _affine(tree, u, 1.2, -0.1), 0.6)
    fac = _affine(tree, u, 1.4, -0.2)
    for name, (mode, clamp) in MIX_RGB_CASES.items():
        out = _node(tree, "ShaderNodeMixRGB", {"Fac": fac, "Color1": color_a, "Color2": color_b}, "Color",
                    blend_type=mode, use_clamp=clamp)
        _aov(scene, tree, f"mix_rgb_{name}", out, "COLOR")
    rgb = tree.nodes.new("ShaderNodeRGB")
    rgb.outputs[0].default_value = (0.9, 0.2, 0.4, 0.3)
    out = _node(tree, "ShaderNodeMixRGB", {"Fac": fac, "Color1": color_a, "Color2": rgb.outputs[0]}, "Color",
                blend_type="MIX", use_alpha=True)
    _aov(scene, tree, "mix_rgb_alpha", out, "COLOR")
    if LEGACY:
        color = _vector(tree, u, v, (1.6, -0.3), (1.2, 0.0), (-1.0, 0.9))
        for c in "RGB":
            out = _node(tree, "ShaderNodeSeparateRGB", {"Image": color}, c)
            _aov(scene, tree, f"separate_rgb_{c.lower()}", out)
        for c in "HSV":
            out = _node(tree, "ShaderNodeSeparateHSV", {"Color": color}, c)
            _aov(scene, tree, f"separate_hsv_{c.lower()}", out)
        inputs = {"R": _affine(tree, u, 1.2, -0.1), "G": v, "B": 0.7}
        _aov(scene, tree, "combine_rgb", _node(tree, "ShaderNodeCombineRGB", inputs, "Image"), "COLOR")
        inputs = {"H": _affine(tree, u, 1.2, -0.1), "S": v, "V": 0.7}
        _aov(scene, tree, "combine_hsv", _node(tree, "ShaderNodeCombineHSV", inputs, "Color"), "COLOR")
    return _against_cycles(scene, mat, tmp_path_factory.mktemp("color"))


@pytest.mark.parametrize("case", COLOR_CASES)
def test_color_nodes_match_cycles(color_results, case):
    # measured: at most 3.2e-7 (Mix's Color), but Wavelength 2.3e-6 on 5.0, 5.8e-6 on 4.5 (its XYZ
    # -> RGB rows as Cycles holds them, to a few 1e-6: Blender 5's matrix on 4.5 was 1.8e-4 off) and
    # Dodge 1.8e-6 (its division, as the Mix node's)
    if case == "wavelength":
        modern = bpy.app.version >= (5, 0, 0)
        _compare(color_results, case, 6e-6 if modern else 1.5e-5, "2.3e-6" if modern else "5.8e-6")
    elif case.startswith("mix_rgb_dodge"):
        _compare(color_results, case, 5e-6, "1.8e-6")
    else:
        _compare(color_results, case, 1e-6, "<= 3.2e-7")


@pytest.mark.parametrize("case", LEGACY_CASES)
def test_legacy_color_nodes_match_cycles(color_results, case):
    if not LEGACY:
        pytest.skip(f"Blender {bpy.app.version_string} has no ShaderNodeSeparateRGB / CombineRGB / "
                    "SeparateHSV / CombineHSV (5.0 removed them)")
    # measured on 4.5: at most 6.6e-7 (Combine HSV), the rest 1.2e-7
    _compare(color_results, case, 2e-6, "<= 6.6e-7")


# --- Mapping, Vector Rotate, Normal ---------------------------------------------------------------

LOCATION, ROTATION, SCALE = (0.3, -0.2, 0.5), (0.4, -1.1, 2.3), (1.5, -0.7, 0.8)
MAPPING_TYPES = ("POINT", "TEXTURE", "VECTOR", "NORMAL")
ROTATE_TYPES = ("AXIS_ANGLE", "X_AXIS", "Y_AXIS", "Z_AXIS", "EULER_XYZ")
VECTOR_CASES = [f"mapping_{t.lower()}" for t in MAPPING_TYPES]
VECTOR_CASES += [f"mapping_{t.lower()}_linked" for t in MAPPING_TYPES]
VECTOR_CASES += ["mapping_texture_zero_scale", "mapping_normal_zero_scale"]
VECTOR_CASES += [f"rotate_{t.lower()}{s}" for t in ROTATE_TYPES for s in ("", "_inverted")]
VECTOR_CASES += ["rotate_zero_axis", "normal_direction", "normal_dot", "normal_dot_unlinked"]


@pytest.fixture(scope="module")
def vector_results(tmp_path_factory):
    """Mapping of every type with constant Location / Rotation / Scale, with all three linked from
    the UV, with a zero scale component; Vector Rotate of every type, inverted or not, around a
    Center, the angle from the UV, about an axis not of unit length (and a zero one); the Normal
    node's direction (not of unit length) and its Dot to a linked and an unlinked normal."""
    scene, mat, tree, u, v = _plane_scene()
    vector = _vector(tree, u, v, (2.0, -1.0), (2.0, -1.0), (-1.0, 0.5))
    location = _combine(tree, u, 0.2, _affine(tree, v, -1.0, 0.3))
    rotation = _combine(tree, _affine(tree, u, 2.0, -0.5), _affine(tree, v, 3.0, -1.0), 1.0)
    scale = _combine(tree, _affine(tree, v, 2.0, -0.5), 0.9, _affine(tree, u, 1.5, 0.2))
    for kind in MAPPING_TYPES:
        sockets = {"Vector": vector, "Location": LOCATION, "Rotation": ROTATION, "Scale": SCALE}
        linked = {"Vector": vector, "Location": location, "Rotation": rotation, "Scale": scale}
        for suffix, inputs in (("", sockets), ("_linked", linked)):
            if kind in ("VECTOR", "NORMAL"):
                inputs = {k: x for k, x in inputs.items() if k != "Location"}
            out = _node(tree, "ShaderNodeMapping", inputs, "Vector", vector_type=kind)
            _aov(scene, tree, f"mapping_{kind.lower()}{suffix}", out, "COLOR")
    for kind in ("TEXTURE", "NORMAL"):
        inputs = {"Vector": vector, "Rotation": ROTATION, "Scale": (1.5, 0.0, 0.8)}
        if kind == "TEXTURE":
            inputs["Location"] = LOCATION
        out = _node(tree, "ShaderNodeMapping", inputs, "Vector", vector_type=kind)
        _aov(scene, tree, f"mapping_{kind.lower()}_zero_scale", out, "COLOR")
    angle = _affine(tree, u, 3.0, -1.0)
    for kind in ROTATE_TYPES:
        for invert in (False, True):
            inputs = {"Vector": vector, "Center": (0.2, -0.1, 0.3)}
            if kind == "EULER_XYZ":
                inputs["Rotation"] = ROTATION
            else:
                inputs["Angle"] = angle
            if kind == "AXIS_ANGLE":
                inputs["Axis"] = (0.3, 0.5, -0.8)
            out = _node(tree, "ShaderNodeVectorRotate", inputs, "Vector", rotation_type=kind, invert=invert)
            _aov(scene, tree, f"rotate_{kind.lower()}{'_inverted' if invert else ''}", out, "COLOR")
    inputs = {"Vector": vector, "Center": (0.2, -0.1, 0.3), "Axis": (0.0, 0.0, 0.0), "Angle": angle}
    out = _node(tree, "ShaderNodeVectorRotate", inputs, "Vector", rotation_type="AXIS_ANGLE")
    _aov(scene, tree, "rotate_zero_axis", out, "COLOR")
    normal = tree.nodes.new("ShaderNodeNormal")
    normal.outputs["Normal"].default_value = (0.3, 0.6, 0.74)
    tree.links.new(vector, normal.inputs["Normal"])
    _aov(scene, tree, "normal_direction", normal.outputs["Normal"], "COLOR")
    _aov(scene, tree, "normal_dot", normal.outputs["Dot"])
    unlinked = tree.nodes.new("ShaderNodeNormal")
    unlinked.outputs["Normal"].default_value = (-0.5, 0.2, 0.4)
    unlinked.inputs["Normal"].default_value = (0.6, -0.3, 0.5)
    _aov(scene, tree, "normal_dot_unlinked", unlinked.outputs["Dot"])
    return _against_cycles(scene, mat, tmp_path_factory.mktemp("vectors"))


@pytest.mark.parametrize("case", VECTOR_CASES)
def test_vector_nodes_match_cycles(vector_results, case):
    # measured: at most 1.9e-7
    _compare(vector_results, case, 1e-6, "<= 1.9e-7")
