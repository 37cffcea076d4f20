"""The numpy twin of the colour nodes' GLSL: RGB <-> HSV and HSL (``glsl/node_color.glsl``, as
Cycles' util/color.h: rgb_to_hsv, hsv_to_rgb, rgb_to_hsl, hsl_to_rgb), the Mix node's colour blend
modes (``glsl/node_mix.glsl``, as Cycles' kernel/svm/color_util.h: svm_mix_blend ... svm_mix_linear)
and the colour converters (``glsl/node_converter.glsl``: Cycles' svm/invert.h, gamma.h,
brightness.h, hsv.h). Vectorised over points: colours (..., 3) RGB, factors (...,) or scalars;
float32 throughout, as the GPU. Every branch is computed, each point takes its own (``np.where``),
so quotients a point does not take may be Inf or NaN: callers silence numpy's warnings. Pure
numpy."""

from __future__ import annotations

import numpy as np

F32 = np.float32
ONE = F32(1.0)


def _f32(x) -> np.ndarray:
    return np.asarray(x, F32)


def _channels(rgb):
    rgb = _f32(rgb)
    return rgb[..., 0], rgb[..., 1], rgb[..., 2]


def _column(t, rgb) -> np.ndarray:
    """A factor (...,) or scalar against colours (..., 3)."""
    t = _f32(t)
    return t[..., None] if t.ndim == rgb.ndim - 1 else t


def _mix(c1, c2, t):
    """GLSL's mix (Cycles' interp): (1 - t) c1 + t c2."""
    return (ONE - t) * c1 + t * c2


# --- colour spaces ----------------------------------------------------------------------------

def rgb_to_hsv(rgb) -> np.ndarray:
    """Hue in [0, 1), saturation, value (Cycles' rgb_to_hsv): a grey has hue and saturation 0."""
    r, g, b = _channels(rgb)
    cmax = np.maximum(r, np.maximum(g, b))
    cmin = np.minimum(r, np.minimum(g, b))
    delta = cmax - cmin
    s = np.where(cmax != 0, delta / np.where(cmax != 0, cmax, ONE), F32(0))
    d = np.where(s != 0, delta, ONE)  # (a grey's hue is not computed: 0)
    cr, cg, cb = (cmax - r) / d, (cmax - g) / d, (cmax - b) / d
    h = np.where(r == cmax, cb - cg, np.where(g == cmax, F32(2) + cr - cb, F32(4) + cg - cr)) / F32(6)
    h = np.where(h < 0, h + ONE, h)
    return np.stack([np.where(s != 0, h, F32(0)), s, cmax], -1).astype(F32)


def hsv_to_rgb(hsv) -> np.ndarray:
    """Cycles' hsv_to_rgb: the sextant of 6h picks the channels (a hue of 1 is 0's)."""
    h, s, v = _channels(hsv)
    h = np.where(h == ONE, F32(0), h) * F32(6)
    i = np.floor(h)
    f = h - i
    p = v * (ONE - s)
    q = v * (ONE - s * f)
    t = v * (ONE - s * (ONE - f))
    sextants = [(v, t, p), (q, v, p), (p, v, t), (p, q, v), (t, p, v)]
    out = np.stack([v, p, q], -1)  # (the last sextant, and any hue outside [0, 1])
    for k in range(4, -1, -1):
        out = np.where((i == k)[..., None], np.stack(sextants[k], -1), out)
    return np.where((s == 0)[..., None], np.stack([v, v, v], -1), out).astype(F32)


