"""A compiled graph's values at given points, in numpy: what the Auto term set's prediction
(``plan/auto_terms.py``) reads where a procedural texture, not an image, feeds a Principled BSDF's
input. Each node is evaluated as its GLSL (``codegen.EMITTERS``) computes it, through the numpy
twins of ``addon/reference/`` (noise.py, voronoi.py, wave.py, patterns.py, gabor.py, hashing.py)
for the procedurals, color.py for the blend modes, colour spaces and colour converters, and plain
numpy for the rest (Math, Vector Math, the curves' tables ...), on float32 as the GPU; a graph
holding any other node (Blackbody, Wavelength ...) is not evaluated (``evaluable`` says so, and
its input keeps its socket's value). Pure numpy: no ``bpy``, no ``gpu``.

The points come as their coordinates: ``Point.generated`` (Generated: the object's texture space,
what a texture node reads where its Vector is unlinked), ``Point.object`` and ``Point.uv``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..reference import color, gabor, hashing, noise, patterns, voronoi, wave
from .graph import CONVERT, Const, FlatGraph, FlatNode, Ref

F32 = np.float32


@dataclass
class Points:
    """Coordinates of N points, each (N, 3) float32."""

    generated: np.ndarray
    object: np.ndarray
    uv: np.ndarray

    def __len__(self) -> int:
        return len(self.generated)


# --- sockets as arrays: a float (N,), a vector (N, 3), a colour (N, 4) ---------------------------

def _constant(value, kind: str, n: int) -> np.ndarray:
    """A socket's value at every point (a value not read: 0)."""
    value = 0.0 if value is None else value
    if kind == "RGBA":
        v = np.asarray(value, F32).reshape(-1)
        v = np.concatenate([v, np.ones(4, F32)])[:4] if len(v) < 4 else v[:4]
        return np.broadcast_to(v, (n, 4)).astype(F32)
    if kind == "VECTOR":
        return np.broadcast_to(np.asarray(value, F32).reshape(-1)[:3], (n, 3)).astype(F32)
    return np.full(n, F32(value), F32)


def _mix(a, b, t):
    return (F32(1) - t) * a + t * b


def _euler_rows(e: np.ndarray) -> np.ndarray:
    """Cycles' euler_to_transform's rotation (glsl/node_vector.glsl's euler_rows), (N, 3, 3)."""
    cx, cy, cz = np.cos(e[:, 0]), np.cos(e[:, 1]), np.cos(e[:, 2])
    sx, sy, sz = np.sin(e[:, 0]), np.sin(e[:, 1]), np.sin(e[:, 2])
    return np.stack([np.stack([cy * cz, sy * sx * cz - cx * sz, sy * cx * cz + sx * sz], -1),
                     np.stack([cy * sz, sy * sx * sz + cx * cz, sy * cx * sz - sx * cz], -1),
                     np.stack([-sy, cy * sx, cy * cx], -1)], 1).astype(F32)


def _safe_divide(a, b):
    with np.errstate(divide="ignore", invalid="ignore"):  # (0 where the divisor is 0, as Cycles')
        return np.where(b != 0, a / np.where(b != 0, b, 1), F32(0)).astype(F32)


# --- the nodes: each (graph, node, its inputs by identifier, points) -> {output: array} ------------

def _texcoord(node, inputs, points):
    if node.props.get("from_instancer") or node.props.get("object_matrix"):
        return None  # (an instancer's or another object's coordinates: not at hand here)
    return {"Generated": points.generated, "Object": points.object, "UV": points.uv}


def _mapping(node, inputs, points):
    kind = node.props.get("vector_type", "POINT")
    v, rotation, scale = inputs["Vector"], inputs["Rotation"], inputs["Scale"]
    rows = _euler_rows(rotation)
    if kind == "POINT":
        return {"Vector": np.einsum("nij,nj->ni", rows, v * scale) + inputs["Location"]}
    if kind == "TEXTURE":
        return {"Vector": _safe_divide(np.einsum("nji,nj->ni", rows, v - inputs["Location"]), scale)}
    if kind == "VECTOR":
        return {"Vector": np.einsum("nij,nj->ni", rows, v * scale)}
    if kind == "NORMAL":  # (node_mapping_normal: the inverse scale, rotated, made unit)
        n = np.einsum("nij,nj->ni", rows, _safe_divide(v, scale))
        length = np.linalg.norm(n, axis=1, keepdims=True)
        return {"Vector": np.where(length != 0, n / np.where(length != 0, length, F32(1)), n).astype(F32)}
    return None


def _fmod(a, b):
    """node_math.glsl's math_fmod (C's fmodf as Cycles 5 computes it): a - b trunc(a / b)."""
    return a - b * np.trunc(a / b)


def _compatible_pow(x, y):
    """math_compatible_pow: x^0 = 1, a negative base to an integer power signed by its parity, 0^y = 0."""
    p = np.power(np.abs(x), y)
    odd = np.fmod(-y, F32(2)) != 0
    return np.where(y == 0, F32(1), np.where(x < 0, np.where(odd, -p, p), np.where(x == 0, F32(0), p)))


