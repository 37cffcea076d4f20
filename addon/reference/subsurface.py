"""The twin of glsl/subsurface.glsl: the Translucent BSDF, Cycles' Christensen-Burley profile, the
subsurface's mean free path as Cycles sets it up from Radius, Scale, the method, the albedo and the
IOR, and the profile pre-integrated against a light's terminator (``ramp``)."""

from __future__ import annotations

import math

import numpy as np

INV_PI = 1.0 / math.pi

#: The Principled BSDF's and the Subsurface Scattering node's methods (Blender's enum identifiers).
METHODS = ("BURLEY", "RANDOM_WALK", "RANDOM_WALK_SKIN")

#: Cycles' BURLEY_TRUNCATE: the profile is 0 beyond 16 d (kernel/closure/bssrdf.h)
TRUNCATE = 16.0


def translucent_direct(color, n, l):
    """glsl/subsurface.glsl's translucent_direct (Cycles' bsdf_translucent_eval): colour x
    max(-n.l, 0) / pi, f (n.l) per unit irradiance."""
    cos = np.maximum(-np.sum(np.asarray(n, np.float64) * np.asarray(l, np.float64), axis=-1), 0.0)
    return np.asarray(color, np.float64) * (cos * INV_PI)[..., None]


def dipole_rd(alpha_prime, fourthird_a):
    """Cycles' bssrdf_dipole_compute_Rd: the diffuse reflectance of a dipole of single-scattering
    albedo alpha' (Jensen et al. 2001)."""
    s = np.sqrt(3.0 * (1.0 - alpha_prime))
    return 0.5 * alpha_prime * (1.0 + np.exp(-fourthird_a * s)) * np.exp(-s)


def fourthird_a(ior):
    """4/3 A of Jensen's internal reflection (the F_dr fit), as Cycles' bssrdf_setup_radius."""
    inv_eta = 1.0 / ior
    f_dr = inv_eta * (-1.440 * inv_eta + 0.710) + 0.668 + 0.0636 * ior
    return (4.0 / 3.0) * (1.0 + f_dr) / (1.0 - f_dr)


def dipole_alpha_prime(rd, ior):
    """Cycles' bssrdf_dipole_compute_alpha_prime: the alpha' whose dipole reflects ``rd``, by its 12
    bisection steps (0 below 1e-4, 0.999999 from 0.995); per element."""
    rd = np.asarray(rd, np.float64)
    a = fourthird_a(np.asarray(ior, np.float64))
    x0, x1 = np.zeros_like(rd), np.ones_like(rd)
    xmid = np.zeros_like(rd)
    for _ in range(12):
        xmid = 0.5 * (x0 + x1)
        low = dipole_rd(xmid, a) < rd
        x0, x1 = np.where(low, xmid, x0), np.where(low, x1, xmid)
    return np.where(rd < 1e-4, 0.0, np.where(rd >= 0.995, 0.999999, xmid))


def mean_free_path(radius, scale, method="RANDOM_WALK", albedo=(0.8, 0.8, 0.8), ior=1.4):
    """(3,) the profile's d per channel (m) as Cycles' bssrdf_setup_radius sets it: Radius x Scale
    (at least 0) over 4 pi for Christensen-Burley and Random Walk, times sqrt(3 (1 - alpha')) of
    the dipole that reflects the albedo for Random Walk (Skin); IOR within [1.01, 3.8]
    (bssrdf_setup's clamp)."""
    r = np.maximum(np.asarray(radius, np.float64) * float(scale), 0.0)
    if method != "RANDOM_WALK_SKIN":
        return r * (0.25 * INV_PI)
    ior = min(max(float(ior), 1.01), 3.8)
    alpha_prime = dipole_alpha_prime(np.clip(np.asarray(albedo, np.float64), 0.0, 1.0), ior)
    return r * np.sqrt(3.0 * (1.0 - alpha_prime))


def burley_radial(d, r):
    """Cycles' bssrdf_burley_eval: the profile's density per unit radius r (the 2D density times
    2 pi r), (e^{-r/d} + e^{-r/3d}) / 4d, 0 beyond TRUNCATE d; it integrates to about 1 (0.99638)."""
    d = np.asarray(d, np.float64)
    r = np.asarray(r, np.float64)
    e = np.exp(-r / (3.0 * d))
    return np.where(r < TRUNCATE * d, (e * e * e + e) / (4.0 * d), 0.0)


def burley_cdf(d, r):
    """The profile's share within radius r (untruncated): 1 - e^{-r/d} / 4 - 3 e^{-r/3d} / 4."""
    return 1.0 - 0.25 * np.exp(-r / d) - 0.75 * np.exp(-r / (3.0 * d))


#: subsurface_bickley's rational fit of Ki_2 (exp(-y) (1 + a y + b y^2) / (1 + c y + e y^2))
BICKLEY_FIT = (2.79411438, 0.3249977, 3.33465849, 1.20353839)


def bickley(y):
    """glsl/subsurface.glsl's subsurface_bickley: Ki_2(y) / pi by the fit."""
    y = np.asarray(y, np.float64)
    a, b, c, e = BICKLEY_FIT
    return np.exp(-y) * (1.0 + y * (a + b * y)) / (math.pi * (1.0 + y * (c + e * y)))


def ramp(NoL, d, curvature):
    """glsl/subsurface.glsl's subsurface_ramp: max(n.l, 0) convolved with the profile of width d
    (m; (..., 3) per channel) on a surface of curvature ``curvature`` (1/m), (..., 3)."""
    NoL = np.asarray(NoL, np.float64)[..., None]
    rho = np.minimum(np.asarray(d, np.float64) * np.asarray(curvature, np.float64)[..., None], 1.0)
    a = np.abs(NoL)
    with np.errstate(divide="ignore", invalid="ignore"):
        near = 0.25 * rho * bickley(a / rho) + 2.25 * rho * bickley(a / (3.0 * rho))
    return np.maximum(NoL, 0.0) + np.where(rho > 0.0, near, 0.0)