def rgb_to_hsl(rgb) -> np.ndarray:
    """Cycles' rgb_to_hsl: lightness at most 1, a grey's hue and saturation 0."""
    r, g, b = _channels(rgb)
    cmax = np.maximum(r, np.maximum(g, b))
    cmin = np.minimum(r, np.minimum(g, b))
    lightness = np.minimum(ONE, (cmax + cmin) * F32(0.5))
    grey = cmax == cmin
    d = np.where(grey, ONE, cmax - cmin)  # (a grey's hue and saturation are not computed: 0)
    s = np.where(lightness > 0.5, d / (F32(2) - cmax - cmin), d / (cmax + cmin))
    h = np.where(cmax == r, (g - b) / d + np.where(g < b, F32(6), F32(0)),
                 np.where(cmax == g, (b - r) / d + F32(2), (r - g) / d + F32(4)))
    zero = F32(0)
    return np.stack([np.where(grey, zero, h / F32(6)), np.where(grey, zero, s), lightness], -1).astype(F32)


def hsl_to_rgb(hsl) -> np.ndarray:
    """Cycles' hsl_to_rgb."""
    h, s, lightness = _channels(hsl)
    n = np.clip(np.stack([np.abs(h * F32(6) - F32(3)) - ONE, F32(2) - np.abs(h * F32(6) - F32(2)),
                          F32(2) - np.abs(h * F32(6) - F32(4))], -1), F32(0), ONE)
    chroma = (ONE - np.abs(F32(2) * lightness - ONE)) * s
    return ((n - F32(0.5)) * chroma[..., None] + lightness[..., None]).astype(F32)


# --- the Mix node's blend modes ----------------------------------------------------------------

def _per_channel_dodge(t, c1, c2):
    """svm_mix_dodge: c1 / (1 - t c2), 1 where that is past 1 or the divisor not positive; 0 stays."""
    tmp = ONE - t * c2
    q = c1 / np.where(tmp != 0, tmp, ONE)
    return np.where(c1 == 0, c1, np.where((tmp <= 0) | (q > 1), ONE, q))


def _per_channel_burn(t, c1, c2):
    """svm_mix_burn: 1 - (1 - c1) / ((1 - t) + t c2) saturated, 0 where the divisor is not positive."""
    tmp = (ONE - t) + t * c2
    return np.where(tmp <= 0, F32(0), np.clip(ONE - (ONE - c1) / np.where(tmp > 0, tmp, ONE), F32(0), ONE))


def _overlay(t, c1, c2):
    tm = ONE - t
    return np.where(c1 < 0.5, c1 * (tm + F32(2) * t * c2), ONE - (tm + F32(2) * t * (ONE - c2)) * (ONE - c1))


def _divide(t, c1, c2):
    return np.where(c2 != 0, (ONE - t) * c1 + t * c1 / np.where(c2 != 0, c2, ONE), c1)


def _take_hue(t, c1, c2, with_saturation: bool):
    """HUE and COLOR: c1 given c2's hue (and, for COLOR, its saturation) where c2 has a hue."""
    hsv2 = rgb_to_hsv(c2)
    hsv = rgb_to_hsv(c1)
    hsv[..., 0] = hsv2[..., 0]
    if with_saturation:
        hsv[..., 1] = hsv2[..., 1]
    return np.where((hsv2[..., 1] == 0)[..., None], c1, _mix(c1, hsv_to_rgb(hsv), t))


def _saturation(t, c1, c2):
    hsv = rgb_to_hsv(c1)
    grey = (hsv[..., 1] == 0)[..., None]
    hsv[..., 1] = (ONE - t[..., 0]) * hsv[..., 1] + t[..., 0] * rgb_to_hsv(c2)[..., 1]
    return np.where(grey, c1, hsv_to_rgb(hsv))


def _value(t, c1, c2):
    hsv = rgb_to_hsv(c1)
    hsv[..., 2] = (ONE - t[..., 0]) * hsv[..., 2] + t[..., 0] * rgb_to_hsv(c2)[..., 2]
    return hsv_to_rgb(hsv)


def _soft_light(t, c1, c2):
    screen = ONE - (ONE - c2) * (ONE - c1)
    return (ONE - t) * c1 + t * ((ONE - c1) * c2 * c1 + c1 * screen)


