"""Directional albedo tables for specular energy compensation (glsl/multiscatter.glsl).

E(mu, r) = integral over l of D V (n.l) with F = 1: the fraction of light a white single-scatter
microfacet lobe reflects when seen at n.v = mu, for perceptual roughness r. Computed here (pure
numpy, deterministic stratified quadrature over half vectors drawn by D(h)(n.h)) on a grid that
includes both ends, mu, r = i / (N - 1) (mu = 0 taken at the shaders' n.v floor 1e-4), so that
interpolation never clamps to an inner value (a texel-centre grid lost 6 % of a white metal's
energy at r = 1, found by tests/test_reference.py).

The tables take seconds to compute (the Principled set's ~8 s on two cores), so they ship as data:
``tables.npz`` beside this file, written by ``scripts/build_tables.py`` from the ``compute_*``
functions here (tests/test_tables.py checks that the shipped tables equal what they compute). A
table missing from the file, or asked for at another size, is computed and cached.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from ..scene.snapshot import TERM_CHOICES, Terms, f0_from_ior
from . import brdf

#: Side of the multiple-scattering albedo table, in texels.
MS_SIZE = 32
#: Side of the Principled set's 3D table S(r, mu, z), as Cycles' (16^3).
S_SIZE = 16


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


def _albedo_samples(ndf: str, visibility: str, mu, roughness: float, strata: int, azimuths: int):
    """Per half-vector sample of the quadrature: (weight, v.h), with E(mu) = mean(weight)."""
    terms = Terms(ndf=ndf, visibility=visibility)
    r = max(roughness, brdf.MIN_PERCEPTUAL_ROUGHNESS)
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
        V = brdf.pbr_visibility(NoV, np.maximum(NoL, 1e-12), np.broadcast_to(NoH, NoL.shape), VoH,
                                   alpha, terms)
        # E = E_h[V NoL 4 VoH / NoH] for h drawn with pdf D(h) NoH (l = reflect(v, h): dl = 4 VoH dh)
        weight = np.where(valid, V * NoL * 4.0 * VoH / NoH, 0.0)
    return weight, VoH


def directional_albedo(ndf: str, visibility: str, mu, roughness: float, strata: int = 512,
                       azimuths: int = 32) -> np.ndarray:
    """E(mu) for one roughness, mu an array of n.v values."""
    return _albedo_samples(ndf, visibility, mu, roughness, strata, azimuths)[0].mean(axis=1)


SHIPPED = Path(__file__).with_name("tables.npz")


@lru_cache(maxsize=1)
def _shipped() -> dict[str, np.ndarray]:
    """The shipped tables by name ({} when the file is missing or unreadable: they are computed)."""
    try:
        with np.load(SHIPPED, allow_pickle=False) as data:
            return {name: data[name] for name in data.files}
    except (OSError, ValueError):
        return {}


def _table(name: str, shape: tuple, compute) -> np.ndarray:
    shipped = _shipped().get(name)
    if shipped is not None and shipped.shape == shape:
        return shipped
    return compute()


def split_sum_table(ndf: str, visibility: str, size: int = MS_SIZE) -> np.ndarray:
    """``compute_split_sum_table``, shipped."""
    return _table(f"split_{ndf}_{visibility}", (size, size, 4),
                  lambda: compute_split_sum_table(ndf, visibility, size))


def albedo_table(ndf: str, visibility: str, size: int = MS_SIZE) -> np.ndarray:
    """``compute_albedo_table``, shipped."""
    return _table(f"albedo_{ndf}_{visibility}", (size, size),
                  lambda: compute_albedo_table(ndf, visibility, size))


def average_albedo(size: int = MS_SIZE) -> np.ndarray:
    """``compute_average_albedo``, shipped."""
    return _table("average_albedo", (size,), lambda: compute_average_albedo(size))


def principled_s_table(size: int = S_SIZE) -> np.ndarray:
    """``compute_principled_s_table``, shipped."""
    return _table("principled_s", (size, size, size), lambda: compute_principled_s_table(size))


def compute_all() -> dict[str, np.ndarray]:
    """Every table the engine uses, by its name in ``tables.npz``."""
    out = {}
    for ndf in TERM_CHOICES["ndf"]:
        for visibility in TERM_CHOICES["visibility"]:
            out[f"albedo_{ndf}_{visibility}"] = compute_albedo_table(ndf, visibility)
            out[f"split_{ndf}_{visibility}"] = compute_split_sum_table(ndf, visibility)
    out["average_albedo"] = compute_average_albedo()
    out["principled_s"] = compute_principled_s_table()
    return out


@lru_cache(maxsize=16)
def compute_split_sum_table(ndf: str, visibility: str, size: int = MS_SIZE) -> np.ndarray:
    """(size, size, 4) float32 on the grid of ``albedo_table``: E(mu, r) and B(mu, r), the part of
    the albedo carried by Schlick's (1 - v.h)^5, so that a Schlick-Fresnel lobe reflects
    F0 (E - B) + F90 B of a uniform environment (Karis 2013's split sum, second factor)."""
    grid = np.arange(size) / (size - 1)
    mu = np.maximum(grid, brdf.MIN_COS)
    out = np.zeros((size, size, 4), np.float32)
    for j, r in enumerate(grid):
        weight, VoH = _albedo_samples(ndf, visibility, mu, r, 512, 32)
        out[j, :, 0] = weight.mean(axis=1)
        out[j, :, 1] = (weight * brdf.pow5(1.0 - np.clip(VoH, 0.0, 1.0))).mean(axis=1)
    return out


@lru_cache(maxsize=16)
def compute_albedo_table(ndf: str, visibility: str, size: int = MS_SIZE) -> np.ndarray:
    """(size, size) float32: row j = roughness j / (size - 1), column i = mu i / (size - 1)."""
    grid = np.arange(size) / (size - 1)
    mu = np.maximum(grid, brdf.MIN_COS)
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


# --- Blender's Principled BSDF (Cycles 5.0) ------------------------------------------------------
#
# The "Principled" term set reproduces Cycles' Principled BSDF for opaque materials: per-lobe
# multiple-scattering compensation M = 1 + Fms (1 - E) / E with Kulla & Conty 2017's
# Fms = Fss Eavg / (1 - Fss (1 - Eavg)), and the diffuse base weighted by 1 - the dielectric
# specular layer's estimated albedo E M mix(F0, 1, S). E, Eavg and S are defined as Cycles
# defines its tables (scene/shader.tables, app/cycles_precompute.cpp) and computed here.

@lru_cache(maxsize=4)
def compute_average_albedo(size: int = MS_SIZE, samples: int = 64) -> np.ndarray:
    """Eavg(r) = integral_0^1 2 mu E(mu) dmu for GGX + Smith height-correlated, on r = j / (N - 1)."""
    grid = np.arange(size) / (size - 1)
    mu = (np.arange(samples) + 0.5) / samples  # midpoint rule in mu
    return np.array([np.mean(2.0 * mu * directional_albedo("GGX", "SMITH_CORRELATED", mu, r))
                     for r in grid], np.float32)


def _vndf_half_vectors(alpha: float, mu: float, n: int) -> np.ndarray:
    """Half vectors distributed as GGX's visible normals for the view (sqrt(1 - mu^2), 0, mu)
    (Heitz 2018, "Sampling the GGX Distribution of Visible Normals"), on an n x n stratified grid."""
    u1, u2 = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n, indexing="ij")
    u1, u2 = u1.ravel(), u2.ravel()
    vh = np.array([alpha * np.sqrt(max(1.0 - mu * mu, 0.0)), 0.0, mu])
    vh /= np.linalg.norm(vh)
    lensq = vh[0] ** 2 + vh[1] ** 2
    t1 = np.array([-vh[1], vh[0], 0.0]) / np.sqrt(lensq) if lensq > 0 else np.array([1.0, 0.0, 0.0])
    t2 = np.cross(vh, t1)
    radius, phi = np.sqrt(u1), 2.0 * np.pi * u2
    p1, p2 = radius * np.cos(phi), radius * np.sin(phi)
    s = 0.5 * (1.0 + vh[2])
    p2 = (1.0 - s) * np.sqrt(np.maximum(1.0 - p1 * p1, 0.0)) + s * p2
    nh = (p1[:, None] * t1 + p2[:, None] * t2
          + np.sqrt(np.maximum(1.0 - p1 * p1 - p2 * p2, 0.0))[:, None] * vh)
    ne = np.column_stack([alpha * nh[:, 0], alpha * nh[:, 1], np.maximum(nh[:, 2], 0.0)])
    return ne / np.linalg.norm(ne, axis=1, keepdims=True)


