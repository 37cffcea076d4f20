"""A graph's values in numpy (addon/materials/evaluate.py: what the Auto term set reads of a
procedural texture feeding a Principled input) against Cycles evaluating the same graph into AOVs:
procedurals (Noise, Voronoi, Wave, Gradient, Checker, White Noise, Magic, Brick, Gabor, Radial
Tiling) at Generated (a texture's unlinked Vector), Object and UV coordinates, through Mapping,
Vector Math, Math, Map Range, Color Ramp, the curves, Mix (every blend mode, a per-component
factor) and the legacy Mix, the colour converters (Hue/Saturation/Value, Invert, Gamma,
Bright/Contrast, Clamp, RGB to BW, Separate / Combine Color in HSV and HSL), Vector Rotate,
Normal and the implicit conversions. One Cycles render for every case.

The points are Cycles' own: its AOVs of Generated, Object and UV at each pixel centre."""

from __future__ import annotations

import bpy
import numpy as np
import pytest
import scenes
from test_material_nodes import SIZE, _aov, _combine, _node, _plane_scene, cycles_aovs_and_graph

from addon.blender import nodes as reader
from addon.materials import codegen, evaluate, graph
from addon.materials.graph import Ref

#: AOV -> (AOV type, the largest difference measured against Cycles)
#: (the twins equal Cycles bit for bit, or to an ulp; Mapping's rotation through float32 sin/cos)
MEASURED = {"noise": ("COLOR", 0.0), "ranged": ("VALUE", 1.4e-6), "ramp": ("COLOR", 6.0e-8),
            "mixed": ("COLOR", 1.5e-8), "math": ("VALUE", 6.0e-8), "white": ("VALUE", 0.0)}
#: The nodes added to the evaluator (``_more``), measured the same way: Magic, Brick, Radial
#: Tiling's segments equal; the rest an ulp or a few of the value (Cycles' CPU kernel fuses some
#: products, numpy does not; Gabor's and the HSV modes' float32 cos, sin, atan2; a division's
#: rounding: Dodge's 1.8e-6 at a value near 1, Divide's 7.7e-6 at a value of 539). Blender 4.5
#: has no Radial Tiling, 4.2 no Gabor (nor Vector Math's Power and Sign): their cases are not
#: made. 4.2's Magic divides where 4.5 and 5.0 multiply by the reciprocal, as the evaluator (an ulp).
RECIPROCAL = bpy.app.version >= (4, 5, 0)
MEASURED.update({
    "magic": ("COLOR", 0.0), "magic_fac": ("VALUE", 0.0 if RECIPROCAL else 1.2e-7), "brick": ("COLOR", 0.0),
    "brick_fac": ("VALUE", 0.0), "gabor_2d": ("VALUE", 9.0e-8), "gabor_3d_phase": ("VALUE", 5.4e-7),
    "gabor_3d_intensity": ("VALUE", 1.8e-7), "radial_coordinates": ("COLOR", 6.0e-8),
    "radial_id": ("VALUE", 0.0), "radial_width": ("VALUE", 0.0), "radial_rotation": ("VALUE", 0.0),
    "vector_components": ("COLOR", 1.2e-7), "mixrgb_overlay": ("COLOR", 2.4e-7),
    "mixrgb_dodge": ("COLOR", 1.8e-6), "rgb_curves": ("COLOR", 1.2e-7), "vector_curves": ("COLOR", 6.0e-8),
    "float_curve": ("VALUE", 6.0e-8), "hsv": ("COLOR", 5.4e-7), "invert": ("COLOR", 6.0e-8),
    "gamma": ("COLOR", 2.4e-7), "bright_contrast": ("COLOR", 1.2e-7), "clamp_minmax": ("VALUE", 6.0e-8),
    "clamp_range": ("VALUE", 6.0e-8), "bw": ("VALUE", 9.5e-7), "separate_hsv": ("VALUE", 1.2e-7),
    "separate_hsl": ("VALUE", 7.2e-7), "combine_hsv": ("COLOR", 6.0e-8), "combine_hsl": ("COLOR", 1.8e-7),
    "rotate_axis": ("COLOR", 1.2e-7), "rotate_euler_inverse": ("COLOR", 6.0e-8),
    "rotate_x": ("COLOR", 1.4e-7), "normal_dot": ("VALUE", 0.0), "range_stepped": ("VALUE", 0.0),
    "range_smoothstep": ("VALUE", 1.8e-7), "range_smootherstep": ("VALUE", 1.3e-6),
    "range_vector": ("COLOR", 0.0), "range_vector_smooth": ("COLOR", 0.0),
    "mapping_normal": ("COLOR", 1.8e-7),
})
#: Every colour blend mode of the Mix node (its factor clamped, the default)
BLEND_MODES = ("DARKEN", "MULTIPLY", "BURN", "LIGHTEN", "SCREEN", "DODGE", "ADD", "OVERLAY", "SOFT_LIGHT",
               "LINEAR_LIGHT", "DIFFERENCE", "EXCLUSION", "SUBTRACT", "DIVIDE", "HUE", "SATURATION", "COLOR",
               "VALUE")