def _smooth_min(a, b, c):
    """math_smooth_min (Cycles' smoothminf): min(a, b) less h^3 c / 6, h = max(c - |a - b|, 0) / c."""
    h = np.maximum(c - np.abs(a - b), F32(0)) / np.where(c != 0, c, F32(1))
    return np.where(c != 0, np.minimum(a, b) - h * h * h * c * (F32(1) / F32(6)), np.minimum(a, b))


def _wrap(a, b, c):
    """math_wrap (Cycles' wrapf(a, max b, min c)): c where the range is empty."""
    span = b - c
    return np.where(span != 0, a - span * np.floor((a - c) / np.where(span != 0, span, F32(1))), c)


def _pingpong(a, b):
    """math_pingpong (Cycles' pingpongf): 0 where the length is 0."""
    x = (a - b) / (b * F32(2))
    return np.where(b != 0, np.abs((x - np.floor(x)) * b * F32(2) - b), F32(0))


def _asin_acos(a, arcsine: bool):
    """math_arcsine, math_arccosine: the argument clamped to [-1, 1], through atan2."""
    x = np.clip(a, F32(-1), F32(1))
    root = np.sqrt(np.maximum(F32(1) - x * x, F32(0)))
    return np.arctan2(x, root) if arcsine else np.arctan2(root, x)


#: The Math node's operations (glsl/node_math.glsl's math_*: Cycles' svm_math), each f(a, b, c).
_MATH = {
    "ADD": lambda a, b, c: a + b, "SUBTRACT": lambda a, b, c: a - b, "MULTIPLY": lambda a, b, c: a * b,
    "DIVIDE": lambda a, b, c: _safe_divide(a, b), "MULTIPLY_ADD": lambda a, b, c: a * b + c,
    "POWER": lambda a, b, c: np.where((a < 0) & (b != np.trunc(b)), F32(0), _compatible_pow(a, b)),
    "LOGARITHM": lambda a, b, c: np.where((a <= 0) | (b <= 0), F32(0), _safe_divide(np.log(a), np.log(b))),
    "SQRT": lambda a, b, c: np.sqrt(np.maximum(a, F32(0))),
    "INVERSE_SQRT": lambda a, b, c: np.where(a > 0, F32(1) / np.sqrt(a), F32(0)),
    "ABSOLUTE": lambda a, b, c: np.abs(a), "EXPONENT": lambda a, b, c: np.exp(a),
    "MINIMUM": lambda a, b, c: np.minimum(a, b), "MAXIMUM": lambda a, b, c: np.maximum(a, b),
    "LESS_THAN": lambda a, b, c: (a < b).astype(F32), "GREATER_THAN": lambda a, b, c: (a > b).astype(F32),
    "SIGN": lambda a, b, c: np.sign(a),
    "COMPARE": lambda a, b, c: ((a == b) | (np.abs(a - b) <= np.maximum(c, F32(1.1920929e-7)))).astype(F32),
    "SMOOTH_MIN": _smooth_min, "SMOOTH_MAX": lambda a, b, c: -_smooth_min(-a, -b, c),
    "ROUND": lambda a, b, c: np.floor(a + F32(0.5)), "FLOOR": lambda a, b, c: np.floor(a),
    "CEIL": lambda a, b, c: np.ceil(a), "TRUNC": lambda a, b, c: np.trunc(a),
    "FRACT": lambda a, b, c: a - np.floor(a),
    "MODULO": lambda a, b, c: np.where(b != 0, _fmod(a, b), F32(0)),
    "FLOORED_MODULO": lambda a, b, c: np.where(b != 0, a - np.floor(a / b) * b, F32(0)),
    "WRAP": _wrap, "SNAP": lambda a, b, c: np.floor(_safe_divide(a, b)) * b,
    "PINGPONG": lambda a, b, c: _pingpong(a, b),
    "SINE": lambda a, b, c: np.sin(a), "COSINE": lambda a, b, c: np.cos(a),
    "TANGENT": lambda a, b, c: np.tan(a), "SINH": lambda a, b, c: np.sinh(a),
    "COSH": lambda a, b, c: np.cosh(a), "TANH": lambda a, b, c: np.tanh(a),
    "ARCSINE": lambda a, b, c: _asin_acos(a, True), "ARCCOSINE": lambda a, b, c: _asin_acos(a, False),
    "ARCTANGENT": lambda a, b, c: np.arctan(a),
    "ARCTAN2": lambda a, b, c: np.where((a == 0) & (b == 0), F32(0), np.arctan2(a, b)),
    "RADIANS": lambda a, b, c: a * F32(3.14159265358979 / 180.0),
    "DEGREES": lambda a, b, c: a * F32(180.0 / 3.14159265358979),
}


def _dot(a, b):
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def _normalize(a):
    """vmath_safe_normalize: a zero vector stays itself."""
    t = np.sqrt(_dot(a, a))[:, None]
    return np.where(t != 0, a / np.where(t != 0, t, F32(1)), a)


def _project(a, b):
    bb = _dot(b, b)[:, None]
    return np.where(bb != 0, b * (_dot(a, b)[:, None] / np.where(bb != 0, bb, F32(1))), F32(0))


