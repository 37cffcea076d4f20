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


def transmission_exit_fraction(cos_i, eta, roughness, spread, fresnel=True):
    """transmission_exit_fraction: the smooth fraction crossing a closed object's far face from inside
    (relative IOR 1 / eta) averaged over incidence angles theta +- s / sqrt(3), +- sqrt(3) s with
    s = ``spread`` x ``roughness`` (each angle folded at the normal and capped at grazing)."""
    cos_i, eta, roughness = (np.asarray(x, np.float64) for x in (cos_i, eta, roughness))
    c = np.clip(cos_i, 0.0, 1.0)
    sin_i = np.sqrt(1.0 - c * c)
    s = spread * roughness
    total = 0.0
    for offset in (1.0 / np.sqrt(3.0), -1.0 / np.sqrt(3.0), np.sqrt(3.0), -np.sqrt(3.0)):
        cos_k = np.maximum(c * np.cos(s * offset) - sin_i * np.sin(s * offset), 0.0)
        total = total + transmission_fraction(cos_k, 1.0 / eta, fresnel)
    return 0.25 * total


def _reflect_ggx(n, v, l, alpha):
    """D V (n.l): the GGX reflection lobe times the cosine, per unit irradiance, without Fresnel."""
    h = v + l
    h = h / np.sqrt(np.maximum(_dot(h, h), 1e-300))[..., None]
    NxH = np.cross(n, h)
    NoL = _dot(n, l)
    D = D_GGX(_dot(n, h), _dot(NxH, NxH), alpha)
    V = V_SmithGGXCorrelated(np.maximum(_dot(n, v), MIN_COS), np.maximum(NoL, MIN_COS), alpha)
    return D * V * NoL, _dot(h, v)


def transmission_exit_light(n, v, inner, exit_n, l, eta, alpha, roughness, alpha_factor, spread,
                            first=1.0, weight=1.0, tint=1.0, reflection_tint=1.0, fresnel=True):
    """transmission_exit_light per unit irradiance E arriving along l at a closed object's far face
    (unit normal ``exit_n`` facing the inside, the view ray refracted in along ``inner``; the near
    face's normal ``n`` and view ``v``): beyond that face, the mean of the far face's transmission
    lobe seen from inside along ``inner`` and the near face's towards the light's ray refracted in at
    the far face (Snell's law, irradiance crossing by cos_out / cos_in, the adjoint lobe's eta^2
    undone), each at ``alpha_factor`` x alpha, times the spread's extra loss at the far face; on the
    inside's side, the GGX reflection with the Fresnel from inside. ``first``: the first crossing's
    fraction (what of the glass enters: inside = weight x tint x first)."""
    n, v, inner, exit_n, l = (np.asarray(x, np.float64) for x in (n, v, inner, exit_n, l))
    eta = np.asarray(eta, np.float64)
    a = np.asarray(alpha, np.float64) * alpha_factor
    inside = weight * tint * np.asarray(first, np.float64)
    NoL = _dot(exit_n, l)
    lobe, HoV = transmission_ggx(exit_n, -inner, l, 1.0 / eta, a)
    far = inside * np.where(lobe > 0.0, transmission_fraction(HoV, 1.0 / eta, fresnel) * lobe, 0.0)
    u = transmission_direction(-l, -exit_n, eta)
    cos_in = _dot(u, exit_n)
    lobe2, HoV2 = transmission_ggx(n, v, -u, eta, a)
    crossings = transmission_fraction(HoV2, eta, fresnel) * transmission_fraction(-NoL, eta, fresnel)
    with np.errstate(divide="ignore", invalid="ignore"):
        near = np.where((cos_in > 0.0) & (lobe2 > 0.0),
                        tint * weight * crossings * lobe2 * (-NoL) / (eta * eta * cos_in), 0.0)
    cos2 = -_dot(inner, exit_n)
    smooth = transmission_fraction(cos2, 1.0 / eta, fresnel)
    rough = transmission_exit_fraction(cos2, eta, roughness, spread, fresnel)
    with np.errstate(divide="ignore", invalid="ignore"):
        loss = np.where(smooth > 0.0, np.minimum(rough / smooth, 1.0), 1.0)
    through = tint * 0.5 * loss * (far + near)
    reflected, HoV_r = _reflect_ggx(exit_n, -inner, l, a)
    reflected = inside * reflection_tint * np.asarray(F_Dielectric(1.0 / eta, HoV_r), np.float64) * reflected
    reflected = np.where(fresnel, reflected, 0.0)
    return np.where(NoL < 0.0, through, reflected)
