"""Blender's implicit conversions between socket types, in one table: what a link between sockets
of two types carries, as Cycles and EEVEE convert it (Cycles' ``svm_node_convert``, EEVEE's
``GPU_link`` conversions): a colour read as a float is its luminance (``LUMA``), a vector read
as a float the average of its components, a float read as a colour grey with alpha 1, a colour read as
a vector its RGB, a vector read as a colour its XYZ with alpha 1. Shaders convert to nothing: a
link from a shader to a value socket is invalid in Blender, and the input keeps a zero.
"""

from __future__ import annotations

from ..scene.colour import XYZ_TO_RGB, XYZ_TO_RGB_4  # noqa: F401 (read here by nodes.py)

#: Colour -> float: the Y row of the default colour configuration's scene linear (Rec. 709) to
#: XYZ D65 matrix, as Cycles' rgb_to_y holds it in Blender 5.0: against Cycles' RGB to BW node
#: 8e-7 (the config's rounded ``luma``, 0.2126 / 0.7152 / 0.0722, was 4.8e-5 off). Blender 4.2 and
#: 4.5 hold LUMA_4 (1.2e-6 there); the reader names the one of the running Blender (``Graph.luma``).
LUMA = (0.2126390, 0.7151687, 0.0721923)
LUMA_4 = (0.2126729, 0.7151522, 0.0721750)
#: Socket types that carry one number, three, or a colour (four, alpha last).
SCALARS = ("VALUE", "INT", "BOOLEAN")
VECTORS = ("VECTOR",)
COLORS = ("RGBA",)
#: Types a node's output can be read as through a link (others, e.g. SHADER, only as themselves).
CONVERTIBLE = SCALARS + VECTORS + COLORS

#: The value each type holds where nothing sets it (a muted node's output with nothing to pass on,
#: an unlinked group output): zero, opaque black.
ZERO = {"VALUE": 0.0, "INT": 0, "BOOLEAN": False, "VECTOR": (0.0, 0.0, 0.0), "RGBA": (0.0, 0.0, 0.0, 1.0),
        "ROTATION": (0.0, 0.0, 0.0)}


def zero(type_: str):
    """The value of a ``type_`` socket that nothing sets (None for types without values)."""
    return ZERO.get(type_)


def _as_float(type_: str, value, luma) -> float:
    if type_ in SCALARS:
        return float(value)
    if type_ in VECTORS:
        return (float(value[0]) + float(value[1]) + float(value[2])) / 3.0
    return sum(c * float(v) for c, v in zip(luma or LUMA, value[:3]))


def value(value, from_type: str, to_type: str, luma=None):
    """A constant of ``from_type`` as a ``to_type`` socket reads it (a zero where the types do
    not convert); ``luma``: a colour's weights as a float (None: LUMA)."""
    if from_type == to_type:
        return value
    if from_type not in CONVERTIBLE or to_type not in CONVERTIBLE:
        return zero(to_type)
    if to_type == "VALUE":
        return _as_float(from_type, value, luma)
    if to_type == "INT":
        return int(_as_float(from_type, value, luma))  # truncated, as C converts
    if to_type == "BOOLEAN":
        return _as_float(from_type, value, luma) > 0.0
    if from_type in SCALARS:
        f = float(value)
        return (f, f, f) if to_type == "VECTOR" else (f, f, f, 1.0)
    xyz = tuple(float(v) for v in value[:3])
    return xyz if to_type == "VECTOR" else (*xyz, 1.0)


def converts(from_type: str, to_type: str) -> bool:
    """Whether a link between the two types carries a value (else the input reads a zero)."""
    return from_type == to_type or (from_type in CONVERTIBLE and to_type in CONVERTIBLE)