def _reflect(a, b):
    n = _normalize(b)
    return a - F32(2) * n * _dot(a, n)[:, None]


def _refract(a, b, s):
    """vmath_refract: Snell's law for a unit incident a, the normal b, the index ratio s; 0 past
    the critical angle."""
    n, s = _normalize(b), s[:, None]
    d = _dot(n, a)[:, None]
    k = F32(1) - s * s * (F32(1) - d * d)
    return np.where(k < 0, F32(0), s * a - (s * d + np.sqrt(np.maximum(k, F32(0)))) * n)


def _each(op: str):
    """A Math operation per component (vmath_power, vmath_modulo, vmath_wrap ...)."""
    return lambda a, b, c, s: _MATH[op](a, b, c)


#: The Vector Math node's operations (glsl/node_vector_math.glsl's vmath_*: Cycles' svm_vector_math),
#: each f(a, b, c, scale); DOT_PRODUCT, DISTANCE and LENGTH give the Value, the others the Vector.
_VECTOR_MATH = {
    **{op: _each(op) for op in ("ADD", "SUBTRACT", "MULTIPLY", "DIVIDE", "MULTIPLY_ADD", "ABSOLUTE", "POWER",
                                "SIGN", "MINIMUM", "MAXIMUM", "FLOOR", "CEIL", "MODULO", "WRAP", "SNAP",
                                "SINE", "COSINE", "TANGENT")},
    "FRACTION": _each("FRACT"),
    "CROSS_PRODUCT": lambda a, b, c, s: np.cross(a, b), "PROJECT": lambda a, b, c, s: _project(a, b),
    "REFLECT": lambda a, b, c, s: _reflect(a, b), "REFRACT": lambda a, b, c, s: _refract(a, b, s),
    "FACEFORWARD": lambda a, b, c, s: np.where((_dot(c, b) < 0)[:, None], a, -a),
    "SCALE": lambda a, b, c, s: a * s[:, None], "NORMALIZE": lambda a, b, c, s: _normalize(a),
    "DOT_PRODUCT": lambda a, b, c, s: _dot(a, b), "DISTANCE": lambda a, b, c, s: np.sqrt(_dot(a - b, a - b)),
    "LENGTH": lambda a, b, c, s: np.sqrt(_dot(a, a)),
}


def _vector_math(node, inputs, points):
    op = node.props.get("operation")
    fn = _VECTOR_MATH.get(op)
    if fn is None:
        return None
    n = len(points)
    zero = np.zeros((n, 3), F32)
    a, b, c = (inputs.get(v, zero) for v in ("Vector", "Vector_001", "Vector_002"))
    value = np.asarray(fn(a, b, c, inputs.get("Scale", np.ones(n, F32))), F32)
    return {"Value": value} if op in ("DOT_PRODUCT", "DISTANCE", "LENGTH") else {"Vector": value}


def _math(node, inputs, points):
    fn = _MATH.get(node.props.get("operation"))
    if fn is None:
        return None
    zero = np.zeros(len(points), F32)
    value = fn(*(inputs.get(s, zero) for s in ("Value", "Value_001", "Value_002"))).astype(F32)
    return {"Value": np.clip(value, F32(0), F32(1)) if node.props.get("use_clamp") else value}


def _smoothstep(e0, e1, x):
    """node_converter.glsl's node_smoothstep (Cycles' smoothstep): 0 below e0, 1 from e1 on."""
    t = (x - e0) / np.where(e1 != e0, e1 - e0, F32(1))
    return np.where(x < e0, F32(0), np.where(x >= e1, F32(1), (F32(3) - F32(2) * t) * (t * t)))


def _smootherstep(e0, e1, x):
    """node_smootherstep (Cycles' smootherstep): the factor clamped to [0, 1], 0 where e0 = e1."""
    t = np.clip(_safe_divide(x - e0, e1 - e0), F32(0), F32(1))
    return t * t * t * (t * (t * F32(6) - F32(15)) + F32(10))


def _stepped(f, steps):
    """Map Range's Stepped factor: floor(f (steps + 1)) / steps, 0 without steps."""
    return np.where(steps > 0, np.floor(f * (steps + F32(1))) / np.where(steps > 0, steps, F32(1)), F32(0))


def _clamp_range(value, lo, hi):
    """clamp_range: to [lo, hi] in either order."""
    return np.clip(value, np.minimum(lo, hi), np.maximum(lo, hi))