@lru_cache(maxsize=2)
def compute_principled_s_table(size: int = S_SIZE, strata: int = 48) -> np.ndarray:
    """S[k, j, i] (z, mu, r): the VNDF expectation of saturate((F(wi.h, ior) - F0) / (1 - F0)) over
    half vectors whose reflection stays above the surface, with ior = (1 + z^2) / (1 - z^2); grid
    r, mu = i / (N - 1) clamped to [1e-4, 1], z = k / (N - 1) clamped to [1e-4, 0.99]."""
    grid = np.arange(size) / (size - 1)
    out = np.zeros((size, size, size), np.float32)
    for k, z in enumerate(np.clip(grid, 1e-4, 0.99)):
        ior = (1.0 + z * z) / (1.0 - z * z)
        f0 = f0_from_ior(ior)
        for j, mu in enumerate(np.clip(grid, 1e-4, 1.0)):
            v = np.array([np.sqrt(1.0 - mu * mu), 0.0, mu])
            for i, r in enumerate(np.clip(grid, 1e-4, 1.0)):
                h = _vndf_half_vectors(r * r, mu, strata)
                voh = h @ v
                l_z = 2.0 * voh * h[:, 2] - mu
                fresnel = brdf.F_Dielectric(ior, voh)
                s = np.clip((fresnel - f0) / (1.0 - f0), 0.0, 1.0)
                out[k, j, i] = np.mean(np.where(l_z > 0.0, s, 0.0))
    return out


