"""Numpy twins of glsl/closures.glsl: the closure nodes drawn beside the Principled BSDF's lobes, as
Cycles 5.0 evaluates them (kernel/closure/bsdf_oren_nayar.h, bsdf_ashikhmin_velvet.h, bsdf_toon.h);
the Oren-Nayar also as Blender 4.2's Cycles does (``rule``, materials/surface.py's ``OREN_NAYAR``).

Every ``*_eval`` returns Cycles' bsdf eval, f (n.l): radiance per unit irradiance arriving along l.
Arrays broadcast; no ``bpy``.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

#: Cycles' FLT_MIN (Oren-Nayar's t over max(n.l, n.v) where both vanish)
FLT_MIN = 1.175494e-38
#: The Oren-Nayar of Blender 4.5 and 5.0 (Fujii's with OpenPBR's multiple scattering, Lambert below
#: roughness 1e-5) and of 4.2 (Fujii's alone, Lambert at roughness 0): glsl/closures.glsl's
#: SL_OREN_NAYAR_<RULE>, materials/surface.py's OREN_NAYAR
MULTISCATTER, SINGLE = "FUJII_MULTISCATTER", "FUJII"


def oren_nayar_G(cos_theta):
    """Fujii's G(theta) (bsdf_oren_nayar_G): E(theta) = A pi + B G(theta); its Taylor expansion below
    cos 1e-6."""
    c = np.asarray(cos_theta, np.float64)
    safe = np.maximum(c, 1e-6)
    s = np.sqrt(np.maximum(1.0 - safe * safe, 0.0))
    theta = np.arccos(np.clip(safe, -1.0, 1.0))
    g = s * (theta - 2.0 / 3.0 - s * safe) + 2.0 / 3.0 * (s / safe) * (1.0 - s * s * s)
    return np.where(c < 1e-6, (0.5 * np.pi - 2.0 / 3.0) - c, g)


def _lambert(sigma, rule):
    """Where Cycles draws the Diffuse BSDF as Lambert (svm_node_closure_bsdf): roughness below 1e-5,
    4.2's at 0 only."""
    sigma = np.asarray(sigma, np.float64)
    return sigma <= 0.0 if rule == SINGLE else sigma < 1e-5


def oren_nayar_setup(sigma, albedo, cos_v, rule=MULTISCATTER):
    """(A, B, E_ms (1 - E(v)) per channel, E_avg) of Cycles' bsdf_oren_nayar_setup: sigma within
    [0, 1], the albedo (the base colour) within [0, 1]; 4.2's (``SINGLE``) has no multiple
    scattering (its E_ms 0)."""
    sigma = np.clip(np.asarray(sigma, np.float64), 0.0, 1.0)
    a = 1.0 / (np.pi + sigma * (0.5 * np.pi - 2.0 / 3.0))
    b = sigma * a
    rho = np.clip(np.asarray(albedo, np.float64), 0.0, 1.0)
    e_avg = a * np.pi + (2.0 * np.pi - 5.6) / 3.0 * b
    ratio = (e_avg / np.maximum(1.0 - e_avg, 1e-6))[..., None]
    e_ms = rho * rho * ratio / (np.pi * (1.0 - rho * (1.0 - e_avg)[..., None]))
    e_v = a * np.pi + b * oren_nayar_G(np.maximum(cos_v, 0.0))
    if rule == SINGLE:
        e_ms = np.zeros_like(e_ms)
    return a, b, e_ms * (1.0 - e_v)[..., None], e_avg


def oren_nayar_ms(sigma, color):
    """glsl/node_closure.glsl's closure_oren_nayar: the multiple scattering's colour of a diffuse base
    of closure weight ``color`` (rgb, at least 0) and roughness ``sigma``, color x E_ms(saturate(color))
    (bsdf_oren_nayar_setup); 0 where sigma is below 1e-5 (Lambert)."""
    sigma = float(np.clip(sigma, 0.0, 1.0))
    color = np.maximum(np.asarray(color, np.float64), 0.0)
    if sigma < 1e-5:
        return np.zeros_like(color)
    a = 1.0 / (np.pi + sigma * (0.5 * np.pi - 2.0 / 3.0))
    e_avg = a * np.pi + (2.0 * np.pi - 5.6) / 3.0 * sigma * a
    rho = np.clip(color, 0.0, 1.0)
    return color * rho * rho * (e_avg / (1.0 - e_avg)) / (np.pi * (1.0 - rho * (1.0 - e_avg)))