BLEND_MEASURED = (1.2e-7, 2.4e-7, 1.2e-7, 1.2e-7, 1.5e-7, 1.8e-6, 2.4e-7, 2.4e-7, 2.4e-7, 4.8e-7, 1.2e-7,
                  2.2e-7, 1.8e-7, 7.7e-6, 3.9e-7, 4.2e-7, 5.4e-7, 4.2e-7)
MEASURED.update({f"blend_{mode.lower()}": ("COLOR", m) for mode, m in zip(BLEND_MODES, BLEND_MEASURED)})
#: Every Math and Vector Math operation: an ulp or a few of the value (Cycles' kernel fuses the
#: products making a and b, numpy does not: a quotient, a power or a logarithm of a divisor or
#: base near 0 or 1 grows that ulp: Divide's 9.9e-5 of values spanning 111, Logarithm's 6.3e-4 of 174)
MATH_MEASURED = {
    "ADD": 4.8e-07, "SUBTRACT": 4.8e-07, "MULTIPLY": 9.6e-07, "DIVIDE": 9.9e-05, "MULTIPLY_ADD": 1.4e-06,
    "POWER": 7.7e-05, "LOGARITHM": 0.00063, "SQRT": 0.0, "INVERSE_SQRT": 0.0, "ABSOLUTE": 0.0,
    "EXPONENT": 3.8e-06, "MINIMUM": 2.4e-07, "MAXIMUM": 2.4e-07, "LESS_THAN": 0.0, "GREATER_THAN": 0.0,
    "SIGN": 0.0, "COMPARE": 0.0, "SMOOTH_MIN": 2.4e-07, "SMOOTH_MAX": 2.4e-07, "ROUND": 0.0, "FLOOR": 0.0,
    "CEIL": 0.0, "TRUNC": 0.0, "FRACT": 0.0, "MODULO": 6.7e-06, "FLOORED_MODULO": 6.7e-06, "WRAP": 6.5e-06,
    "SNAP": 6.7e-06, "PINGPONG": 6.9e-06, "SINE": 6e-08, "COSINE": 6e-08, "TANGENT": 3.8e-06,
    "ARCSINE": 6e-08, "ARCCOSINE": 2.4e-07, "ARCTANGENT": 1.2e-07, "ARCTAN2": 7.2e-07, "SINH": 1.9e-06,
    "COSH": 3.8e-06, "TANH": 6e-08, "RADIANS": 0.0, "DEGREES": 1.6e-05}
MEASURED.update({f"math_{op.lower()}": ("VALUE", m) for op, m in MATH_MEASURED.items()})
VECTOR_MATH_MEASURED = {
    "ADD": 2.4e-07, "SUBTRACT": 1.2e-07, "MULTIPLY": 2.4e-07, "DIVIDE": 1.6e-05, "MULTIPLY_ADD": 2.4e-07,
    "CROSS_PRODUCT": 2.4e-07, "PROJECT": 3e-07, "REFLECT": 8.4e-07, "REFRACT": 9.6e-07, "FACEFORWARD": 0.0,
    "DOT_PRODUCT": 2.4e-07, "DISTANCE": 2.4e-07, "LENGTH": 0.0, "SCALE": 2.4e-07, "NORMALIZE": 6e-08,
    "ABSOLUTE": 0.0, "POWER": 1.2e-07, "SIGN": 0.0, "MINIMUM": 1.2e-07, "MAXIMUM": 1.2e-07, "FLOOR": 0.0,
    "CEIL": 0.0, "FRACTION": 0.0, "MODULO": 2.1e-07, "WRAP": 1.6e-06, "SNAP": 2.4e-07, "SINE": 6e-08,
    "COSINE": 6e-08, "TANGENT": 9.6e-07}