def _map_range(node, inputs, points):
    """Map Range (glsl/node_converter.glsl's map_range_*, map_range_vector: Cycles' svm_node_map_range,
    svm_node_vector_map_range): Linear, Stepped, Smooth Step, Smoother Step on a float (0 where the
    source range is empty) or per component of a vector; Clamp after a linear or stepped mapping."""
    kind = node.props.get("interpolation_type", "LINEAR")
    if kind not in ("LINEAR", "STEPPED", "SMOOTHSTEP", "SMOOTHERSTEP"):
        return None
    clamp = node.props.get("clamp") and kind in ("LINEAR", "STEPPED")
    if node.props.get("data_type", "FLOAT") == "FLOAT_VECTOR":
        names = ("Vector", "From_Min_FLOAT3", "From_Max_FLOAT3", "To_Min_FLOAT3", "To_Max_FLOAT3")
        x, lo, hi, to_lo, to_hi = (inputs[s] for s in names)
        f = _safe_divide(x - lo, hi - lo)
        if kind == "STEPPED":
            f = _stepped(f, inputs.get("Steps_FLOAT3", np.zeros_like(x)))
        elif kind == "SMOOTHSTEP":
            f = np.clip(f, F32(0), F32(1))
            f = (F32(3) - F32(2) * f) * (f * f)
        elif kind == "SMOOTHERSTEP":
            f = _smootherstep(F32(0), F32(1), f)
        value = to_lo + f * (to_hi - to_lo)
        return {"Vector": (_clamp_range(value, to_lo, to_hi) if clamp else value).astype(F32)}
    x, lo, hi, to_lo, to_hi = (inputs[s] for s in ("Value", "From Min", "From Max", "To Min", "To Max"))
    if kind in ("LINEAR", "STEPPED"):
        f = _safe_divide(x - lo, hi - lo)
        f = _stepped(f, inputs.get("Steps", np.zeros_like(x))) if kind == "STEPPED" else f
    else:
        step = _smoothstep if kind == "SMOOTHSTEP" else _smootherstep
        f = np.where(lo > hi, F32(1) - step(hi, lo, x), step(lo, hi, x))
    value = np.where(hi != lo, to_lo + f * (to_hi - to_lo), F32(0))
    return {"Result": (_clamp_range(value, to_lo, to_hi) if clamp else value).astype(F32)}


def _mix_node(node, inputs, points):
    """The Mix node (glsl/node_mix.glsl; codegen._mix): floats and vectors interpolated (a vector
    by one factor or one per component), colours by their blend mode (reference/color.py)."""
    kind = node.props.get("data_type")
    uniform = node.props.get("factor_mode", "UNIFORM") == "UNIFORM" or kind != "VECTOR"
    fac = inputs["Factor_Float" if uniform else "Factor_Vector"]
    if node.props.get("clamp_factor", True):
        fac = np.clip(fac, F32(0), F32(1))
    if kind == "FLOAT":
        return {"Result_Float": _mix(inputs["A_Float"], inputs["B_Float"], fac)}
    if kind == "VECTOR":
        fac = fac[:, None] if uniform else fac  # (one factor, or one per component)
        return {"Result_Vector": _mix(inputs["A_Vector"], inputs["B_Vector"], fac)}
    if kind != "RGBA":
        return None
    return _blend(node.props.get("blend_type"), fac, inputs["A_Color"], inputs["B_Color"],
                  node.props.get("clamp_result"), "Result_Color")


def _blend(mode, fac, a, b, clamp_result, output: str):
    """Colour ``a`` blended with ``b`` (codegen._blend): the result clamped where asked, ``a``'s
    alpha kept; None for a mode not known."""
    if mode not in color.BLEND_MODES:
        return None
    rgb = color.blend(mode, fac, a[:, :3], b[:, :3])
    if clamp_result:
        rgb = np.clip(rgb, F32(0), F32(1))
    return {output: np.concatenate([rgb, a[:, 3:]], 1)}


def _mix_rgb(node, inputs, points):
    """The legacy Mix node (codegen._mix_rgb): its factor clamped to [0, 1], Color1's alpha kept."""
    fac = np.clip(inputs["Fac"], F32(0), F32(1))
    return _blend(node.props.get("blend_type"), fac, inputs["Color1"], inputs["Color2"],
                  node.props.get("use_clamp"), "Color")


def _lookup(table: np.ndarray, f: np.ndarray, interpolate: bool = True) -> np.ndarray:
    """glsl/node_ramp.glsl's ramp_lookup (Cycles' rgb_ramp_lookup) of ``table`` (K, C) at ``f``
    (N,): f clamped to [0, 1] (a NaN to 0, as the clamped index), (N, C)."""
    last = len(table) - 1
    f = np.clip(np.nan_to_num(f), F32(0), F32(1)) * F32(last)
    i = np.clip(f.astype(np.int64), 0, last)
    entry = table[i]
    if interpolate:
        t = (f - i.astype(F32))[:, None]
        entry = np.where(t > 0, (F32(1) - t) * entry + t * table[np.minimum(i + 1, last)], entry)
    return entry.astype(F32)


def _lookup_extrapolated(table: np.ndarray, f: np.ndarray) -> np.ndarray:
    """ramp_lookup_extrapolated: outside [0, 1] the line through the two end entries."""
    last = F32(len(table) - 1)
    below = table[0] + (table[0] - table[1]) * (-f)[:, None] * last
    above = table[-1] + (table[-1] - table[-2]) * (f - F32(1))[:, None] * last
    return np.where((f < 0)[:, None], below, np.where((f > 1)[:, None], above, _lookup(table, f))).astype(F32)


def _ramp(node, inputs, points):
    """Color Ramp: node_ramp_linear / _constant over the reader's table."""
    table = node.props.get("table")
    if table is None:
        return None
    entry = _lookup(np.asarray(table, F32).reshape(-1, 4), inputs["Fac"], node.props.get("interpolate", True))
    return {"Color": entry, "Alpha": entry[:, 3]}