def oren_nayar_eval(sigma, albedo, cos_v, cos_l, cos_lv, rule=MULTISCATTER):
    """f (n.l) over the base colour (rgb) of Cycles' Diffuse BSDF of roughness ``sigma``
    (bsdf_oren_nayar_get_intensity; Lambert's n.l / pi where sigma < 1e-5, bsdf_diffuse_setup), by
    ``rule`` (4.2's ``SINGLE``: no multiple scattering, Lambert at sigma 0 only)."""
    nl = np.maximum(cos_l, 0.0)
    f = oren_nayar_f(sigma, albedo, cos_v, oren_nayar_t(cos_l, cos_v, cos_lv), nl, rule)
    return np.where(_lambert(sigma, rule)[..., None], 1.0 / np.pi, f) * nl[..., None]


def oren_nayar_t(cos_l, cos_v, cos_lv):
    """closures.glsl's oren_nayar_t: l.v - n.l n.v over max(n.l, n.v) where positive (the cosines
    floored at 0)."""
    nl = np.maximum(cos_l, 0.0)
    nv = np.maximum(cos_v, 0.0)
    t = cos_lv - nl * nv
    return np.where(t > 0.0, t / (np.maximum(nl, nv) + FLT_MIN), t)


def oren_nayar_f(sigma, albedo, cos_v, t, cos_l, rule=MULTISCATTER):
    """Oren-Nayar's f over the base colour (rgb; Lambert not taken) of its factors towards the light,
    t and n.l: A + B t + E_ms (1 - E(v)) (1 - E(l)), E(l) = A pi + B G(n.l)."""
    a, b, ms, _ = oren_nayar_setup(sigma, albedo, cos_v, rule)
    e_l = a * np.pi + b * oren_nayar_G(np.maximum(cos_l, 0.0))
    return (a + b * np.asarray(t))[..., None] + ms * (1.0 - e_l)[..., None]


def vogel_disc(i, count: int) -> np.ndarray:
    """common.glsl's vogel_disc: point(s) ``i`` (an int or an array) of ``count`` on the unit disc, (..., 2):
    radius sqrt((i + 1/2) / count), turned by the golden angle per point."""
    i = np.asarray(i, np.float64)
    r = np.sqrt((i + 0.5) / count)
    phi = 2.3999632 * i  # the golden angle
    return np.stack([r * np.cos(phi), r * np.sin(phi)], -1)


#: lights.glsl's polygon_point: the points of a light's polygon the closures' quadratures take
POLYGON_POINTS = 16