MEASURED.update({f"vmath_{op.lower()}": ("VALUE" if op in codegen.VECTOR_MATH_VALUES else "COLOR", m)
                 for op, m in VECTOR_MATH_MEASURED.items()})


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
    _more(scene, tree, coord, noise)


def _math(tree, socket, scale, offset):
    """scale x socket + offset (a Math node, itself evaluated)."""
    return _node(tree, "ShaderNodeMath", {"Value": socket, "Value_001": scale, "Value_002": offset}, "Value",
                 operation="MULTIPLY_ADD")


def _more(scene, tree, coord, noise):
    """The nodes added to the evaluator. Their inputs from the UV: u through a Gradient Texture
    (a procedural: u itself on [0, 1]), v through Separate XYZ; colours A = (2u - 0.5, 1.5v, 0.3),
    B = (0.8 - v, 1.2u - 0.1, 0.6) and the factor 1.4u - 0.2 reach beyond [0, 1], as
    tests/test_material_nodes.py's Mix cases."""
    gradient = _node(tree, "ShaderNodeTexGradient", {"Vector": coord.outputs["UV"]}, "Fac")
    v = _node(tree, "ShaderNodeSeparateXYZ", {"Vector": coord.outputs["UV"]}, "Y")
    color_a = _combine(tree, _math(tree, gradient, 2.0, -0.5), _math(tree, v, 1.5, 0.0), 0.3)
    color_b = _combine(tree, _math(tree, v, -1.0, 0.8), _math(tree, gradient, 1.2, -0.1), 0.6)
    fac = _math(tree, gradient, 1.4, -0.2)
    # the textures
    magic = tree.nodes.new("ShaderNodeTexMagic")
    magic.turbulence_depth = 3
    magic.inputs["Scale"].default_value, magic.inputs["Distortion"].default_value = 2.3, 1.4
    tree.links.new(coord.outputs["Object"], magic.inputs["Vector"])
    _aov(scene, tree, "magic", magic.outputs["Color"], "COLOR")
    _aov(scene, tree, "magic_fac", magic.outputs["Fac"])
    bricks = {"Vector": coord.outputs["Object"], "Color1": noise.outputs["Color"], "Scale": 3.1,
              "Mortar Smooth": 0.3, "Bias": -0.2, "Brick Width": 0.37, "Row Height": 0.21}  # Color1 varies
    brick = _node(tree, "ShaderNodeTexBrick", bricks, "Color", offset=0.3, offset_frequency=3, squash=1.7,
                  squash_frequency=2).node
    _aov(scene, tree, "brick", brick.outputs["Color"], "COLOR")
    _aov(scene, tree, "brick_fac", brick.outputs["Fac"])
    if hasattr(bpy.types, "ShaderNodeTexGabor"):  # (Blender 4.3 on)
        plane = _node(tree, "ShaderNodeTexGabor", {"Scale": 4.0, "Anisotropy": 0.5, "Orientation 2D": 0.6},
                      "Value")
        _aov(scene, tree, "gabor_2d", plane)
        gabor = _node(tree, "ShaderNodeTexGabor", {"Vector": coord.outputs["Object"], "Scale": 3.0,
                                                   "Orientation 3D": (0.3, 0.5, 0.8)}, "Phase",
                      gabor_type="3D").node
        _aov(scene, tree, "gabor_3d_phase", gabor.outputs["Phase"])
        _aov(scene, tree, "gabor_3d_intensity", gabor.outputs["Intensity"])
    if hasattr(bpy.types, "ShaderNodeRadialTiling"):  # (Blender 5)
        centred = _node(tree, "ShaderNodeMapping", {"Vector": coord.outputs["UV"], "Scale": (2.0, 2.0, 1.0),
                                                    "Location": (-1.0, -1.0, 0.0)}, "Vector")
        radial = _node(tree, "ShaderNodeRadialTiling", {"Vector": centred, "Sides": 5.4, "Roundness": 0.3},
                       "Segment Coordinates", normalize=True).node
        _aov(scene, tree, "radial_coordinates", radial.outputs["Segment Coordinates"], "COLOR")
        for name in ("ID", "Width", "Rotation"):
            _aov(scene, tree, f"radial_{name.lower()}", radial.outputs[f"Segment {name}"])
    # Mix: every blend mode, a factor per component, the legacy Mix
    for mode in BLEND_MODES:
        out = _node(tree, "ShaderNodeMix", {"Factor_Float": fac, "A_Color": color_a, "B_Color": color_b},
                    "Result_Color", data_type="RGBA", blend_type=mode)
        _aov(scene, tree, f"blend_{mode.lower()}", out, "COLOR")
    factors = _combine(tree, fac, _math(tree, v, 1.2, -0.1), 0.5)
    out = _node(tree, "ShaderNodeMix", {"Factor_Vector": factors, "A_Vector": color_a, "B_Vector": color_b},
                "Result_Vector", data_type="VECTOR", factor_mode="NON_UNIFORM")
    _aov(scene, tree, "vector_components", out, "COLOR")
    for mode, clamp in (("OVERLAY", False), ("DODGE", True)):
        out = _node(tree, "ShaderNodeMixRGB", {"Fac": fac, "Color1": color_a, "Color2": color_b}, "Color",
                    blend_type=mode, use_clamp=clamp)
        _aov(scene, tree, f"mixrgb_{mode.lower()}", out, "COLOR")
    # curves (a bent curve each; Vector Curves extrapolated past their range)
    rgb = _node(tree, "ShaderNodeRGBCurve", {"Fac": 0.9, "Color": color_a}, "Color").node
    rgb.mapping.curves[3].points.new(0.4, 0.7)
    rgb.mapping.curves[0].points.new(0.6, 0.2)
    _aov(scene, tree, "rgb_curves", rgb.outputs["Color"], "COLOR")
    vector = _node(tree, "ShaderNodeVectorCurve", {"Vector": color_a}, "Vector").node
    vector.mapping.curves[1].points.new(0.3, 0.6)
    vector.mapping.extend = "EXTRAPOLATED"
    _aov(scene, tree, "vector_curves", vector.outputs["Vector"], "COLOR")
    curve = _node(tree, "ShaderNodeFloatCurve", {"Value": gradient}, "Value").node
    curve.mapping.curves[0].points.new(0.3, 0.8)
    _aov(scene, tree, "float_curve", curve.outputs["Value"])
    # the colour converters
    converters = {
        "hsv": ("ShaderNodeHueSaturation", {"Hue": 0.3, "Saturation": 1.4, "Value": 0.9, "Fac": 0.8,
                                            "Color": color_a}, "Color", {}),
        "invert": ("ShaderNodeInvert", {"Fac": 0.7, "Color": color_a}, "Color", {}),
        "gamma": ("ShaderNodeGamma", {"Color": color_a, "Gamma": 2.2}, "Color", {}),
        "bright_contrast": ("ShaderNodeBrightContrast", {"Color": color_a, "Bright": 0.1, "Contrast": 0.4},
                            "Color", {}),
        "clamp_minmax": ("ShaderNodeClamp", {"Value": fac, "Min": 0.1, "Max": 0.7}, "Result", {}),
        "clamp_range": ("ShaderNodeClamp", {"Value": fac, "Min": 0.8, "Max": 0.2}, "Result",
                        {"clamp_type": "RANGE"}),
        "bw": ("ShaderNodeRGBToBW", {"Color": color_a}, "Val", {}),
        "separate_hsv": ("ShaderNodeSeparateColor", {"Color": color_b}, "Red", {"mode": "HSV"}),
        "separate_hsl": ("ShaderNodeSeparateColor", {"Color": color_b}, "Green", {"mode": "HSL"}),
        "combine_hsv": ("ShaderNodeCombineColor", {"Red": gradient, "Green": v, "Blue": 0.7}, "Color",
                        {"mode": "HSV"}),
        "combine_hsl": ("ShaderNodeCombineColor", {"Red": gradient, "Green": v, "Blue": 0.4}, "Color",
                        {"mode": "HSL"}),
        "rotate_axis": ("ShaderNodeVectorRotate", {"Vector": color_a, "Center": (0.1, 0.2, 0.0),
                                                   "Axis": (0.3, 0.4, 0.8), "Angle": 0.9}, "Vector", {}),
        "rotate_euler_inverse": ("ShaderNodeVectorRotate", {"Vector": color_a, "Rotation": (0.4, -0.3, 0.7)},
                                 "Vector", {"rotation_type": "EULER_XYZ", "invert": True}),
        "rotate_x": ("ShaderNodeVectorRotate", {"Vector": color_b, "Angle": fac}, "Vector",
                     {"rotation_type": "X_AXIS"}),
        "normal_dot": ("ShaderNodeNormal", {"Normal": color_a}, "Dot", {}),
        "range_stepped": ("ShaderNodeMapRange", {"Value": fac, "From Min": 0.1, "From Max": 0.9,
                                                 "To Min": 0.2, "To Max": 0.8, "Steps": 4.0}, "Result",
                          {"interpolation_type": "STEPPED"}),
        "range_smoothstep": ("ShaderNodeMapRange", {"Value": fac, "From Min": 0.9, "From Max": 0.1}, "Result",
                             {"interpolation_type": "SMOOTHSTEP"}),
        "range_smootherstep": ("ShaderNodeMapRange", {"Value": fac, "From Min": 0.1, "From Max": 0.9,
                                                      "To Min": -0.5}, "Result",
                               {"interpolation_type": "SMOOTHERSTEP"}),
        "range_vector": ("ShaderNodeMapRange", {"Vector": color_a, "From_Min_FLOAT3": (0.1, -0.2, 0.0),
                                                "To_Max_FLOAT3": (2.0, 0.5, 1.0)}, "Vector",
                         {"data_type": "FLOAT_VECTOR", "clamp": True}),
        "range_vector_smooth": ("ShaderNodeMapRange", {"Vector": color_a}, "Vector",
                                {"data_type": "FLOAT_VECTOR", "interpolation_type": "SMOOTHSTEP"}),
        "mapping_normal": ("ShaderNodeMapping", {"Vector": color_a, "Rotation": (0.3, -0.5, 0.9),
                                                 "Scale": (2.0, 0.5, 1.5)}, "Vector",
                           {"vector_type": "NORMAL"}),
    }
    for name, (kind, inputs, output, props) in converters.items():
        _aov(scene, tree, name, _node(tree, kind, inputs, output, **props), MEASURED[name][0])
    # every Math and Vector Math operation: a = 8u - 3.9, b = 6v - 2.93, c = 0.7 (their zeros, and
    # a = b, between pixel centres: Cycles' kernel fuses their products, numpy does not, and a or b
    # near 0 would grow that ulp without bound in a quotient or flip a comparison); vectors A, B,
    # and C = (1.4u - 0.2, 0.5, -0.3), scale 1.4u - 0.2
    a, b = _math(tree, gradient, 8.0, -3.9), _math(tree, v, 6.0, -2.93)
    for op in codegen.MATH_OPERATIONS:
        _aov(scene, tree, f"math_{op.lower()}", _node(tree, "ShaderNodeMath", {"Value": a, "Value_001": b,
                                                                                "Value_002": 0.7}, "Value",
                                                      operation=op))
    vector_c = _combine(tree, fac, 0.5, -0.3)
    known = bpy.types.ShaderNodeVectorMath.bl_rna.properties["operation"].enum_items.keys()
    for op in (op for op in codegen.VECTOR_MATH_OPERATIONS if op in known):  # (4.2: no Power, Sign)
        value = op in codegen.VECTOR_MATH_VALUES
        inputs = {"Vector": color_a, "Vector_001": color_b, "Vector_002": vector_c, "Scale": fac}
        out = _node(tree, "ShaderNodeVectorMath", inputs, "Value" if value else "Vector", operation=op)
        _aov(scene, tree, f"vmath_{op.lower()}", out, "VALUE" if value else "COLOR")


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
    if name not in results:
        pytest.skip(f"{name}: a node this Blender has not")
    ours, cycles = results[name]
    worst = float(np.abs(ours - cycles).max())
    measured = MEASURED[name][1]
    print(f"{name}: {worst:.3g} (spread {np.ptp(cycles):.3g})")
    assert len(ours) > 0.9 * SIZE * SIZE and np.ptp(cycles) > 0.1, (len(ours), np.ptp(cycles))
    # (a measured 0: a float step of the value allowed)
    assert worst <= 3 * measured + 1e-7, f"{name}: largest difference {worst:.3g} (measured {measured:.2g})"