#: The blend modes (Blender's blend_type), each f(t (..., 1), c1, c2) -> (..., 3).
BLEND_MODES = {
    "MIX": lambda t, c1, c2: _mix(c1, c2, t),
    "ADD": lambda t, c1, c2: _mix(c1, c1 + c2, t),
    "MULTIPLY": lambda t, c1, c2: _mix(c1, c1 * c2, t),
    "SUBTRACT": lambda t, c1, c2: _mix(c1, c1 - c2, t),
    "DIFFERENCE": lambda t, c1, c2: _mix(c1, np.abs(c1 - c2), t),
    "EXCLUSION": lambda t, c1, c2: np.maximum(_mix(c1, c1 + c2 - F32(2) * c1 * c2, t), F32(0)),
    "DARKEN": lambda t, c1, c2: _mix(c1, np.minimum(c1, c2), t),
    "LIGHTEN": lambda t, c1, c2: _mix(c1, np.maximum(c1, c2), t),
    "SCREEN": lambda t, c1, c2: ONE - ((ONE - t) + t * (ONE - c2)) * (ONE - c1),
    "OVERLAY": _overlay,
    "DIVIDE": _divide,
    "DODGE": _per_channel_dodge,
    "BURN": _per_channel_burn,
    "HUE": lambda t, c1, c2: _take_hue(t, c1, c2, False),
    "SATURATION": _saturation,
    "VALUE": _value,
    "COLOR": lambda t, c1, c2: _take_hue(t, c1, c2, True),
    "SOFT_LIGHT": _soft_light,
    "LINEAR_LIGHT": lambda t, c1, c2: c1 + t * (F32(2) * c2 - ONE),
}


def blend(mode: str, t, c1, c2) -> np.ndarray:
    """Colour ``c1`` blended with ``c2`` (each (..., 3)) by blend mode ``mode`` at factor ``t``
    ((...,) or a scalar; clamped first where the node says so, by the caller)."""
    c1, c2 = _f32(c1), _f32(c2)
    t = np.broadcast_to(_column(t, c1), c1.shape[:-1] + (1,))
    return np.asarray(BLEND_MODES[mode](t, c1, c2), F32)


# --- converters ---------------------------------------------------------------------------------

def invert(fac, rgb) -> np.ndarray:
    """Invert (svm_node_invert): rgb toward 1 - rgb by fac."""
    rgb = _f32(rgb)
    return _mix(rgb, ONE - rgb, _column(fac, rgb)).astype(F32)


def gamma(rgb, g) -> np.ndarray:
    """Gamma (svm_node_gamma): each positive channel to the power g; a gamma of 0 gives white."""
    rgb, g = _f32(rgb), _column(g, _f32(rgb))
    out = np.where(rgb > 0, np.power(np.where(rgb > 0, rgb, ONE), g), rgb)
    return np.where(g == 0, ONE, out).astype(F32)


def brightness_contrast(rgb, bright, contrast) -> np.ndarray:
    """Bright/Contrast (svm_node_brightness): (1 + contrast) rgb + bright - contrast / 2, not below 0."""
    rgb = _f32(rgb)
    a = ONE + _column(contrast, rgb)
    b = _column(bright, rgb) - _column(contrast, rgb) * F32(0.5)
    return np.maximum(a * rgb + b, F32(0)).astype(F32)


def hue_saturation_value(hue, saturation, value, fac, rgb) -> np.ndarray:
    """Hue/Saturation/Value (svm_node_hsv): the hue turned (wrapped), the saturation scaled and
    saturated, the value scaled, blended with the input by fac; not below 0."""
    rgb = _f32(rgb)
    hsv = rgb_to_hsv(rgb)
    h = hsv[..., 0] + _f32(hue) + F32(0.5)
    hsv[..., 0] = h - np.floor(h)
    hsv[..., 1] = np.clip(hsv[..., 1] * _f32(saturation), F32(0), ONE)
    hsv[..., 2] = hsv[..., 2] * _f32(value)
    f = _column(fac, rgb)
    return np.maximum(f * hsv_to_rgb(hsv) + (ONE - f) * rgb, F32(0)).astype(F32)
