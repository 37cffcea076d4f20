"""Numpy twin of glsl/node_anisotropy.glsl and glsl/anisotropy.glsl: the anisotropic GGX lobe of the
Principled, Glossy and Metallic BSDFs as Cycles 5.0 sets it up (kernel/svm/closure.h,
svm_node_closure_bsdf: the stretch of alpha, the tangent rotated about the normal) and evaluates it
(kernel/closure/bsdf_microfacet.h: bsdf_aniso_D, bsdf_aniso_lambda; Heitz 2014, eqs. 85-86 and 72),
and the bent normal its isotropic stand-ins reflect about (Filament's getReflectedVector).

Vectors are (..., 3) arrays; every function broadcasts over the leading axes.
"""

from __future__ import annotations

import numpy as np


def _dot(a, b):
    return np.sum(np.asarray(a) * np.asarray(b), axis=-1)


def principled_stretch(anisotropic):
    """The Principled (and Metallic) BSDF's k: 1 / sqrt(1 - 0.9 a), a clamped to [0, 1]."""
    return 1.0 / np.sqrt(1.0 - 0.9 * np.clip(anisotropic, 0.0, 1.0))


def glossy_stretch(anisotropy):
    """The Glossy BSDF's k: a clamped to [-0.99, 0.99]; 1 - a above 0, 1 / (1 + a) below, 1 within
    1e-4 of 0."""
    a = np.clip(np.asarray(anisotropy, np.float64), -0.99, 0.99)
    k = np.where(a > 0.0, 1.0 - a, 1.0 / (1.0 + a))
    return np.where(np.abs(a) <= 1e-4, 1.0, k)


def rotate_about_axis(p, axis, angle):
    """p rotated by ``angle`` radians about the unit ``axis`` (Rodrigues; Cycles' rotate_around_axis)."""
    p, axis = np.asarray(p, np.float64), np.asarray(axis, np.float64)
    c, s = np.cos(angle)[..., None], np.sin(angle)[..., None]
    return p * c + np.cross(axis, p) * s + axis * (_dot(axis, p)[..., None] * (1.0 - c))


def tangent(t, n, rotation):
    """The closure's tangent (node_anisotropy.glsl's closure_anisotropic): t normalised (0 stays 0),
    rotated by ``rotation`` turns about the unit n."""
    t = np.asarray(t, np.float64)
    length = np.linalg.norm(t, axis=-1, keepdims=True)
    unit = np.where(length ** 2 > 1e-20, t / np.maximum(length, 1e-300), 0.0)
    return rotate_about_axis(unit, n, 2.0 * np.pi * np.asarray(rotation, np.float64))


def lobe(n, t, alpha, stretch):
    """(x, y, alpha_x, alpha_y) about the unit n (anisotropy.glsl's anisotropic_lobe): y = n x t
    normalised, x = y x n; without a direction across n (|n x t|^2 <= 1e-6 |t|^2) any frame and k = 1;
    alpha_x = alpha k, alpha_y = alpha / k, each at most 1; k within 1 / 100 .. 100, 1 where <= 0."""
    n, t = np.broadcast_arrays(np.asarray(n, np.float64), np.asarray(t, np.float64))
    y = np.cross(n, t)
    y2 = _dot(y, y)
    framed = (y2 > 1e-6 * _dot(t, t)) & (y2 > 1e-30)
    other = np.where((np.abs(n[..., 0]) < 0.9)[..., None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    y = np.where(framed[..., None], y, np.cross(n, other))
    y = y / np.linalg.norm(y, axis=-1, keepdims=True)
    x = np.cross(y, n)
    stretch = np.asarray(stretch, np.float64)
    k = np.where(framed & (stretch > 0.0), np.clip(stretch, 0.01, 100.0), 1.0)
    alpha = np.asarray(alpha, np.float64)
    return x, y, np.minimum(alpha * k, 1.0), np.minimum(alpha / k, 1.0)


def roughness(alpha_x, alpha_y):
    """(alpha_x alpha_y)^(1/4): Cycles' roughness of the lobe's compensation (and the stand-ins')."""
    return np.sqrt(np.sqrt(np.asarray(alpha_x) * np.asarray(alpha_y)))


def D(h, n, x, y, alpha_x, alpha_y):
    """GGX's anisotropic D(h) (Cycles' bsdf_aniso_D)."""
    s = np.stack([_dot(h, x) / alpha_x, _dot(h, y) / alpha_y, _dot(h, n)], -1)
    d = _dot(s, s)
    return 1.0 / (np.pi * alpha_x * alpha_y * d * d)


def Lambda(w, n, x, y, alpha_x, alpha_y):
    """Smith's Lambda towards w above the surface (Cycles' bsdf_aniso_lambda)."""
    wz = _dot(w, n)
    tan2 = ((alpha_x * _dot(w, x)) ** 2 + (alpha_y * _dot(w, y)) ** 2) / (wz * wz)
    return 0.5 * (np.sqrt(1.0 + tan2) - 1.0)


def V(v, l, n, x, y, alpha_x, alpha_y, NoV=None):
    """G2 / (4 n.v n.l) = 1 / (4 n.v n.l (1 + Lambda_v + Lambda_l)), in anisotropy.glsl's form (n.v
    floored as the surface floors it, where given)."""
    NoV = _dot(v, n) if NoV is None else NoV
    NoL = _dot(l, n)
    vx, vy = _dot(v, x), _dot(v, y)
    t2 = vx * vx + vy * vy  # v's part along the surface as the floored n.v's (below the horizon)
    scale = np.where(t2 > 0.0, np.sqrt(np.maximum(1.0 - NoV * NoV, 0.0) / np.maximum(t2, 1e-300)), 0.0)
    lv = np.sqrt((alpha_x * vx * scale) ** 2 + (alpha_y * vy * scale) ** 2 + NoV ** 2)
    ll = np.sqrt((alpha_x * _dot(l, x)) ** 2 + (alpha_y * _dot(l, y)) ** 2 + NoL ** 2)
    return 0.5 / (NoL * lv + NoV * ll)


def bent_normal(n, v, x, y, alpha_x, alpha_y, perceptual):
    """The normal the isotropic stand-ins reflect about (anisotropy.glsl's anisotropic_bent_normal):
    n leaned by |ax - ay| / (ax + ay) saturate(5 r) towards v within the plane across the short axis."""
    anisotropy = (alpha_x - alpha_y) / (alpha_x + alpha_y)
    across = np.where((anisotropy >= 0.0)[..., None], y, x)
    facing = v - across * _dot(v, across)[..., None]
    f2 = _dot(facing, facing)
    bend = (np.abs(anisotropy) * np.clip(5.0 * np.asarray(perceptual, np.float64), 0.0, 1.0))[..., None]
    unit = facing / np.sqrt(np.maximum(f2, 1e-300))[..., None]
    bent = np.where((f2 > 1e-12)[..., None], n + (unit - n) * bend, n)
    b2 = _dot(bent, bent)
    return np.where((b2 > 1e-12)[..., None], bent / np.sqrt(np.maximum(b2, 1e-300))[..., None], n)
