"""The numpy twin of the BRDF terms: ``glsl/common.glsl``, ``glsl/brdf.glsl`` and the term
dispatchers of ``glsl/pbr_terms.glsl`` that depend on the terms alone, function for function.

Inputs are arrays ((..., 3) for vectors and colours, (...) for scalars), evaluated in float64. The
tables of ``multiscatter.py`` are integrals of these terms and the models of ``shading.py``
compose them with those tables: the imports read one way, brdf -> multiscatter -> shading. Pure
numpy: no ``bpy``, no ``gpu``.
"""

from __future__ import annotations

import numpy as np

from ..scene.snapshot import Terms

PI = np.pi
INV_PI = 1.0 / np.pi
MIN_PERCEPTUAL_ROUGHNESS = 0.045
MIN_COS = 1e-4


def _dot(a, b):
    return np.sum(np.asarray(a) * np.asarray(b), axis=-1)


def saturate(x):
    return np.clip(x, 0.0, 1.0)


def pow5(x):
    x2 = x * x
    return x2 * x2 * x


# --- BRDF terms (glsl/brdf.glsl) ---------------------------------------------------------------

def _rgb_scalar(x):
    return np.asarray(x, np.float64)[..., None]


def F_Schlick(f0, f90, LoH):
    """Eq. 1.11 (F90 = 1) / eq. 1.13 with p = 1/5, on l.h."""
    f0 = np.asarray(f0, np.float64)
    return f0 + (_rgb_scalar(f90) - f0) * _rgb_scalar(pow5(1.0 - np.asarray(LoH, np.float64)))


def F_SchlickSG(f0, f90, LoH):
    """Eq. 1.12."""
    LoH = np.asarray(LoH, np.float64)
    f0 = np.asarray(f0, np.float64)
    return f0 + (_rgb_scalar(f90) - f0) * _rgb_scalar(np.exp2((-5.55473 * LoH - 6.98316) * LoH))


def F_SchlickGeneral(f0, f90, p, LoH):
    """Eq. 1.13."""
    f0 = np.asarray(f0, np.float64)
    base = np.maximum(1.0 - np.asarray(LoH, np.float64), 0.0)
    return f0 + (_rgb_scalar(f90) - f0) * _rgb_scalar(base ** (1.0 / np.asarray(p, np.float64)))