def polygon_points(to_centre, x_half, y_half, sides, count: int = POLYGON_POINTS):
    """lights.glsl's polygon_point over a light's polygon (its centre ``to_centre`` from the points,
    half-axes ``x_half``, ``y_half``; ``sides`` 4 a rectangle, else an ellipse or disc): ((..., count, 3)
    unit directions, (..., count) weights, the emitter's cosine over the squared distance; 0 on the
    light): k x k midpoints of a rectangle (k = sqrt(count); the program's 4 x 4), ``count`` points of
    Vogel's spiral over an ellipse or disc (common.glsl's vogel_disc). A count above 16 is the tests'
    fine average."""
    i = np.arange(count)
    if sides == 4:
        k = int(round(math.sqrt(count)))
        uv = np.stack([(i % k + 0.5) / k, (i // k + 0.5) / k], -1) * 2.0 - 1.0
    else:
        uv = vogel_disc(i, count)
    x_half, y_half = np.asarray(x_half, np.float64), np.asarray(y_half, np.float64)
    d = (np.asarray(to_centre, np.float64)[..., None, :] + uv[:, :1] * x_half[..., None, :]
         + uv[:, 1:] * y_half[..., None, :])
    normal = np.cross(x_half, y_half)
    normal = normal / np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), 1e-19)
    d2 = np.sum(d * d, -1)
    on = d2 > 0.0  # a point on the light: no direction
    l = d / np.sqrt(np.where(on, d2, 1.0))[..., None]
    w = np.where(on, np.abs(np.sum(l * normal[..., None, :], -1)) / np.where(on, d2, 1.0), 0.0)
    return l, w


def oren_nayar_polygon(n, v, to_centre, x_half, y_half, sides):
    """closures.glsl's oren_nayar_polygon: (..., 3) (mean t, mean n.l, 1) over the polygon's points
    above the horizon, each weighted by its weight times n.l; (0, 0, 0) where none lies above."""
    l, w = polygon_points(to_centre, x_half, y_half, sides)
    n, v = np.asarray(n, np.float64)[..., None, :], np.asarray(v, np.float64)[..., None, :]
    nl = np.sum(n * l, -1)
    nv = np.maximum(np.sum(n * v, -1), 0.0)
    weight = np.where(nl > 0.0, w * nl, 0.0)
    total = weight.sum(-1)
    t = (weight * oren_nayar_t(nl, nv, np.sum(l * v, -1))).sum(-1)
    mean_nl = (weight * nl).sum(-1)
    some = total > 0.0
    safe = np.where(some, total, 1.0)
    return np.stack([np.where(some, t / safe, 0.0), np.where(some, mean_nl / safe, 0.0), some * 1.0], -1)


def oren_nayar_albedo(sigma, albedo, cos_v, rule=MULTISCATTER):
    """The directional albedo at the view over the base colour (rgb): E(v) + pi E_ms (1 - E(v))
    (1 - E_avg), the integral of oren_nayar_eval over the light's hemisphere in closed form (4.2's
    E(v) alone); 1 for Lambert."""
    a, b, ms, e_avg = oren_nayar_setup(sigma, albedo, cos_v, rule)
    e_v = a * np.pi + b * oren_nayar_G(np.maximum(cos_v, 0.0))
    out = e_v[..., None] + np.pi * ms * (1.0 - e_avg)[..., None]
    return np.where(_lambert(sigma, rule)[..., None], 1.0, out)


def velvet_eval(sigma, cos_v, cos_l, cos_nh, cos_hl):
    """Ashikhmin's velvet f (n.l) (bsdf_ashikhmin_velvet_eval), sigma floored at 0.01 as its setup."""
    sigma = np.maximum(np.asarray(sigma, np.float64), 0.01)
    inv = 1.0 / (sigma * sigma)
    ok = (cos_v > 0.0) & (cos_l > 0.0) & (np.abs(cos_nh) < 1.0 - 1e-5) & (cos_hl > 1e-5)
    safe_hl = np.where(ok, cos_hl, 1.0)
    ratio = np.maximum(cos_nh / safe_hl, 1e-5)
    g = np.minimum(1.0, 2.0 * ratio * np.minimum(cos_v, cos_l))
    sin2 = np.where(ok, 1.0 - cos_nh * cos_nh, 1.0)
    d = np.exp(-cos_nh * cos_nh / sin2 * inv) * inv / (np.pi * sin2 * sin2)
    return np.where(ok, 0.25 * d * g / np.where(ok, cos_v, 1.0), 0.0)


def velvet_at(sigma, n, v, l):
    """velvet_eval of unit vectors (..., 3)."""
    h = l + v
    h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-30)
    dot = lambda a, b: np.sum(a * b, axis=-1)  # noqa: E731
    return velvet_eval(sigma, dot(n, v), dot(n, l), dot(n, h), np.abs(dot(l, h)))


def velvet_albedo(sigma, cos_v, points: tuple[int, int] = (16, 8)):
    """The velvet's directional albedo by glsl/closures.glsl's midpoint rule: ``points`` over
    t = sqrt(cos theta) and half the azimuth (the GLSL's 16 x 8)."""
    cos_v = np.maximum(np.asarray(cos_v, np.float64), 1e-4)[..., None, None]
    v = np.stack(np.broadcast_arrays(np.sqrt(1.0 - cos_v * cos_v), 0.0 * cos_v, cos_v), -1)
    t = (np.arange(points[0]) + 0.5) / points[0]
    c = t * t
    phi = np.pi * (np.arange(points[1]) + 0.5) / points[1]
    s = np.sqrt(1.0 - c * c)
    l = np.stack(np.broadcast_arrays(s[:, None] * np.cos(phi)[None], s[:, None] * np.sin(phi)[None],
                                     c[:, None] + 0.0 * phi[None]), -1)
    n = np.array([0.0, 0.0, 1.0])
    f = velvet_at(np.asarray(sigma, np.float64)[..., None, None], n, v, l) * (2.0 * t)[:, None]
    return f.sum((-2, -1)) * (2.0 * np.pi / (points[0] * points[1]))


