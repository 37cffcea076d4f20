"""Directional albedo tables for specular energy compensation (glsl/multiscatter.glsl).

E(mu, r) = integral over l of D V (n.l) with F = 1: the fraction of light a white single-scatter
microfacet lobe reflects when seen at n.v = mu, for perceptual roughness r. Computed here (pure
numpy, deterministic stratified quadrature over half vectors drawn by D(h)(n.h)) on a grid that
includes both ends, mu, r = i / (N - 1) (mu = 0 taken at the shaders' n.v floor 1e-4), so that
interpolation never clamps to an inner value (a texel-centre grid lost 6 % of a white metal's
energy at r = 1, found by tests/test_reference.py); built at first use in a fraction of a second
and cached per (D, V) pair.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from . import shading
from .programs import MS_SIZE
from .snapshot import Terms


def _half_vectors(ndf: str, alpha: float, strata: int, azimuths: int):
    """Half vectors at the midpoints of a stratified grid in (xi1, phi); pdf D(h) (n.h)."""
    xi = (np.arange(strata) + 0.5) / strata
    tan2 = alpha * alpha * (xi / (1.0 - xi) if ndf == "GGX" else -np.log1p(-xi))
    cos_t = 1.0 / np.sqrt(1.0 + tan2)
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    phi = (np.arange(azimuths) + 0.5) / azimuths * np.pi  # the lobe is symmetric about the plane
    h = np.stack([np.outer(sin_t, np.cos(phi)), np.outer(sin_t, np.sin(phi)),
                  np.outer(cos_t, np.ones_like(phi))], axis=-1)
    return h.reshape(-1, 3)


def directional_albedo(ndf: str, visibility: str, mu, roughness: float, strata: int = 512,
                       azimuths: int = 32) -> np.ndarray:
    """E(mu) for one roughness, mu an array of n.v values."""
    terms = Terms(ndf=ndf, visibility=visibility)
    r = max(roughness, shading.MIN_PERCEPTUAL_ROUGHNESS)
    alpha = r * r
    h = _half_vectors(ndf, alpha, strata, azimuths)  # (S, 3)
    mu = np.atleast_1d(np.asarray(mu, np.float64))
    v = np.stack([np.sqrt(1.0 - mu * mu), np.zeros_like(mu), mu], axis=-1)  # (M, 3)
    VoH = v @ h.T  # (M, S)
    NoH = h[:, 2][None, :]
    NoL = 2.0 * VoH * NoH - mu[:, None]  # l = 2 (v.h) h - v
    valid = (NoL > 0.0) & (VoH > 0.0)
    NoV = np.broadcast_to(mu[:, None], NoL.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        V = shading.pbr_visibility(NoV, np.maximum(NoL, 1e-12), np.broadcast_to(NoH, NoL.shape), VoH,
                                   alpha, terms)
        # E = E_h[V NoL 4 VoH / NoH] for h drawn with pdf D(h) NoH (l = reflect(v, h): dl = 4 VoH dh)
        weight = np.where(valid, V * NoL * 4.0 * VoH / NoH, 0.0)
    return weight.mean(axis=1)


@lru_cache(maxsize=16)
def albedo_table(ndf: str, visibility: str, size: int = MS_SIZE) -> np.ndarray:
    """(size, size) float32: row j = roughness j / (size - 1), column i = mu i / (size - 1)."""
    grid = np.arange(size) / (size - 1)
    mu = np.maximum(grid, shading.MIN_COS)
    table = np.stack([directional_albedo(ndf, visibility, mu, r) for r in grid])
    return table.astype(np.float32)


def interpolate(table: np.ndarray, mu, roughness) -> np.ndarray:
    """Bilinear lookup on the grid i / (N - 1): the twin of ms_albedo() in GLSL."""
    n = table.shape[0]
    x = np.clip(np.asarray(mu, np.float64) * (n - 1), 0.0, n - 1.0)
    y = np.clip(np.asarray(roughness, np.float64) * (n - 1), 0.0, n - 1.0)
    i0, j0 = np.floor(x).astype(int), np.floor(y).astype(int)
    i1, j1 = np.minimum(i0 + 1, n - 1), np.minimum(j0 + 1, n - 1)
    tx, ty = x - i0, y - j0
    t = table.astype(np.float64)
    top = t[j0, i0] * (1 - tx) + t[j0, i1] * tx
    bottom = t[j1, i0] * (1 - tx) + t[j1, i1] * tx
    return top * (1 - ty) + bottom * ty