def F_Dielectric(eta, cos_i):
    """Exact unpolarised dielectric Fresnel (Walter et al. 2007, eq. 22); 1 under total internal
    reflection, 0 for eta = 1 (no interface) even at c = 0."""
    c = np.abs(np.asarray(cos_i, np.float64))
    g2 = np.asarray(eta, np.float64) ** 2 - 1.0 + c * c
    g = np.sqrt(np.maximum(g2, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (g - c) / (g + c)
        b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
        f = 0.5 * a * a * (1.0 + b * b)
    return np.where(g2 <= 0.0, np.where(np.asarray(eta) < 1.0, 1.0, 0.0), f)  # eta = 1, c = 0: no interface


def F_Conductor(n, k, cos_i):
    """Exact unpolarised conductor Fresnel per channel (PBRT 3rd ed., FrConductor, from air)."""
    n = np.asarray(n, np.float64)
    k = np.asarray(k, np.float64)
    c = _rgb_scalar(np.clip(cos_i, 0.0, 1.0))
    c2 = c * c
    s2 = 1.0 - c2
    t0 = n * n - k * k - s2
    a2b2 = np.sqrt(t0 * t0 + 4.0 * n * n * k * k)
    a = np.sqrt(np.maximum(0.5 * (a2b2 + t0), 0.0))
    t1 = a2b2 + c2
    t2 = 2.0 * c * a
    rs = (t1 - t2) / np.maximum(t1 + t2, 1e-30)
    t3 = c2 * a2b2 + s2 * s2
    t4 = t2 * s2
    rp = rs * (t3 - t4) / np.maximum(t3 + t4, 1e-30)
    return 0.5 * (rp + rs)


def D_GGX(NoH, NxH2, alpha):
    """Eq. 1.15 in the |n x h|^2 form."""
    a = NoH * alpha
    k = alpha / (NxH2 + a * a)
    return k * k * INV_PI


def D_Beckmann(NoH, NxH2, alpha):
    """Eq. 1.14."""
    NoH = np.asarray(NoH, np.float64)
    a2 = alpha * alpha
    c2 = NoH * NoH
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        d = np.exp(-np.asarray(NxH2) / (a2 * c2)) / (PI * a2 * c2 * c2)
    return np.where(NoH >= 0.1, d, 0.0)  # see glsl: below 0.1 D < 3e-40


def V_SmithGGXCorrelated(NoV, NoL, alpha):
    """Eqs. 1.16-1.17 divided by 4 NoV NoL."""
    a2 = alpha * alpha
    lambda_v = NoL * np.sqrt(NoV * NoV * (1.0 - a2) + a2)
    lambda_l = NoV * np.sqrt(NoL * NoL * (1.0 - a2) + a2)
    return 0.5 / (lambda_v + lambda_l)


def V_SmithGGXSeparable(NoV, NoL, alpha):
    a2 = alpha * alpha
    gv = NoV + np.sqrt(a2 + (1.0 - a2) * NoV * NoV)
    gl = NoL + np.sqrt(a2 + (1.0 - a2) * NoL * NoL)
    return 1.0 / (gv * gl)


def Lambda_Beckmann(NoX, alpha):
    NoX = np.asarray(NoX, np.float64)
    s2 = np.maximum(1.0 - NoX * NoX, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.maximum(NoX / (alpha * np.sqrt(s2)), 1e-7)
        lam = (1.0 - 1.259 * a + 0.396 * a * a) / (3.535 * a + 2.181 * a * a)
    return np.where((s2 <= 0.0) | (a >= 1.6), 0.0, lam)


def V_SmithBeckmannCorrelated(NoV, NoL, alpha):
    G = 1.0 / (1.0 + Lambda_Beckmann(NoV, alpha) + Lambda_Beckmann(NoL, alpha))
    return G / (4.0 * NoV * NoL)


def V_SmithBeckmannSeparable(NoV, NoL, alpha):
    G = 1.0 / ((1.0 + Lambda_Beckmann(NoV, alpha)) * (1.0 + Lambda_Beckmann(NoL, alpha)))
    return G / (4.0 * NoV * NoL)


def V_CookTorrance(NoV, NoL, NoH, VoH):
    G = np.minimum(1.0, 2.0 * NoH * np.minimum(NoV, NoL) / np.maximum(VoH, MIN_COS))
    return G / (4.0 * NoV * NoL)


def V_SmithGGXHammon(NoV, NoL, alpha):
    return 0.5 / (2.0 * NoL * NoV + alpha * (NoL + NoV - 2.0 * NoL * NoV))


def V_SchlickBeckmann(NoV, NoL, alpha):
    k = alpha * 0.7978845608
    return 0.25 / ((NoV * (1.0 - k) + k) * (NoL * (1.0 - k) + k))


def Fd_Lambert():
    return INV_PI


def Fd_Burley(NoV, NoL, LoH, roughness):
    f90 = 0.5 + 2.0 * roughness * LoH * LoH
    return (1.0 + (f90 - 1.0) * pow5(1.0 - NoL)) * (1.0 + (f90 - 1.0) * pow5(1.0 - NoV)) * INV_PI


def Fd_BurleyRenormalized(NoV, NoL, LoH, roughness):
    energy_bias = 0.5 * roughness
    energy_factor = 1.0 + roughness * (1.0 / 1.51 - 1.0)
    f90 = energy_bias + 2.0 * LoH * LoH * roughness
    light = 1.0 + (f90 - 1.0) * pow5(1.0 - NoL)
    view = 1.0 + (f90 - 1.0) * pow5(1.0 - NoV)
    return light * view * energy_factor * INV_PI


def Fd_OrenNayar(rho, NoV, NoL, cos_phi, roughness):
    rho = np.asarray(rho, np.float64)
    s2 = roughness * roughness
    theta_i = np.arccos(np.clip(NoL, -1.0, 1.0))
    theta_r = np.arccos(np.clip(NoV, -1.0, 1.0))
    alpha = np.maximum(theta_i, theta_r)
    beta = np.minimum(theta_i, theta_r)
    C1 = 1.0 - 0.5 * s2 / (s2 + 0.33)
    C2 = 0.45 * s2 / (s2 + 0.09) * np.where(cos_phi >= 0.0, np.sin(alpha),
                                             np.sin(alpha) - (2.0 * beta / PI) ** 3)
    C3 = 0.125 * (s2 / (s2 + 0.09)) * (4.0 * alpha * beta / (PI * PI)) ** 2
    L1 = (C1 + cos_phi * C2 * np.tan(np.minimum(beta, 1.5))
          + (1.0 - np.abs(cos_phi)) * C3 * np.tan(np.minimum(0.5 * (alpha + beta), 1.5)))
    L2 = 0.17 * s2 / (s2 + 0.13) * (1.0 - cos_phi * (2.0 * beta / PI) ** 2)
    return (rho * _rgb_scalar(L1) + rho * rho * _rgb_scalar(L2)) * INV_PI


def Fd_GGXHammon(rho, NoV, NoL, NoH, LoV, alpha):
    rho = np.asarray(rho, np.float64)
    facing = 0.5 + 0.5 * LoV
    rough = facing * (0.9 - 0.4 * facing) * ((0.5 + NoH) / np.maximum(NoH, MIN_COS))
    smooth = 1.05 * (1.0 - pow5(1.0 - NoL)) * (1.0 - pow5(1.0 - NoV))
    single = smooth + alpha * (rough - smooth)
    multi = 0.1159 * np.asarray(alpha, np.float64)
    return rho * (_rgb_scalar(single) + rho * _rgb_scalar(multi)) * INV_PI


def S_BlinnPhong(NoH, shininess):
    return np.power(np.maximum(NoH, 0.0), shininess)


def S_Phong(n, l, v, shininess):
    r = 2.0 * _dot(n, l)[..., None] * n - l
    return np.power(np.maximum(_dot(r, v), 0.0), shininess)


def S_BlinnPhongNormalized(NoH, shininess):
    return (shininess + 8.0) / (8.0 * PI) * np.power(np.maximum(NoH, 0.0), shininess)


def half_vector(l, v, n):
    s = l + v
    len2 = _dot(s, s)
    safe = np.where(len2 > 1e-12, len2, 1.0)
    return np.where((len2 > 1e-12)[..., None], s / np.sqrt(safe)[..., None], n)



# --- term dispatchers (glsl/pbr_terms.glsl) -----------------------------------------------------

def pbr_distribution(NoH, NxH2, alpha, terms: Terms):
    return (D_Beckmann if terms.ndf == "BECKMANN" else D_GGX)(NoH, NxH2, alpha)


def pbr_visibility(NoV, NoL, NoH, LoH, alpha, terms: Terms):
    if terms.visibility == "VCAVITY":
        return V_CookTorrance(NoV, NoL, NoH, LoH)
    table = {
        ("GGX", "SMITH_CORRELATED"): V_SmithGGXCorrelated,
        ("GGX", "SMITH_SEPARABLE"): V_SmithGGXSeparable,
        ("GGX", "APPROX"): V_SmithGGXHammon,
        ("BECKMANN", "SMITH_CORRELATED"): V_SmithBeckmannCorrelated,
        ("BECKMANN", "SMITH_SEPARABLE"): V_SmithBeckmannSeparable,
        ("BECKMANN", "APPROX"): V_SchlickBeckmann,
    }
    return table[terms.ndf, terms.visibility](NoV, NoL, alpha)