def _curves(node, inputs, points):
    """RGB Curves, Vector Curves, Float Curve (glsl/node_ramp.glsl, Cycles' svm_node_curves and
    svm_node_curve): each component through its column of the reader's table over the curves' x
    range, extrapolated where the curve's Extend says so, blended with the input by the factor."""
    table, bounds = node.props.get("table"), node.props.get("range")
    if table is None or bounds is None:
        return None
    lo, hi = (F32(b) for b in bounds)
    extrapolate = node.props.get("extrapolate")

    def through(values, column):
        rel = (values - lo) / (hi - lo)
        found = _lookup_extrapolated(column, rel) if extrapolate else _lookup(column, rel)
        return found

    table = np.asarray(table, F32)
    if node.kind == "ShaderNodeFloatCurve":
        fac, value = inputs["Factor"], inputs["Value"]
        return {"Value": (F32(1) - fac) * value + fac * through(value, table[:, :1])[:, 0]}
    socket, output = ("Color", "Color") if node.kind == "ShaderNodeRGBCurve" else ("Vector", "Vector")
    v, fac = inputs[socket], inputs["Fac"][:, None]
    curved = np.stack([through(v[:, k], table[:, k:k + 1])[:, 0] for k in range(3)], -1)
    rgb = (F32(1) - fac) * v[:, :3] + fac * curved
    return {output: np.concatenate([rgb, v[:, 3:]], 1) if socket == "Color" else rgb}


#: The colour spaces Separate / Combine Color read and write, each its pair of twins.
_SPACES = {"RGB": (lambda c: c, lambda c: c), "HSV": (color.rgb_to_hsv, color.hsv_to_rgb),
           "HSL": (color.rgb_to_hsl, color.hsl_to_rgb)}


def _separate_color(node, inputs, points, names=("Red", "Green", "Blue"), socket="Color", mode=None):
    space = _SPACES.get(mode or node.props.get("mode", "RGB"))
    if space is None:
        return None
    c = space[0](inputs[socket][:, :3])
    return {name: c[:, k] for k, name in enumerate(names)}


def _combine_color(node, inputs, points, names=("Red", "Green", "Blue"), output="Color", mode=None):
    space = _SPACES.get(mode or node.props.get("mode", "RGB"))
    if space is None:
        return None
    return {output: _colour(space[1](np.stack([inputs[s] for s in names], -1)))}


def _legacy(fn, mode, names, socket):
    """The legacy Separate / Combine RGB and HSV (Blender 4)."""
    return lambda node, inputs, points: fn(node, inputs, points, names, socket, mode)


def _clamp(node, inputs, points):
    """Clamp (node_converter.glsl's clamp_minmax, clamp_range: the bounds in either order)."""
    v, lo, hi = inputs["Value"], inputs["Min"], inputs["Max"]
    if node.props.get("clamp_type") == "RANGE":
        lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
    return {"Result": np.minimum(np.maximum(v, lo), hi)}


def _rgb_nodes(fn, names, output="Color"):
    """A colour converter of reference/color.py on its inputs ``names`` (the colour last or first
    as the twin takes it), the colour's alpha kept."""
    def node_fn(node, inputs, points):
        args = [inputs[s][:, :3] if s == "Color" else inputs[s] for s in names]
        return {output: np.concatenate([fn(*args), inputs["Color"][:, 3:]], 1)}
    return node_fn


def _rgb_to_bw(node, inputs, points, luma):
    """RGB to BW: the colour's luminance with the running Blender's weights (codegen._luminance)."""
    return {"Val": inputs["Color"][:, :3] @ np.asarray(luma, F32)}


def _rotate_around_axis(p, axis, angle):
    """glsl/node_vector.glsl's vector_rotate_around_axis (Cycles' rotate_around_axis): Rodrigues'
    matrix of a unit axis."""
    c, s = np.cos(angle), np.sin(angle)
    t = F32(1) - c
    x, y, z = axis[:, 0], axis[:, 1], axis[:, 2]
    px, py, pz = p[:, 0], p[:, 1], p[:, 2]
    return np.stack([(c + t * x * x) * px + (t * x * y - z * s) * py + (t * x * z + y * s) * pz,
                     (t * x * y + z * s) * px + (c + t * y * y) * py + (t * y * z - x * s) * pz,
                     (t * x * z - y * s) * px + (t * y * z + x * s) * py + (c + t * z * z) * pz], -1)


_AXES = {"X_AXIS": (1.0, 0.0, 0.0), "Y_AXIS": (0.0, 1.0, 0.0), "Z_AXIS": (0.0, 0.0, 1.0)}