def test_what_cannot_be_evaluated_is_said():
    """A graph reading a node the evaluator has not (a Blackbody fed by a Noise Texture here), or
    none that varies per point, is not evaluable, and one reading an output it has not (Texture
    Coordinate's Normal) has no values: its input keeps its socket's value in the prediction."""
    scene, mat, tree, _, _ = _plane_scene()
    noise = tree.nodes.new("ShaderNodeTexNoise")
    kelvin = _node(tree, "ShaderNodeMapRange", {"Value": noise.outputs["Fac"], "To Min": 1000.0,
                                                "To Max": 8000.0}, "Result")
    blackbody = _node(tree, "ShaderNodeBlackbody", {"Temperature": kelvin}, "Color")
    value = tree.nodes.new("ShaderNodeValue")
    _aov(scene, tree, "blackbody", blackbody, "COLOR")
    _aov(scene, tree, "ranged", kelvin)
    _aov(scene, tree, "value", value.outputs["Value"])
    flat = graph.flatten(*reader.read_material(mat, "ALL"))
    aovs = {n.props["aov_name"]: n for n in flat.nodes.values() if n.kind == "ShaderNodeOutputAOV"}
    sources = {name: aovs[name].inputs["Color" if name == "blackbody" else "Value"].source
               for name in ("blackbody", "ranged", "value")}
    assert evaluate.evaluable(flat, sources["ranged"])  # (what feeds the Blackbody is)
    assert not evaluate.evaluable(flat, sources["blackbody"])
    assert not evaluate.evaluable(flat, sources["value"])
    # a texture at Texture Coordinate's Normal (not among the points' coordinates): no values
    coord = tree.nodes.new("ShaderNodeTexCoord")
    bent = _node(tree, "ShaderNodeTexNoise", {"Vector": coord.outputs["Normal"]}, "Fac")
    _aov(scene, tree, "bent", bent)
    flat = graph.flatten(*reader.read_material(mat, "ALL"))
    source = next(n for n in flat.nodes.values() if n.props.get("aov_name") == "bent").inputs["Value"].source
    points = evaluate.Points(*(np.zeros((4, 3), np.float32) for _ in range(3)))
    assert evaluate.evaluate(flat, source, points) is None


