"""Numpy twin of glsl/node_anisotropy.glsl and glsl/anisotropy.glsl: the anisotropic GGX lobe of the
Principled, Glossy and Metallic BSDFs as Cycles 5.0 sets it up (kernel/svm/closure.h,
svm_node_closure_bsdf: the stretch of alpha, the tangent rotated about the normal) and evaluates it
(kernel/closure/bsdf_microfacet.h: bsdf_aniso_D, bsdf_aniso_lambda; Heitz 2014, eqs. 85-86 and 72),
and the bent normal its isotropic stand-ins reflect about (Filament's getReflectedVector).

Lights with a size and the world (``polygon_integral``, ``sample``): the lobe by its visible normals,
a clamped cosine in the hemisphere configuration (Heitz 2018), integrated over a light's polygon in
closed form, sampled over the world.

Vectors are (..., 3) arrays; every function broadcasts over the leading axes.
"""

from __future__ import annotations

import math

import numpy as np

from .brdf import MIN_PERCEPTUAL_ROUGHNESS


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


# --- lights with a size: the lobe's integral over a polygon ------------------------------------------

def _stretched_half(u, v, n, x, y, alpha_x, alpha_y):
    """The half vector of the unit u and v in the lobe's hemisphere configuration, (h.x / ax, h.y / ay,
    h.n) with h = u + v (any length: only its direction counts)."""
    h = u + v
    return np.stack([_dot(h, x) / alpha_x, _dot(h, y) / alpha_y, _dot(h, n)], -1)


