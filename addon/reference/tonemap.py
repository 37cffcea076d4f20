"""Numpy twin of glsl/tonemap.glsl: exposure, tone curves and the transfer function."""

from __future__ import annotations

import numpy as np

from ..scene.snapshot import Choice

#: Who turns radiance into display values: Blender's view transform, or one of the engine's curves.
TONE_MAPPER_CHOICES = (
    Choice("BLENDER", "Blender", "blender", "Combined holds scene-linear radiance; Blender's view "
                                            "transform (AgX, Filmic, Standard ...) displays it, as for "
                                            "Cycles and EEVEE"),
    Choice("CLAMP", "Clamp", "clamp", "Clip to [0, 1], the seed's LDR pipeline"),
    Choice("REINHARD", "Reinhard", "reinhard", "Reinhard et al. 2002, L / (1 + L) per channel"),
    Choice("HABLE", "Hable Filmic", "hable", "Hable 2010, the Uncharted 2 filmic curve"),
    Choice("ACES", "ACES Fitted", "aces", "Hill's fit of the ACES RRT + sRGB ODT"),
)
TONE_MAPPERS = tuple(c.id for c in TONE_MAPPER_CHOICES)
TRANSFERS = ("SRGB", "GAMMA22")


def tonemap_clamp(x):
    return np.clip(x, 0.0, 1.0)


def tonemap_reinhard(x):
    return x / (1.0 + x)


def hable_curve(x):
    A, B, C, D, E, F = 0.15, 0.50, 0.10, 0.20, 0.02, 0.30
    return ((x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F)) - E / F


def tonemap_hable(x):
    return np.clip(hable_curve(2.0 * np.asarray(x, np.float64)) / hable_curve(11.2), 0.0, 1.0)


_TO_AP1 = np.array([[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566], [0.02840, 0.13383, 0.83777]])
_FROM_AP1 = np.array([[1.60475, -0.53108, -0.07367], [-0.10208, 1.10813, -0.00605],
                      [-0.00327, -0.07276, 1.07602]])


def tonemap_aces(x):
    v = np.asarray(x, np.float64) @ _TO_AP1.T
    a = v * (v + 0.0245786) - 0.000090537
    b = v * (0.983729 * v + 0.4329510) + 0.238081
    return np.clip((a / b) @ _FROM_AP1.T, 0.0, 1.0)


def srgb_to_linear(c):
    c = np.asarray(c, np.float64)
    return np.where(c >= 0.04045, ((c + 0.055) / 1.055) ** 2.4, c / 12.92)


def linear_to_srgb(x):
    x = np.asarray(x, np.float64)
    return np.where(x >= 0.0031308, 1.055 * np.maximum(x, 0.0031308) ** (1 / 2.4) - 0.055, 12.92 * x)


def transfer_gamma22(y):
    return srgb_to_linear(np.maximum(y, 0.0) ** (1.0 / 2.2))


CURVES = {"CLAMP": tonemap_clamp, "REINHARD": tonemap_reinhard, "HABLE": tonemap_hable, "ACES": tonemap_aces}


def display(radiance, tone_mapper: str, exposure_ev: float = 0.0, transfer: str = "SRGB"):
    """What the Combined pass holds for an engine tone mapper (display-linear, before Blender's
    Standard view transform encodes it)."""
    y = CURVES[tone_mapper](np.maximum(np.asarray(radiance, np.float64), 0.0) * 2.0 ** exposure_ev)
    return transfer_gamma22(y) if transfer == "GAMMA22" else y