def toon_shape(size, smooth):
    """(Size, Smooth) in radians as bsdf_toon_setup_common takes them."""
    return np.clip(size, 1e-5, 1.0) * 0.5 * np.pi, np.clip(smooth, 0.0, 1.0) * 0.5 * np.pi


def toon_intensity(size, smooth, angle):
    """bsdf_toon_get_intensity (radians)."""
    ramp = np.where(smooth != 0.0, 1.0 - (angle - size) / np.where(smooth != 0.0, smooth, 1.0), 0.0)
    return np.where(angle < size, 1.0, np.where((angle < size + smooth) & (smooth != 0.0), ramp, 0.0))


def toon_eval(size, smooth, angle):
    """The toon's f (n.l) at ``angle`` from its axis (n for Diffuse, the view's reflection for
    Glossy), Size and Smooth in radians: its intensity times the uniform cone's pdf."""
    cone = np.minimum(size + smooth, 0.5 * np.pi)
    pdf = 1.0 / (4.0 * np.pi * np.sin(0.5 * cone) ** 2)
    return np.where(angle < cone, toon_intensity(size, smooth, angle) * pdf, 0.0)


def toon_albedo(size, smooth):
    """The toon's directional albedo (its cone whole above the horizon), closures.glsl's closed form
    free of cancellation: the inner cap 2 sin^2(size / 2) and the ramp over w = cone - size,
    sin(size) Re J + cos(size) Im J, J = int_0^w (1 - u / smooth) e^(iu) du."""
    size = np.minimum(size, 0.5 * np.pi)
    cone = np.minimum(size + smooth, 0.5 * np.pi)
    w = cone - size
    m = np.where(smooth > 0.0, smooth, 1.0)
    hw = np.sin(0.5 * w)
    re = np.sin(w) - (w * np.sin(w) - 2.0 * hw * hw) / m
    im = 2.0 * hw * hw - (np.sin(w) - w * np.cos(w)) / m
    ramp = np.where((smooth > 0.0) & (w > 0.0), np.sin(size) * re + np.cos(size) * im, 0.0)
    return (2.0 * np.sin(0.5 * size) ** 2 + ramp) / (2.0 * np.sin(0.5 * cone) ** 2)


def D_V_AshikhminShirley(NoV, NoL, NoH, LoH, alpha):
    """closures.glsl's Ashikhmin-Shirley lobe (Cycles' bsdf_ashikhmin_shirley_eval over n.l, its
    Fresnel left out): (e + 1) / (8 pi) (n.h)^e / ((l.h) max(n.v, n.l)), e = 2 / alpha^2 - 2; 0 at
    alpha <= 1e-4."""
    alpha = np.asarray(alpha, np.float64)
    e = 2.0 / np.maximum(alpha, 1e-4) ** 2 - 2.0
    pump = 1.0 / np.maximum(1e-6, np.maximum(LoH, 1e-6) * np.maximum(np.maximum(NoV, NoL), 1e-6))
    out = (e + 1.0) / (8.0 * np.pi) * np.maximum(NoH, 1e-6) ** e * pump
    return np.where(alpha <= 1e-4, 0.0, out)


def cone_above_horizon(cos_axis, c):
    """closures.glsl's share of a cone of half-angle ``c`` about an axis at ``cos_axis`` from n that
    lies above the horizon (two spherical caps' intersection over the cone's solid angle)."""
    cos_axis = np.clip(np.asarray(cos_axis, np.float64), -1.0, 1.0)
    c = np.asarray(c, np.float64)
    g = np.arccos(cos_axis)
    sin_c, sin_g = np.maximum(np.sin(c), 1e-6), np.maximum(np.sin(g), 1e-6)
    with np.errstate(invalid="ignore"):
        omega = 2.0 * (np.pi - np.arccos(np.clip(cos_axis / sin_c, -1.0, 1.0))
                       - np.cos(c) * np.arccos(np.clip(-cos_axis * np.cos(c) / (sin_g * sin_c), -1.0, 1.0)))
    # a cone of no width lies wholly on one side (the cases below): its share here is not used
    share = np.clip(omega / np.maximum(4.0 * np.pi * np.sin(0.5 * c) ** 2, 1e-300), 0.0, 1.0)
    return np.where(g + c <= 0.5 * np.pi, 1.0, np.where(g - c >= 0.5 * np.pi, 0.0, share))