def test_auto_reads_the_values_of_newly_evaluable_nodes():
    """A Principled BSDF whose Base Color comes from a Magic Texture through Hue/Saturation/Value
    and whose Roughness from a Brick Texture through a Float Curve (nodes the evaluator once did
    not have: their inputs then kept their sockets' values, one colour and one roughness at every
    point) is predicted from the values its graph gives at each point."""
    from addon.blender import extract
    from addon.plan import auto_terms

    scene, mat, tree, _, _ = _plane_scene()
    scenes.light(scene, "SUN", energy=2.0)
    bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
    output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    tree.links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    magic = tree.nodes.new("ShaderNodeTexMagic")
    tinted = _node(tree, "ShaderNodeHueSaturation", {"Color": magic.outputs["Color"], "Hue": 0.2}, "Color")
    tree.links.new(tinted, bsdf.inputs["Base Color"])
    brick = tree.nodes.new("ShaderNodeTexBrick")
    rough = _node(tree, "ShaderNodeFloatCurve", {"Value": brick.outputs["Fac"]}, "Value")
    tree.links.new(rough, bsdf.inputs["Roughness"])
    bpy.context.view_layer.update()
    snap = extract.snapshot(bpy.context.evaluated_depsgraph_get())
    assert {entry[0] for entry in snap.materials[mat.name].graph.procedural} == {"base_color", "roughness"}
    material = auto_terms.material_samples(snap, mat.name).material
    base, roughness = np.asarray(material.base_color), np.asarray(material.roughness)
    print(f"base colour spread {np.ptp(base, axis=0)}, roughness spread {np.ptp(roughness):.3g}")
    assert base.ndim == 2 and np.all(np.ptp(base, axis=0) > 0.2), np.ptp(base, axis=0)
    assert roughness.ndim == 1 and np.ptp(roughness) > 0.2, np.ptp(roughness)