def _vector_rotate(node, inputs, points):
    """Vector Rotate (codegen._vector_rotate; Cycles' svm_node_vector_rotate): about an axis (a zero
    axis leaves the vector) or by an Euler rotation, around Center; Invert the inverse."""
    kind, invert = node.props.get("rotation_type"), bool(node.props.get("invert"))
    v, center = inputs["Vector"], inputs["Center"]
    if kind == "EULER_XYZ":
        rows = _euler_rows(inputs["Rotation"])
        return {"Vector": np.einsum("nji,nj->ni" if invert else "nij,nj->ni", rows, v - center) + center}
    if kind == "AXIS_ANGLE":
        axis = inputs["Axis"]
    elif kind in _AXES:
        axis = _constant(_AXES[kind], "VECTOR", len(points))
    else:
        return None
    angle = -inputs["Angle"] if invert else inputs["Angle"]
    length = np.linalg.norm(axis, axis=1)
    unit = axis / np.where(length != 0, length, F32(1))[:, None]
    turned = _rotate_around_axis(v - center, unit, angle) + center
    return {"Vector": np.where((length != 0)[:, None], turned, v).astype(F32)}


def _normal(node, inputs, points):
    """The Normal node (glsl/node_vector.glsl's node_normal_direction, node_normal_dot)."""
    direction = np.asarray(node.values.get("Normal", (0.0, 0.0, 1.0)), F32)
    direction = direction / np.sqrt(np.dot(direction, direction))
    n = inputs["Normal"]
    unit = n / np.linalg.norm(n, axis=1, keepdims=True)
    return {"Normal": _constant(direction, "VECTOR", len(points)), "Dot": unit @ direction}


def _separate_xyz(node, inputs, points):
    v = inputs["Vector"]
    return {"X": v[:, 0], "Y": v[:, 1], "Z": v[:, 2]}


def _combine_xyz(node, inputs, points):
    return {"Vector": np.stack([inputs["X"], inputs["Y"], inputs["Z"]], -1)}


def _convert(node, inputs, points, luma):
    kinds = {"INT": "VALUE", "BOOLEAN": "VALUE"}
    f, t = (kinds.get(node.props[k], node.props[k]) for k in ("from", "to"))
    v = inputs["Value"]
    if f == t:
        return {"Value": v}
    one = np.ones((len(v), 1), F32)
    table = {("RGBA", "VALUE"): lambda: v[:, :3] @ np.asarray(luma, F32),
             ("VECTOR", "VALUE"): lambda: (v[:, 0] + v[:, 1] + v[:, 2]) * F32(1.0 / 3.0),
             ("VALUE", "RGBA"): lambda: np.concatenate([np.repeat(v[:, None], 3, 1), one], 1),
             ("VALUE", "VECTOR"): lambda: np.repeat(v[:, None], 3, 1),
             ("RGBA", "VECTOR"): lambda: v[:, :3], ("VECTOR", "RGBA"): lambda: np.concatenate([v, one], 1)}
    found = table.get((f, t))
    return {"Value": found().astype(F32)} if found is not None else None


def _vector(node, inputs, points):
    """A texture node's Vector: what is linked to it, else Generated (textures.vector); None where
    its own Texture Mapping is set (not compiled)."""
    if node.props.get("texture_mapping"):
        return None
    spec = node.inputs.get("Vector")
    return inputs["Vector"] if spec is not None and isinstance(spec.source, Ref) else points.generated


def _scalar(node, inputs, name: str, n: int) -> np.ndarray:
    return inputs[name] if name in inputs else np.zeros(n, F32)


def _uniform(inputs, names) -> dict | None:
    """The procedurals' settings as the twins take them, scalars: None where one varies per point
    (the twins take one value per call)."""
    out = {}
    for name in names:
        value = inputs[name]
        if np.any(np.ptp(value, axis=0) != 0):
            return None
        out[name] = value[0]  # (a float, or a vector's three)
    return out


def _colour(rgb: np.ndarray) -> np.ndarray:
    return np.concatenate([rgb, np.ones((len(rgb), 1), F32)], 1).astype(F32)


def _noise(node, inputs, points):
    props, n = node.props, len(points)
    co = _vector(node, inputs, points)
    dims = int(props.get("noise_dimensions", "3D")[0])
    names = ["Scale", "Detail", "Roughness", "Lacunarity", "Distortion"] + \
        [s for s in ("Offset", "Gain") if s in inputs]
    settings = _uniform(inputs, names)
    if co is None or settings is None:
        return None
    fac, color = noise.noise_texture(dims, props.get("noise_type", "FBM"), co, _scalar(node, inputs, "W", n),
                                     **{k.lower(): v for k, v in settings.items()},
                                     normalize=bool(props.get("normalize", True)))
    return {"Fac": fac.astype(F32), "Color": _colour(color)}


def _voronoi(node, inputs, points):
    props, n = node.props, len(points)
    co = _vector(node, inputs, points)
    names = [s for s in ("Scale", "Detail", "Roughness", "Lacunarity", "Smoothness", "Exponent", "Randomness")
             if s in inputs]
    settings = _uniform(inputs, names)
    if co is None or settings is None:
        return None
    out = voronoi.voronoi(int(props.get("voronoi_dimensions", "3D")[0]), props.get("feature", "F1"),
                          props.get("distance", "EUCLIDEAN"), co, _scalar(node, inputs, "W", n),
                          **{k.lower(): v for k, v in settings.items()},
                          normalize=bool(props.get("normalize")), cells=props.get("voronoi_cells", "INT"))
    return {"Distance": out["distance"], "Color": _colour(out["color"]), "Position": out["position"],
            "W": out["w"], "Radius": out["radius"]}