def ashikhmin_shirley_albedo(mu, roughness, strata: int = 256, azimuths: int = 32):
    """The directional albedo of the Glossy BSDF's Ashikhmin-Shirley lobe (D_V_AshikhminShirley (n.l)
    integrated over the light's hemisphere) at n.v = ``mu`` (array) for one perceptual roughness (alpha
    its square, floored at MIN_PERCEPTUAL_ROUGHNESS as the engine draws it), by Cycles' own sampling of
    it (bsdf_ashikhmin_shirley_sample: half vectors of density (e + 1) / (2 pi) (n.h)^e, cos theta_h =
    xi^(1 / (e + 1))), whose weight f (n.l) / pdf reduces to n.l / max(n.v, n.l) (the pump's l.h cancels
    the pdf's): a stratified midpoint grid over (xi, phi), half the azimuths (the lobe is symmetric)."""
    from .brdf import MIN_PERCEPTUAL_ROUGHNESS

    alpha = max(float(roughness), MIN_PERCEPTUAL_ROUGHNESS) ** 2
    e = 2.0 / (alpha * alpha) - 2.0
    xi = (np.arange(strata) + 0.5) / strata
    cos_t = xi ** (1.0 / (e + 1.0))
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    phi = (np.arange(azimuths) + 0.5) / azimuths * np.pi
    h = np.stack([np.outer(sin_t, np.cos(phi)), np.outer(sin_t, np.sin(phi)),
                  np.outer(cos_t, np.ones_like(phi))], axis=-1).reshape(-1, 3)
    mu = np.atleast_1d(np.asarray(mu, np.float64))
    v = np.stack([np.sqrt(np.maximum(1.0 - mu * mu, 0.0)), np.zeros_like(mu), mu], axis=-1)
    VoH = v @ h.T
    NoL = 2.0 * VoH * h[:, 2][None, :] - mu[:, None]  # l = 2 (v.h) h - v
    # Cycles' floors: both cosines at least 1e-6 (the eval is 0 below either horizon)
    weight = np.where(NoL > 0.0, np.maximum(NoL, 1e-6) / np.maximum(np.maximum(mu[:, None], NoL), 1e-6), 0.0)
    return weight.mean(axis=1)


@lru_cache(maxsize=2)
def ashikhmin_shirley_albedo_table(size: int = 32) -> np.ndarray:
    """(size, size) float32 on multiscatter.albedo_table's grid (row j: roughness j / (size - 1),
    column i: n.v = i / (size - 1), floored at MIN_COS): ``ashikhmin_shirley_albedo`` (0.3 s, once).
    Within 2.3e-3 of 16x as many points (the smoothest rows at grazing)."""
    from .brdf import MIN_COS

    grid = np.arange(size) / (size - 1)
    mu = np.maximum(grid, MIN_COS)
    return np.stack([ashikhmin_shirley_albedo(mu, r) for r in grid]).astype(np.float32)


def cone_roughness(c):
    """closures.glsl's cone_roughness: the perceptual roughness of the prefiltered world whose lobe (GGX
    about the direction, n = v, weighted by n.l) has a uniform cone of half-angle ``c``'s median angle;
    cones wider than roughness 1's (1.144 rad) take 1."""
    t = np.minimum(np.asarray(c, np.float64), 1.144)
    return np.minimum(np.sqrt(np.tan(t / (2.0 * np.sqrt(2.0)))) * (1.0583 + t * (0.5579 * t - 0.2543)), 1.0)


def oren_nayar_b_moments(cos_v):
    """closures.glsl's oren_nayar_environment's fits of 3/2 int w(l) l dl (w the Oren-Nayar B term's
    weight (n.l) t, t = l.v - (n.l)(n.v) over max(n.l, n.v) where positive) along the view's tangent and
    along n: 2.133 (1 - n.v)^0.6, 0.450 (1 - n.v)^0.89."""
    one_minus = 1.0 - np.clip(np.asarray(cos_v, np.float64), 0.0, 1.0)
    return 2.133 * one_minus ** 0.6, 0.450 * one_minus ** 0.89