def _edge_term(a, b, u):
    """theta g . u of the spherical edge from direction a to b (any lengths): the angle between them
    times the unit normal of their plane, along u (Arvo 1995's edge term)."""
    c = np.cross(a, b)
    s = np.linalg.norm(c, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(s > 0.0, np.arctan2(s, _dot(a, b)) / np.where(s > 0.0, s, 1.0) * _dot(c, u), 0.0)


def _unit(w):
    length = np.linalg.norm(w, axis=-1, keepdims=True)
    return w / np.where(length > 0.0, length, 1.0)


def visible_view(v, n, NoV):
    """v with its height above the surface floored as the surface floors n.v (``V``'s rule): its part
    along the surface scaled to sqrt(1 - n.v^2); n where v has none."""
    vt = v - n * _dot(v, n)[..., None]
    t2 = _dot(vt, vt)
    scale = np.sqrt(np.maximum(1.0 - NoV * NoV, 0.0) / np.where(t2 > 1e-20, t2, 1.0))
    return np.where((t2 > 1e-20)[..., None], n * np.asarray(NoV)[..., None] + vt * scale[..., None], n)


#: A light's edge is split into pieces whose chords between unit directions are at most this long (~ the
#: angle, radians), up to POLYGON_PIECES of them (``polygon_integral``; anisotropy.glsl's ANISOTROPIC_PIECE)
POLYGON_PIECE = 0.15
POLYGON_PIECES = 16


def polygon_integral(n, v, NoV, x, y, alpha_x, alpha_y, offsets, to_centre, jitter=None):
    """The lobe's integral over a light's polygon, int_P D V (n.l) dl (F = 1; anisotropy.glsl's
    anisotropic_polygon): each edge of the polygon (corners to_centre + offsets from the points,
    (..., k, 3)) clipped at the horizon, and last the horizon's own edge where the outline crossed it,
    split into pieces (chords of at most POLYGON_PIECE between unit directions), each piece's half
    vectors mapped to the hemisphere configuration and the visible normals' clamped cosine integrated
    over them in closed form (Arvo's edge terms); times G2 / G1(v) at the clipped outline's
    length-weighted mean.
    ``jitter`` (roundings, unit directions (..., 3)), for tests: the corners and each piece's unit
    direction moved along the directions (alternately +-) by that many float32 roundings of their length,
    and the edge terms' sum by as many of each term (ltc.ltc_integral's): the errors float32 leaves there
    (tests/test_stability.py) -- the half vector u + v cancels where a direction nears -v (a grazing
    view's mirror direction), where one rounding of u moves a narrow lobe's h by eps / |u + v|."""
    n, v = np.asarray(n, np.float64), np.asarray(v, np.float64)
    corners = np.asarray(to_centre, np.float64)[..., None, :] + np.asarray(offsets, np.float64)
    shape = np.broadcast_shapes(np.shape(n), corners.shape[:-2] + (3,))
    n, v, x, y = (np.broadcast_to(a, shape) for a in (n, v, x, y))
    alpha_x, alpha_y = np.broadcast_to(alpha_x, shape[:-1]), np.broadcast_to(alpha_y, shape[:-1])
    corners = np.broadcast_to(corners, shape[:-1] + corners.shape[-2:])
    unit = 0.0
    if jitter is not None:  # as many roundings of each corner's coordinates
        roundings, direction = jitter
        unit = roundings * float(np.finfo(np.float32).eps) / 2.0
        sign = np.where(np.arange(corners.shape[-2]) % 2 == 0, 1.0, -1.0)[:, None]
        corners = corners + (unit * np.linalg.norm(corners, axis=-1, keepdims=True) * sign
                             * np.asarray(direction, np.float64)[..., None, :])
    ve = visible_view(v, n, np.broadcast_to(NoV, shape[:-1]))
    vh = _unit(np.stack([alpha_x * _dot(ve, x), alpha_y * _dot(ve, y), _dot(ve, n)], -1))
    frame = (ve, n, x, y, alpha_x, alpha_y)
    total = np.zeros(shape[:-1])
    terms = np.zeros(shape[:-1])  # sum |term|, the scale of the sum's roundings
    mean = np.zeros(shape)
    sides = corners.shape[-2]
    height = np.sum(corners * n[..., None, :], axis=-1)
    leaves, returns, left = n, n, np.zeros(shape[:-1], bool)
    for i in range(sides + 1):
        a, b = corners[..., i - 1, :], corners[..., min(i, sides - 1), :]
        h_a, h_b = height[..., i - 1], height[..., min(i, sides - 1)]
        above_a, above_b = h_a > 0.0, h_b > 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            t = h_a / np.where(above_a != above_b, h_a - h_b, 1.0)
        cut = a + (b - a) * t[..., None]
        left = left | (above_a & ~above_b)
        leaves = np.where((above_a & ~above_b)[..., None], cut, leaves)
        returns = np.where((~above_a & above_b)[..., None], cut, returns)
        horizon = i == sides
        on = left if horizon else above_a | above_b
        p_a = leaves if horizon else np.where(above_a[..., None], a, cut)
        p_b = returns if horizon else np.where(above_b[..., None], b, cut)
        u_a = np.where(on[..., None], _unit(p_a), n)
        u_b = np.where(on[..., None], _unit(p_b), n)
        if jitter is not None:  # the ends rounded (a horizon edge's are near opposite: their mean cancels)
            u_a = u_a + unit * np.asarray(direction, np.float64)
            u_b = u_b - unit * np.asarray(direction, np.float64)
        chord = np.linalg.norm(u_b - u_a, axis=-1)
        pieces = np.clip(np.ceil(chord / POLYGON_PIECE), 1, POLYGON_PIECES)
        w = _stretched_half(u_a, *frame)
        for j in range(1, int(pieces.max(initial=1)) + 1):
            now = j <= pieces
            u = _unit(u_a + (u_b - u_a) * (j / pieces)[..., None])
            if jitter is not None:  # each piece's direction rounded (h = u + v cancels where u ~ -v)
                u = u + unit * (1.0 if j % 2 else -1.0) * np.asarray(direction, np.float64)
            w_next = _stretched_half(u, *frame)
            term = np.where(now, _edge_term(w, w_next, vh), 0.0)
            total += term
            terms += np.abs(term)
            middle = (u_a + (u_b - u_a) * ((j - 0.5) / pieces)[..., None]) * (chord / pieces)[..., None]
            mean += np.where((on & now)[..., None], middle, 0.0)  # (the pieces' length-weighted mean)
            w = np.where(now[..., None], w_next, w)
    if jitter is not None:
        total = total + unit * terms * np.sign(total) * np.asarray(direction, np.float64)[..., 2]
    visible = np.abs(total) / (np.pi * (1.0 + vh[..., 2]))
    l = _unit(mean)
    lam_v = Lambda(ve, n, x, y, alpha_x, alpha_y)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam_l = Lambda(l, n, x, y, alpha_x, alpha_y)
        g = (1.0 + lam_v) / (1.0 + lam_v + lam_l)
    return np.where(_dot(mean, n) > 0.0, visible * g, 0.0)


def widened(alpha_x, alpha_y, alpha, alpha_wide):
    """The lobe of a sphere light's widened stand-in (anisotropy.glsl's anisotropic_widened): each axis
    widened by the disc alike, in quadrature, at most 1."""
    theta2 = np.maximum(np.asarray(alpha_wide) ** 2 - np.asarray(alpha) ** 2, 0.0)
    return tuple(np.minimum(np.sqrt(np.asarray(a) ** 2 + theta2), 1.0) for a in (alpha_x, alpha_y))


# --- the world: samples of the visible normals ---------------------------------------------------------

#: The world's split-sum light through the lobe reads at most this many strips of its visible normals
#: (anisotropy.glsl's ANISOTROPIC_WORLD_STRIPS: one per aspect, ``strips``) and weighs their light by its
#: albedo over this many of them (ANISOTROPIC_WORLD_ALBEDO).
WORLD_STRIPS = 8
WORLD_ALBEDO = 16
GOLDEN_FRACTION = 0.61803399


def view(n, v, NoV, x, y, alpha_x, alpha_y):
    """(v, v_h, t1, t2, Lambda_v): the lobe's visible normals seen from v (anisotropy.glsl's
    anisotropic_view): the view above the horizon, stretched to the hemisphere configuration in the lobe's
    frame (x, y, n), a frame (t1, t2) about it and Lambda(v)."""
    n, v = np.asarray(n, np.float64), np.asarray(v, np.float64)
    ve = visible_view(v, n, NoV)
    vh = _unit(np.stack([alpha_x * _dot(ve, x), alpha_y * _dot(ve, y), _dot(ve, n)], -1))
    across = np.stack([-vh[..., 1], vh[..., 0], np.zeros(np.shape(vh)[:-1])], -1)
    t1 = np.where((vh[..., 2] < 0.9999)[..., None], _unit(across), [1.0, 0.0, 0.0])
    t2 = np.cross(vh, t1)
    return ve, vh, t1, t2, Lambda(ve, n, x, y, alpha_x, alpha_y)


def sample_disc(n, seen, NoV, x, y, alpha_x, alpha_y, p1, p2):
    """(l, pdf, v.h, weight) of the visible normal at the point (p1, p2) of the unit disc (anisotropy.glsl's
    anisotropic_sample_disc, Heitz 2018's listing 1), ``seen`` the lobe's ``view``: the light direction
    the half vector reflects v to, its density per steradian of l, D G1(v) / (4 n.v), and f (n.l) / pdf
    with F = 1, G2 / G1(v) (0 below the horizon)."""
    ve, vh, t1, t2, lam_v = seen
    p1, p2 = np.asarray(p1, np.float64), np.asarray(p2, np.float64)
    s = 0.5 * (1.0 + vh[..., 2])
    p2 = (1.0 - s) * np.sqrt(np.maximum(1.0 - p1 * p1, 0.0)) + s * p2
    lift = np.sqrt(np.maximum(1.0 - p1 * p1 - p2 * p2, 0.0))
    nh = p1[..., None] * t1 + p2[..., None] * t2 + lift[..., None] * vh
    h = _unit(x * (alpha_x * nh[..., 0])[..., None] + y * (alpha_y * nh[..., 1])[..., None]
              + n * np.maximum(nh[..., 2], 0.0)[..., None])
    VoH = _dot(ve, h)
    l = 2.0 * VoH[..., None] * h - ve
    pdf = D(h, n, x, y, alpha_x, alpha_y) / ((1.0 + lam_v) * 4.0 * NoV)
    NoL = _dot(n, l)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam_l = Lambda(l, n, x, y, alpha_x, alpha_y)
        weight = np.where(NoL > 0.0, (1.0 + lam_v) / (1.0 + lam_v + lam_l), 0.0)
    return l, pdf, VoH, weight


def sample(n, v, NoV, x, y, alpha_x, alpha_y, i: int, count: int):
    """``sample_disc`` at the i-th of ``count`` points of a Fibonacci lattice taken to the disc
    (anisotropy.glsl's anisotropic_sample)."""
    n = np.asarray(n, np.float64)
    r = math.sqrt((i + 0.5) / count)
    phi = 2.0 * math.pi * ((i * GOLDEN_FRACTION + 0.5) % 1.0)
    seen = view(n, v, NoV, x, y, alpha_x, alpha_y)
    shape = np.shape(seen[4])
    return sample_disc(n, seen, NoV, x, y, alpha_x, alpha_y, np.full(shape, r * math.cos(phi)),
                       np.full(shape, r * math.sin(phi)))


def strips(alpha_x, alpha_y):
    """How many strips the world's light reads (anisotropy.glsl's anisotropic_environment): the aspect
    alpha_long / alpha_short rounded up, within 1 and WORLD_STRIPS."""
    aspect = np.maximum(alpha_x, alpha_y) / np.minimum(alpha_x, alpha_y)
    return np.clip(np.ceil(aspect), 1, WORLD_STRIPS).astype(int)


def disc_quantile(u):
    """The point of the unit disc's diameter with the share ``u`` of its area on one side (anisotropy.glsl's
    anisotropic_disc_quantile): s = sin phi with phi + sin(2 phi) / 2 = pi (u - 1/2), three Newton steps
    from phi / 2, as the GPU takes them."""
    c = np.pi * (np.asarray(u, np.float64) - 0.5)
    phi = 0.5 * c
    for _ in range(3):
        phi = phi - (phi + 0.5 * np.sin(2.0 * phi) - c) / (1.0 + np.cos(2.0 * phi))
    return np.sin(phi)


def strip_sample(n, seen, NoV, x, y, alpha_x, alpha_y, i, count):
    """``sample_disc`` at strip ``i`` of ``count`` (arrays): the point of the disc's diameter along the lobe's
    long axis (x where alpha_x >= alpha_y, else y) at the strip's middle share (``disc_quantile``)."""
    _, _, t1, t2, _ = seen
    k = np.where(np.asarray(alpha_x) >= np.asarray(alpha_y), 0, 1)[..., None]
    d = np.stack([np.take_along_axis(t1, k, -1)[..., 0], np.take_along_axis(t2, k, -1)[..., 0]], -1)
    d2 = np.sum(d * d, -1, keepdims=True)
    d = np.where(d2 > 1e-12, d / np.sqrt(np.maximum(d2, 1e-300)), [1.0, 0.0])
    along = disc_quantile((np.asarray(i) + 0.5) / np.asarray(count))
    return sample_disc(n, seen, NoV, x, y, alpha_x, alpha_y, along * d[..., 0], along * d[..., 1])


def sample_roughness(pdf, count, narrow=0.0):
    """The perceptual roughness of the GGX lobe that covers a strip's share of the lobe, 1 / (N pdf)
    sr = 4 pi alpha^2 (anisotropy.glsl's anisotropic_environment), its alpha at least ``narrow`` (the
    lobe's short axis), within the floor and 1."""
    alpha2 = 1.0 / (4.0 * np.pi * count * np.maximum(np.asarray(pdf, np.float64), 1e-30))
    alpha2 = np.maximum(alpha2, np.asarray(narrow, np.float64) ** 2)
    return np.clip(np.sqrt(np.sqrt(alpha2)), MIN_PERCEPTUAL_ROUGHNESS, 1.0)
