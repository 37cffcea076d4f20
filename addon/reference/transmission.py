"""Numpy twin of glsl/transmission.glsl's lobe math: the dielectric Fresnel split between
reflection and transmission, the refracted direction (Snell's law) and the GGX transmission lobe
(Walter et al. 2007, as Cycles' bsdf_microfacet_eval evaluates a glass closure's transmission).
Rows of vectors (..., 3), float64."""

from __future__ import annotations

import numpy as np

from .brdf import D_GGX, F_Dielectric, V_SmithGGXCorrelated

#: brdf.glsl's MIN_COS
MIN_COS = 1e-4


def _dot(a, b):
    return np.sum(np.asarray(a, np.float64) * np.asarray(b, np.float64), axis=-1)


def transmission_fraction(cos_i, eta, fresnel=True):
    """transmission_fraction: 1 - F (exact Fresnel, 0 under total internal reflection), or, without
    Fresnel (the Refraction BSDF), 1 but 0 under total internal reflection."""
    F = F_Dielectric(eta, cos_i)
    return np.where(fresnel, 1.0 - F, np.where(F >= 1.0, 0.0, 1.0))


def transmission_direction(d, n, eta):
    """transmission_direction: GLSL's refract(d, n, 1 / eta) -- the direction along unit d continues
    through the interface of unit normal n (facing against d) into relative IOR eta; 0 under total
    internal reflection."""
    d = np.asarray(d, np.float64)
    n = np.asarray(n, np.float64)
    ratio = 1.0 / np.asarray(eta, np.float64)
    c = _dot(n, d)
    k = 1.0 - ratio * ratio * (1.0 - c * c)
    out = ratio[..., None] * d - (ratio * c + np.sqrt(np.maximum(k, 0.0)))[..., None] * n
    return np.where((k < 0.0)[..., None], 0.0, out)


def transmission_ggx(n, v, l, eta, alpha):
    """transmission_ggx: (the lobe times |n.l| per unit irradiance without Fresnel and tint, h.v)."""
    n, v, l = (np.asarray(x, np.float64) for x in (n, v, l))
    eta = np.asarray(eta, np.float64)
    NoV, NoL = _dot(n, v), _dot(n, l)
    h = -(v + eta[..., None] * l)
    len2 = _dot(h, h)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = h / np.sqrt(np.maximum(len2, 1e-300))[..., None]
    h = np.where((_dot(h, n) < 0.0)[..., None], -h, h)
    HoV, HoL = _dot(h, v), _dot(h, l)
    NoH = _dot(n, h)
    NxH = np.cross(n, h)
    D = D_GGX(NoH, _dot(NxH, NxH), alpha)
    V = V_SmithGGXCorrelated(np.maximum(NoV, MIN_COS), np.maximum(-NoL, MIN_COS), alpha)
    denominator = HoV + eta * HoL
    lobe = 4.0 * D * V * (-NoL) * eta * eta * HoV * (-HoL) / np.maximum(denominator * denominator, 1e-12)
    valid = (NoV > 0.0) & (NoL < 0.0) & (np.abs(eta - 1.0) >= 1e-4) & (len2 > 1e-20)
    valid &= (HoV > 0.0) & (HoL < 0.0)
    return np.where(valid, lobe, 0.0), np.where(valid, HoV, 0.0)