def oren_nayar_world(sigma, color, cos_v, irradiance, e_towards, e_away, rule=MULTISCATTER):
    """closures.glsl's oren_nayar_world: the Diffuse BSDF's light from the world times pi (rgb), its
    colour ``color`` (within [0, 1]), from the irradiance about n and about the view's tangent towards
    and away from the view (rgb each; all three alike where the view lies along n): Lambert's colour
    times the irradiance; Oren-Nayar's A term and multiple scattering times it, its B term times G(n.v)
    L0 + 2/3 L1.(int w l) of the world taken as linear (``oren_nayar_b_moments``), at least 0."""
    color = np.asarray(color, np.float64)
    nv = np.clip(np.asarray(cos_v, np.float64), 0.0, 1.0)
    a, b, ms, e_avg = oren_nayar_setup(sigma, color, nv, rule)
    G = oren_nayar_G(nv)[..., None]
    along_t, along_n = (m[..., None] for m in oren_nayar_b_moments(nv))
    e, up, down = (np.asarray(x, np.float64) for x in (irradiance, e_towards, e_away))
    mean = 0.5 * (up + down)
    b_light = np.maximum(G * mean + along_n * (e - mean) + along_t * 0.5 * (up - down), 0.0)
    multiple = color * np.pi * ms * (1.0 - e_avg)[..., None]  # (ms is per unit colour, as oren_nayar_eval's)
    out = color * (a[..., None] * np.pi * e + b[..., None] * b_light) + multiple * e
    return np.where(_lambert(sigma, rule)[..., None], color * e, out)


def velvet_world_points(sigma, cos_v):
    """closures.glsl's velvet_world_point for its 6 x 8 points: (directions (..., 48, 3) in the frame (the
    tangent towards v, n x it, n), weights (..., 48): the velvet's f (n.l) there times t = sqrt(cos))."""
    i = np.arange(48)
    t = (i // 8 + 0.5) / 6.0
    c = t * t
    s = np.sqrt(1.0 - c * c)
    phi = np.pi * (i % 8 + 0.5) / 4.0
    local = np.stack([s * np.cos(phi), s * np.sin(phi), c], -1)
    cos_v = np.asarray(cos_v, np.float64)[..., None]
    v = np.stack(np.broadcast_arrays(np.sqrt(np.maximum(1.0 - cos_v * cos_v, 0.0)), 0.0 * cos_v, cos_v), -1)
    f = velvet_at(np.asarray(sigma, np.float64)[..., None], np.array([0.0, 0.0, 1.0]), v, local)
    return np.broadcast_to(local, f.shape + (3,)), f * t


def velvet_world_radiance(sigma, cos_v, read):
    """closures.glsl's velvet_world_radiance in the frame: the mean of ``read(directions (..., 48, 3))``
    (rgb) weighted by velvet_world_points' weights."""
    local, w = velvet_world_points(sigma, np.maximum(np.asarray(cos_v, np.float64), 1e-4))
    return np.einsum("...k,...kc->...c", w, read(local)) / w.sum(-1)[..., None]


def polygon_average(direct, to_centre, x_half, y_half, sides: int, count: int = POLYGON_POINTS):
    """closures.glsl's closure_bsdfs_polygon: ``direct(l)`` (..., count, k; l unit, (..., count, 3))
    averaged over the polygon's points (``polygon_points``), each weighted by the solid angle it stands
    for (the emitter's cosine over the squared distance)."""
    l, w = polygon_points(to_centre, x_half, y_half, sides, count)
    return np.einsum("...k,...kc->...c", w, direct(l)) / w.sum(-1)[..., None]


#: closures.glsl's TOON_WORLD_SAMPLES: the points of a toon's cone the world is read at.
TOON_WORLD_SAMPLES = 16


def toon_world_points(size, smooth, count: int = TOON_WORLD_SAMPLES):
    """closures.glsl's toon_world_point for its points of the cone (Size and Smooth in radians): directions
    (..., count, 3) in the cone's frame (z its axis), spread by solid angle (Vogel's disc mapped to the cap
    by area), and the toon's intensity there (..., count)."""
    i = np.arange(count)
    r = np.sqrt((i + 0.5) / count)
    phi = 2.3999632 * i
    half_cap = np.sin(0.5 * np.minimum(np.asarray(size, np.float64) + smooth, 0.5 * np.pi))[..., None]
    one_minus_cos = 2.0 * r * r * half_cap * half_cap
    sin_t = np.sqrt(np.maximum(one_minus_cos * (2.0 - one_minus_cos), 0.0))
    local = np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), 1.0 - one_minus_cos], -1)
    angle = 2.0 * np.arcsin(r * half_cap)
    size, smooth = (np.asarray(x, np.float64)[..., None] for x in (size, smooth))
    return local, toon_intensity(size, smooth, angle)
