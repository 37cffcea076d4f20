"""The numpy twin of ``glsl/environment.glsl``: the world as a radiance field, looked up in a
direction exactly as Cycles' Environment Texture does (``kernel/camera/projection.h``).

Directions are arrays of shape (..., 3), not necessarily unit; images are ``snapshot.ImageData``.
Pure numpy: no ``bpy``, no ``gpu``.
"""

from __future__ import annotations

import numpy as np

from .snapshot import MAX_ENVIRONMENT_IMAGES, EnvironmentTerm, ImageData, World
from .tonemap import srgb_to_linear


def equirect_uv(d) -> np.ndarray:
    """Cycles' equirectangular mapping: u = (pi - atan2(y, x)) / 2pi, v = 1 - acos(z) / pi."""
    d = np.asarray(d, np.float64)
    length = np.linalg.norm(d, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.where((d[..., 0] == 0.0) & (d[..., 1] == 0.0), 0.5,
                     0.5 - np.arctan2(d[..., 1], d[..., 0]) / (2.0 * np.pi))
        v = 1.0 - np.arccos(np.clip(d[..., 2] / length, -1.0, 1.0)) / np.pi
    return np.where((length > 0.0)[..., None], np.stack([u, v], -1), 0.0)


def equirect_direction(u, v) -> np.ndarray:
    """The unit direction of equirectangular coordinates (u, v): the inverse of ``equirect_uv``."""
    phi = np.pi - 2.0 * np.pi * np.asarray(u, np.float64)
    theta = np.pi * (1.0 - np.asarray(v, np.float64))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)


def mirror_ball_uv(d) -> np.ndarray:
    """Cycles' mirror ball: a chrome ball photographed along +Y."""
    d = np.asarray(d, np.float64)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    x, y, z = d[..., 0], d[..., 1] - 1.0, d[..., 2]
    div = 2.0 * np.sqrt(np.maximum(-0.5 * y, 0.0))
    safe = np.where(div > 0.0, div, 1.0)
    return 0.5 * (np.stack([x / safe, z / safe], -1) + 1.0)


def linear_pixels(image: ImageData) -> np.ndarray:
    """(h, w, 4) float64 as the sampler returns them: sRGB bytes decoded, other bytes / 255."""
    pixels = np.asarray(image.pixels, np.float64)
    if image.pixels.dtype == np.uint8:
        pixels = pixels / 255.0
    if image.storage == "SRGB8":
        pixels = np.concatenate([srgb_to_linear(pixels[..., :3]), pixels[..., 3:]], -1)
    return pixels


def lookup(pixels: np.ndarray, uv, closest: bool = False) -> np.ndarray:
    """Bilinear between texel centres (Cycles' "Linear"), repeating in u and clamped in v; or the
    texel under uv ("Closest"). ``pixels`` (h, w, c), bottom row first."""
    h, w = pixels.shape[:2]
    uv = np.asarray(uv, np.float64)
    p = uv * np.array([w, h])

    def texel(x, y):
        return pixels[np.clip(y, 0, h - 1), np.mod(x, w)]

    if closest:
        return texel(np.floor(p[..., 0]).astype(int), np.floor(p[..., 1]).astype(int))
    p = p - 0.5
    i = np.floor(p)
    f = p - i
    x, y = i[..., 0].astype(int), i[..., 1].astype(int)
    fx, fy = f[..., 0:1], f[..., 1:2]
    bottom = texel(x, y) * (1 - fx) + texel(x + 1, y) * fx
    top = texel(x, y + 1) * (1 - fx) + texel(x + 1, y + 1) * fx
    return bottom * (1 - fy) + top * fy


def term_radiance(term: EnvironmentTerm, d) -> np.ndarray:
    """(..., 3): one term's radiance in directions ``d``."""
    d = np.asarray(d, np.float64)
    if term.image is None:
        return np.broadcast_to(np.asarray(term.weight, np.float64), d.shape).copy()
    m = np.asarray(term.lookup, np.float64)
    v = d @ m[:3, :3].T + m[:3, 3]
    uv = mirror_ball_uv(v) if term.projection == "MIRROR_BALL" else equirect_uv(v)
    return np.asarray(term.weight, np.float64) * lookup(linear_pixels(term.image), uv, term.closest)[..., :3]


def world_radiance(terms, d) -> np.ndarray:
    """(..., 3): a radiance field (``World.camera`` or ``World.lighting``) in directions ``d``,
    its constant terms and its first ``MAX_ENVIRONMENT_IMAGES`` image terms, as the GPU sums it."""
    d = np.asarray(d, np.float64)
    out = np.broadcast_to(np.asarray(World.constant(terms)), d.shape).copy()
    for term in World.images(terms)[:MAX_ENVIRONMENT_IMAGES]:
        out += term_radiance(term, d)
    return out
