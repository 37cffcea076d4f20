"""A compiled graph's values at given points, in numpy: what the Auto term set's prediction
(``plan/auto_terms.py``) reads where a procedural texture, not an image, feeds a Principled BSDF's
input. Each node is evaluated as its GLSL (``codegen.EMITTERS``) computes it, through the numpy
twins of ``addon/reference/`` (noise.py, voronoi.py, wave.py, patterns.py, hashing.py) for the
procedurals and plain numpy for the converters, on float32 as the GPU; a graph holding any other
node is not evaluated (``evaluable`` says so, and its input keeps its socket's value). Pure numpy:
no ``bpy``, no ``gpu``.

The points come as their coordinates: ``Point.generated`` (Generated: the object's texture space,
what a texture node reads where its Vector is unlinked), ``Point.object`` and ``Point.uv``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..reference import hashing, noise, patterns, voronoi, wave
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
    return None


_VECTOR_MATH = {"ADD": lambda a, b, s: a + b, "SUBTRACT": lambda a, b, s: a - b,
                "MULTIPLY": lambda a, b, s: a * b, "DIVIDE": lambda a, b, s: _safe_divide(a, b),
                "SCALE": lambda a, b, s: a * s[:, None]}


def _vector_math(node, inputs, points):
    fn = _VECTOR_MATH.get(node.props.get("operation"))
    if fn is None:
        return None
    n = len(points)
    b = inputs.get("Vector_001", np.zeros((n, 3), F32))
    return {"Vector": fn(inputs["Vector"], b, inputs.get("Scale", np.ones(n, F32))).astype(F32)}


_MATH = {"ADD": lambda a, b, c: a + b, "SUBTRACT": lambda a, b, c: a - b, "MULTIPLY": lambda a, b, c: a * b,
         "DIVIDE": lambda a, b, c: _safe_divide(a, b), "MULTIPLY_ADD": lambda a, b, c: a * b + c,
         "MINIMUM": lambda a, b, c: np.minimum(a, b), "MAXIMUM": lambda a, b, c: np.maximum(a, b),
         "ABSOLUTE": lambda a, b, c: np.abs(a)}


def _math(node, inputs, points):
    fn = _MATH.get(node.props.get("operation"))
    if fn is None:
        return None
    zero = np.zeros(len(points), F32)
    value = fn(*(inputs.get(s, zero) for s in ("Value", "Value_001", "Value_002"))).astype(F32)
    return {"Value": np.clip(value, F32(0), F32(1)) if node.props.get("use_clamp") else value}


def _map_range(node, inputs, points):
    props = node.props
    if props.get("data_type", "FLOAT") != "FLOAT" or props.get("interpolation_type", "LINEAR") != "LINEAR":
        return None
    lo, hi, to_lo, to_hi = (inputs[s] for s in ("From Min", "From Max", "To Min", "To Max"))
    value = to_lo + _safe_divide(inputs["Value"] - lo, hi - lo) * (to_hi - to_lo)
    if node.props.get("clamp"):  # (in either order of the target range, as Cycles' clamp_range)
        value = np.clip(value, np.minimum(to_lo, to_hi), np.maximum(to_lo, to_hi))
    return {"Result": value.astype(F32)}


def _mix_node(node, inputs, points):
    kind = node.props.get("data_type")
    if kind == "VECTOR" and node.props.get("factor_mode", "UNIFORM") != "UNIFORM":
        return None
    fac = inputs["Factor_Float"]
    if node.props.get("clamp_factor", True):
        fac = np.clip(fac, F32(0), F32(1))
    if kind == "FLOAT":
        return {"Result_Float": _mix(inputs["A_Float"], inputs["B_Float"], fac)}
    if kind == "VECTOR":
        return {"Result_Vector": _mix(inputs["A_Vector"], inputs["B_Vector"], fac[:, None])}
    if kind != "RGBA" or node.props.get("blend_type") != "MIX":
        return None
    a, b = inputs["A_Color"], inputs["B_Color"]
    rgb = _mix(a[:, :3], b[:, :3], fac[:, None])
    if node.props.get("clamp_result"):
        rgb = np.clip(rgb, F32(0), F32(1))
    return {"Result_Color": np.concatenate([rgb, a[:, 3:]], 1)}


def _ramp(node, inputs, points):
    """glsl/node_ramp.glsl's ramp_lookup over the reader's table (Cycles' rgb_ramp_lookup)."""
    table = node.props.get("table")
    if table is None:
        return None
    table = np.asarray(table, F32).reshape(-1, 4)
    f = np.clip(np.nan_to_num(inputs["Fac"]), F32(0), F32(1)) * F32(len(table) - 1)
    i = np.clip(f.astype(np.int64), 0, len(table) - 1)
    color = table[i]
    if node.props.get("interpolate", True):
        t = (f - i)[:, None]
        color = np.where(t > 0, (F32(1) - t) * color + t * table[np.minimum(i + 1, len(table) - 1)], color)
    return {"Color": color.astype(F32), "Alpha": color[:, 3].astype(F32)}


def _separate_color(node, inputs, points):
    if node.props.get("mode", "RGB") != "RGB":
        return None
    c = inputs["Color"]
    return {"Red": c[:, 0], "Green": c[:, 1], "Blue": c[:, 2]}


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
        if np.ptp(value) != 0:
            return None
        out[name] = F32(value.reshape(-1)[0])
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


def _value(node, inputs, points):
    return {s: _constant(node.values.get(s, 0.0), kind, len(points)) for s, kind in node.outputs.items()}


#: The nodes evaluated, each its function.
NODES = {
    "ShaderNodeValue": _value, "ShaderNodeRGB": _value, "ShaderNodeTexCoord": _texcoord,
    "ShaderNodeMapping": _mapping, "ShaderNodeVectorMath": _vector_math, "ShaderNodeMath": _math,
    "ShaderNodeMapRange": _map_range, "ShaderNodeMix": _mix_node, "ShaderNodeValToRGB": _ramp,
    "ShaderNodeSeparateColor": _separate_color, "ShaderNodeSeparateXYZ": _separate_xyz,
    "ShaderNodeCombineXYZ": _combine_xyz, "ShaderNodeTexNoise": _noise, "ShaderNodeTexVoronoi": _voronoi,
    "ShaderNodeTexWave": _wave, "ShaderNodeTexGradient": _gradient, "ShaderNodeTexChecker": _checker,
    "ShaderNodeTexWhiteNoise": _white_noise,
}
#: The procedurals among them: an input is predicted from points only where one of these feeds it.
PROCEDURALS = frozenset({"ShaderNodeTexNoise", "ShaderNodeTexVoronoi", "ShaderNodeTexWave",
                         "ShaderNodeTexGradient", "ShaderNodeTexChecker", "ShaderNodeTexWhiteNoise"})


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
    return bool(kinds & PROCEDURALS) and all(k in NODES or k == CONVERT for k in kinds)


def evaluate(flat: FlatGraph, source: Ref, points: Points) -> np.ndarray | None:
    """``source``'s value at ``points``: (N,) for a float, (N, 3) a vector, (N, 4) a colour; None
    where a node cannot be evaluated with its settings (a setting that varies per point, a mode not
    here)."""
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
                inputs[socket] = found if found is not None else _constant(spec.default, spec.type, n)
        with np.errstate(all="ignore"):  # (a twin's float32 arithmetic as the GPU's: Inf and NaN pass)
            out = _convert(node, inputs, points, flat.luma) if node.kind == CONVERT else \
                NODES[node.kind](node, inputs, points)
        if out is None:
            return None
        values.update({(name, socket): np.asarray(v, F32) for socket, v in out.items()})
    return values.get((source.node, source.socket))