def _wave(node, inputs, points):
    props = node.props
    co = _vector(node, inputs, points)
    settings = _uniform(inputs, ("Scale", "Distortion", "Detail", "Detail Scale", "Detail Roughness",
                                 "Phase Offset"))
    if co is None or settings is None:
        return None
    kind = props.get("wave_type", "BANDS")
    direction = props.get("bands_direction" if kind == "BANDS" else "rings_direction", "X")
    fac = wave.wave(co, kind=kind, direction=direction, profile=props.get("wave_profile", "SIN"),
                    **{k.lower().replace(" ", "_"): v for k, v in settings.items()},
                    phase_rule=props.get("wave_phase", "RECIPROCAL")).astype(F32)
    return {"Fac": fac, "Color": _colour(np.repeat(fac[:, None], 3, 1))}


def _gradient(node, inputs, points):
    co = _vector(node, inputs, points)
    if co is None:
        return None
    fac = patterns.gradient(node.props.get("gradient_type", "LINEAR"), co).astype(F32)
    return {"Fac": fac, "Color": _colour(np.repeat(fac[:, None], 3, 1))}


def _checker(node, inputs, points):
    co = _vector(node, inputs, points)
    settings = _uniform(inputs, ("Scale",))
    if co is None or settings is None:
        return None
    fac = patterns.checker(co, settings["Scale"]).astype(F32)
    rgb = np.where(fac[:, None] == 1, inputs["Color1"][:, :3], inputs["Color2"][:, :3])
    return {"Fac": fac, "Color": _colour(rgb.astype(F32))}


def _white_noise(node, inputs, points):
    co = _vector(node, inputs, points)
    if co is None:
        return None
    dims = int(node.props.get("noise_dimensions", "3D")[0])
    value, color = hashing.white_noise(dims, co, _scalar(node, inputs, "W", len(points)))
    return {"Value": np.asarray(value, F32), "Color": _colour(np.asarray(color, F32))}


def _magic(node, inputs, points):
    """Magic Texture (textures._magic): reference/patterns.py's magic, Depth a setting."""
    co = _vector(node, inputs, points)
    settings = _uniform(inputs, ("Scale", "Distortion"))
    if co is None or settings is None:
        return None
    rgb, fac = patterns.magic(co, settings["Scale"], settings["Distortion"],
                              int(node.props.get("turbulence_depth", 2)))
    return {"Color": _colour(rgb), "Fac": fac}


def _brick(node, inputs, points):
    """Brick Texture (textures._brick): reference/patterns.py's brick; its colours may vary per
    point, its sizes are one value (as the twin takes them), offset and squash settings."""
    co = _vector(node, inputs, points)
    sizes = ("Scale", "Mortar Size", "Mortar Smooth", "Bias", "Brick Width", "Row Height")
    settings = _uniform(inputs, sizes)
    if co is None or settings is None:
        return None
    props = node.props
    rgb, fac = patterns.brick(co, inputs["Color1"], inputs["Color2"], inputs["Mortar"],
                              *(settings[s] for s in sizes), F32(props.get("offset", 0.5)),
                              int(props.get("offset_frequency", 2)), F32(props.get("squash", 1.0)),
                              int(props.get("squash_frequency", 2)))
    return {"Color": _colour(rgb), "Fac": fac}


def _gabor(node, inputs, points):
    """Gabor Texture (textures._gabor): reference/gabor.py's, 2D (an angle) or 3D (a direction)."""
    kind = node.props.get("gabor_type", "2D")
    orientation = f"Orientation {kind}"
    co = _vector(node, inputs, points)
    if kind not in ("2D", "3D") or orientation not in inputs or co is None:
        return None
    settings = _uniform(inputs, ("Scale", "Frequency", "Anisotropy", orientation))
    if settings is None:
        return None
    value, phase, intensity = gabor.gabor(kind, co, *settings.values())
    return {"Value": value, "Phase": phase, "Intensity": intensity}


def _radial_tiling(node, inputs, points):
    """Radial Tiling (textures._radial_tiling): reference/patterns.py's radial_tiling; its Vector
    unlinked is the socket's value (not a texture node)."""
    settings = _uniform(inputs, ("Sides", "Roundness"))
    if settings is None:
        return None
    coordinates, ids, width, rotation = patterns.radial_tiling(inputs["Vector"], settings["Sides"],
                                                               settings["Roundness"],
                                                               bool(node.props.get("normalize")))
    return {"Segment Coordinates": coordinates, "Segment ID": ids, "Segment Width": width,
            "Segment Rotation": rotation}


def _value(node, inputs, points):
    return {s: _constant(node.values.get(s, 0.0), kind, len(points)) for s, kind in node.outputs.items()}