def principled_fss(eta):
    """Kulla & Conty 2017's fit of the average dielectric Fresnel, as Cycles uses it (eta >= 1)."""
    eta = np.asarray(eta, np.float64)
    return (eta - 1.0) / (4.08567 + 1.00071 * eta)


def principled_compensation(fss, E, e_avg):
    """M = 1 + Fms (1 - E) / E with Fms = Fss Eavg / (1 - Fss (1 - Eavg)) (Kulla & Conty 2017)."""
    fms = fss * e_avg / (1.0 - fss * (1.0 - e_avg))
    return 1.0 + fms * (1.0 - E) / E


def interpolate_1d(values: np.ndarray, x) -> np.ndarray:
    n = len(values)
    t = np.clip(np.asarray(x, np.float64) * (n - 1), 0.0, n - 1.0)
    i0 = np.floor(t).astype(int)
    i1 = np.minimum(i0 + 1, n - 1)
    w = t - i0
    return values[i0] * (1 - w) + values[i1] * w


def interpolate_s(table: np.ndarray, roughness, mu, z) -> np.ndarray:
    """Trilinear lookup of ``principled_s_table`` (grid i / (N - 1) on each axis)."""
    n = table.shape[0]
    coords = [np.clip(np.asarray(c, np.float64) * (n - 1), 0.0, n - 1.0) for c in (z, mu, roughness)]
    lo = [np.floor(c).astype(int) for c in coords]
    hi = [np.minimum(i + 1, n - 1) for i in lo]
    w = [c - i for c, i in zip(coords, lo)]
    t = table.astype(np.float64)
    out = 0.0
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                idx = tuple((hi if d else lo)[a] for a, d in enumerate((dz, dy, dx)))
                weight = ((w[0] if dz else 1 - w[0]) * (w[1] if dy else 1 - w[1])
                          * (w[2] if dx else 1 - w[2]))
                out = out + t[idx] * weight
    return out
