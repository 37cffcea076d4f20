"""Reads a Blender light into ``Light``: its kind, intensity as Cycles normalises it, size and
shape, spot cone, shadow settings and reach.
"""

from __future__ import annotations

import math

import bpy
import numpy as np

from ..plan import light_tiles
from ..scene import snapshot as S

LIGHT_KIND = {"POINT": "POINT", "SPOT": "SPOT", "SUN": "SUN", "AREA": "AREA"}


def light_strength(light: bpy.types.Light) -> np.ndarray:
    """Linear rgb colour x energy x 2^exposure (x blackbody colour when temperature is used)."""
    color = np.array(light.color, np.float64)
    if getattr(light, "use_temperature", False):
        color = color * np.array(light.temperature_color, np.float64)
    return color * float(light.energy) * 2.0 ** float(getattr(light, "exposure", 0.0))


def make_light(light: bpy.types.Light, matrix) -> S.Light:
    """The light as the shaders see it, reaching as far as its Custom Distance (everywhere
    without one); the Light Threshold's reach is the scene's to give (``programs.light_reaches``)."""
    m = np.array(matrix, np.float64)
    position = tuple(float(x) for x in m[:3, 3])
    axis = -m[:3, 2]
    norm = np.linalg.norm(axis)
    direction = tuple(float(x) for x in (axis / norm if norm > 0 else np.array([0.0, 0.0, -1.0])))
    strength = light_strength(light)
    kind = LIGHT_KIND[light.type]
    extra = {}
    normalized = getattr(light, "normalize", True)
    # Cycles (scene/light.cpp): eval_fac = (normalize ? 1 / area : 1) / pi, with area = 4 for a
    # radius-0 point or spot, 1 for a zero-angle sun, and the light's surface for an area light.
    if kind in ("POINT", "SPOT"):
        intensity = strength / (4.0 * math.pi if normalized else math.pi)  # I = P / 4 pi W/sr
    elif kind == "SUN":
        intensity = strength  # W/m^2 at any angle when normalized
        half = 0.5 * float(light.angle)
        if not normalized and half > 0.0:
            intensity = strength * math.pi * math.sin(half) ** 2
    else:  # AREA: a Lambertian emitter of radiance P / (pi A) gives I = P / pi along its normal
        intensity = strength / math.pi
        if not normalized:
            intensity = intensity * _area(light)
    if kind == "SPOT":
        extra = dict(
            spot_cos_half=math.cos(0.5 * light.spot_size),
            spot_smooth=S.spot_smooth(light.spot_size, light.spot_blend),
        )
    if kind == "SUN":
        extra["angle"] = max(float(light.angle), 0.0)
    elif kind == "AREA":
        scale_x, scale_y = (float(np.linalg.norm(m[:3, i])) for i in (0, 1))
        sx, sy, ellipse = _area_shape(light)
        half = (0.5 * sx * scale_x, 0.5 * sy * scale_y)
        extra["radius"] = math.sqrt(half[0] * half[1] * (1.0 if ellipse else 4.0 / math.pi))  # equal area
        extra["axis_x"] = tuple(float(x) for x in m[:3, 0] / max(scale_x, 1e-30))
        extra["half_size"] = half
        extra["ellipse"] = ellipse
        extra["spread"] = min(max(float(getattr(light, "spread", math.pi)), 0.0), math.pi)
    else:
        extra["radius"] = max(float(light.shadow_soft_size), 0.0)
        extra["soft_falloff"] = bool(getattr(light, "use_soft_falloff", False))
    custom = float(light.cutoff_distance) if getattr(light, "use_custom_distance", False) else None
    extra["cutoff"] = extra["influence"] = light_tiles.influence_radius(kind, intensity, 0.0, custom)
    return S.Light(
        kind=kind,
        position=position,
        direction=direction,
        intensity=tuple(float(x) for x in intensity),
        diffuse_factor=float(light.diffuse_factor),
        specular_factor=float(light.specular_factor),
        shadow=bool(getattr(light, "use_shadow", True)),
        shadow_filter=max(float(getattr(light, "shadow_filter_radius", 1.0)), 0.0),
        shadow_resolution_limit=max(float(getattr(light, "shadow_maximum_resolution", 0.001)), 0.0),
        shadow_jitter=bool(getattr(light, "use_shadow_jitter", False)),
        **extra,
    )


def _area_shape(light) -> tuple[float, float, bool]:
    """An area light's width, height and whether it is a disk or an ellipse."""
    sy = light.size_y if light.shape in ("RECTANGLE", "ELLIPSE") else light.size
    return float(light.size), float(sy), light.shape in ("DISK", "ELLIPSE")


def _area(light) -> float:
    sx, sy, ellipse = _area_shape(light)
    return sx * sy * (math.pi / 4.0 if ellipse else 1.0)
