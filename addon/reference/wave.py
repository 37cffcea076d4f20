"""The numpy twin of ``glsl/node_tex_wave.glsl``: Cycles' Wave Texture (kernel/svm/wave.h,
svm_wave): bands along an axis or the diagonal, rings about an axis or a point, a sine, saw or
triangle profile of the phase, displaced by the normalised fBM noise of ``noise.py``. Float32 as
Cycles computes, with its kernel's fused operations and its division by 2 pi as a product with the
reciprocal (-ffast-math; Blender 4.2's Cycles: a division, ``phase_rule``), measured: equal to
Cycles' output but for its sinf, whose result is one unit in the last place from the correctly
rounded sine at 0.5 % of the points. Pure numpy."""

from __future__ import annotations

import numpy as np

from . import noise

F32 = np.float32
TYPES = ("BANDS", "RINGS")
BANDS_DIRECTIONS = ("X", "Y", "Z", "DIAGONAL")
RINGS_DIRECTIONS = ("X", "Y", "Z", "SPHERICAL")
PROFILES = ("SIN", "SAW", "TRI")
#: Rings about an axis: the coordinate's components kept (Cycles' rp *= mask); SPHERICAL all.
_RINGS_MASK = {"X": (0, 1, 1), "Y": (1, 0, 1), "Z": (1, 1, 0), "SPHERICAL": (1, 1, 1)}
_HALF_PI = F32(np.pi / 2)
#: The most octaves a linked Detail gets (glsl/node_tex_wave.glsl's WAVE_MAX_DETAIL; Cycles' loop
#: has no bound).
MAX_DETAIL = F32(64)
_TWO_PI = F32(2 * np.pi)
_INV_TWO_PI = F32(1) / _TWO_PI
#: The phase over 2 pi: times the reciprocal (Blender 4.5, 5.0) or divided (4.2), the reader's
#: ``wave_phase``
PHASE_RULES = ("RECIPROCAL", "DIVIDE")


def phase(p: np.ndarray, kind: str, direction: str) -> np.ndarray:
    """The wave's phase before its Phase Offset: 20 x the coordinate along the bands' axis (10 x
    the sum for the diagonal), or 20 x the distance from the rings' axis."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    if kind == "BANDS":
        if direction == "DIAGONAL":
            return ((x + y) + z) * F32(10)
        return {"X": x, "Y": y, "Z": z}[direction] * F32(20)
    r = p * np.array(_RINGS_MASK[direction], F32)
    # Cycles' len: sqrt of SSE4's dot product (products rounded, summed pairwise: (x + y) + z)
    dot = (r[..., 0] * r[..., 0] + r[..., 1] * r[..., 1]) + r[..., 2] * r[..., 2]
    return np.sqrt(dot) * F32(20)


def wave(co, scale=5.0, kind="BANDS", direction="X", profile="SIN", distortion=0.0, detail=2.0,
         detail_scale=1.0, detail_roughness=0.5, phase_offset=0.0, phase_rule="RECIPROCAL") -> np.ndarray:
    """The Wave Texture's Fac at ``co`` (..., 3) (its Color is Fac in each channel); ``direction``
    is the bands' or the rings' as ``kind`` says, ``phase_rule`` one of ``PHASE_RULES``."""
    if kind not in TYPES or profile not in PROFILES or phase_rule not in PHASE_RULES:
        raise ValueError(f"Wave Texture: unknown type {kind!r}, profile {profile!r} or phase {phase_rule!r}")
    # Cycles: "prevent precision issues on unit coordinates", co x scale fused into the sum
    p = noise.fma(co, F32(scale), F32(1e-6)) * F32(0.999999)
    n = phase(p, kind, direction) + F32(phase_offset)
    if F32(distortion) != 0:
        octaves = F32(detail) if F32(detail) < MAX_DETAIL else MAX_DETAIL  # the GPU's loop bound (NaN too)
        fbm = noise.fbm(p * F32(detail_scale), octaves, detail_roughness, 2.0, True)
        n = noise.fma(F32(distortion), noise.fma(fbm, F32(2), F32(-1)), n)
    if profile == "SIN":  # sinf correctly rounded (float64 rounded once): Cycles' differs by an ulp
        return F32(0.5) + F32(0.5) * np.sin((n - _HALF_PI).astype(np.float64)).astype(F32)
    n = n * _INV_TWO_PI if phase_rule == "RECIPROCAL" else n / _TWO_PI
    if profile == "SAW":
        return n - np.floor(n)
    return np.abs(n - np.floor(n + F32(0.5))) * F32(2)