#: The nodes evaluated, each its function.
NODES = {
    "ShaderNodeValue": _value, "ShaderNodeRGB": _value, "ShaderNodeTexCoord": _texcoord,
    "ShaderNodeMapping": _mapping, "ShaderNodeVectorMath": _vector_math, "ShaderNodeMath": _math,
    "ShaderNodeMapRange": _map_range, "ShaderNodeMix": _mix_node, "ShaderNodeMixRGB": _mix_rgb,
    "ShaderNodeValToRGB": _ramp, "ShaderNodeRGBCurve": _curves, "ShaderNodeVectorCurve": _curves,
    "ShaderNodeFloatCurve": _curves, "ShaderNodeClamp": _clamp,
    "ShaderNodeSeparateColor": _separate_color, "ShaderNodeCombineColor": _combine_color,
    "ShaderNodeSeparateRGB": _legacy(_separate_color, "RGB", ("R", "G", "B"), "Image"),
    "ShaderNodeCombineRGB": _legacy(_combine_color, "RGB", ("R", "G", "B"), "Image"),
    "ShaderNodeSeparateHSV": _legacy(_separate_color, "HSV", ("H", "S", "V"), "Color"),
    "ShaderNodeCombineHSV": _legacy(_combine_color, "HSV", ("H", "S", "V"), "Color"),
    "ShaderNodeInvert": _rgb_nodes(color.invert, ("Fac", "Color")),
    "ShaderNodeGamma": _rgb_nodes(color.gamma, ("Color", "Gamma")),
    "ShaderNodeBrightContrast": _rgb_nodes(color.brightness_contrast, ("Color", "Bright", "Contrast")),
    "ShaderNodeHueSaturation": _rgb_nodes(color.hue_saturation_value,
                                          ("Hue", "Saturation", "Value", "Fac", "Color")),
    "ShaderNodeSeparateXYZ": _separate_xyz, "ShaderNodeCombineXYZ": _combine_xyz,
    "ShaderNodeVectorRotate": _vector_rotate, "ShaderNodeNormal": _normal,
    "ShaderNodeTexNoise": _noise, "ShaderNodeTexVoronoi": _voronoi, "ShaderNodeTexWave": _wave,
    "ShaderNodeTexGradient": _gradient, "ShaderNodeTexChecker": _checker,
    "ShaderNodeTexWhiteNoise": _white_noise, "ShaderNodeTexMagic": _magic, "ShaderNodeTexBrick": _brick,
    "ShaderNodeTexGabor": _gabor, "ShaderNodeRadialTiling": _radial_tiling,
}
#: The nodes that read the running Blender's luminance weights (the flat graph's), each its function.
LUMA_NODES = {CONVERT: _convert, "ShaderNodeRGBToBW": _rgb_to_bw}
#: The procedurals among them: an input is predicted from points only where one of these feeds it.
PROCEDURALS = frozenset({"ShaderNodeTexNoise", "ShaderNodeTexVoronoi", "ShaderNodeTexWave",
                         "ShaderNodeTexGradient", "ShaderNodeTexChecker", "ShaderNodeTexWhiteNoise",
                         "ShaderNodeTexMagic", "ShaderNodeTexBrick", "ShaderNodeTexGabor",
                         "ShaderNodeRadialTiling"})


def upstream(flat: FlatGraph, source: Ref) -> list[str]:
    """The nodes ``source`` reads, dependencies first."""
    seen: dict[str, None] = {}

    def visit(name: str) -> None:
        if name in seen or name not in flat.nodes:
            return
        for spec in flat.nodes[name].inputs.values():
            if isinstance(spec.source, Ref):
                visit(spec.source.node)
        seen[name] = None

    visit(source.node)
    return list(seen)


def evaluable(flat: FlatGraph, source: Ref) -> bool:
    """Whether ``source`` can be evaluated here: every node it reads is in ``NODES`` (or a
    conversion), and a procedural among them (else its value does not vary with the point)."""
    names = upstream(flat, source)
    kinds = {flat.nodes[n].kind for n in names}
    return bool(kinds & PROCEDURALS) and all(k in NODES or k in LUMA_NODES for k in kinds)


def evaluate(flat: FlatGraph, source: Ref, points: Points) -> np.ndarray | None:
    """``source``'s value at ``points``: (N,) for a float, (N, 3) a vector, (N, 4) a colour; None
    where a node cannot be evaluated with its settings (a setting that varies per point, a mode not
    here) or reads an output not evaluated here (Texture Coordinate's Normal ...)."""
    n = len(points)
    values: dict[tuple[str, str], np.ndarray] = {}
    for name in upstream(flat, source):
        node: FlatNode = flat.nodes[name]
        inputs = {}
        for socket, spec in node.inputs.items():
            if isinstance(spec.source, Const):
                inputs[socket] = _constant(spec.source.value, spec.type, n)
            else:
                found = values.get((spec.source.node, spec.source.socket))
                if found is None:  # an output not evaluated here (Texture Coordinate's Normal ...)
                    return None
                inputs[socket] = found
        with np.errstate(all="ignore"):  # (a twin's float32 arithmetic as the GPU's: Inf and NaN pass)
            out = LUMA_NODES[node.kind](node, inputs, points, flat.luma) if node.kind in LUMA_NODES else \
                NODES[node.kind](node, inputs, points)
        if out is None:
            return None
        values.update({(name, socket): np.asarray(v, F32) for socket, v in out.items()})
    return values.get((source.node, source.socket))
