"""The twin of glsl/subsurface.glsl: the Translucent BSDF, Cycles' Christensen-Burley profile, the
subsurface's mean free path as Cycles sets it up from Radius, Scale, the method, the albedo and the
IOR, the profile pre-integrated against a light's terminator (``ramp``; under a sized light
``ramp_sized``; the light's own curvature ``curved_light``), and Cycles' random walk's reflectance, drift
and convex gain, tabulated (``walk_factor``)."""

from __future__ import annotations

import math
from functools import lru_cache
from pathlib import Path

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
    (m; (..., 3) per channel) on a surface of curvature ``curvature`` (1/m), (..., 3); n.l (...)."""
    return ramp_channels(np.asarray(NoL, np.float64)[..., None], d, curvature)


def ramp_channels(NoL, d, curvature):
    """``ramp`` of an n.l per channel (..., 3) (the walk's drift moves each channel's: drift_cosine)."""
    NoL = np.asarray(NoL, np.float64)
    rho = np.minimum(np.asarray(d, np.float64) * np.asarray(curvature, np.float64)[..., None], 1.0)
    a = np.abs(NoL)
    with np.errstate(divide="ignore", invalid="ignore"):
        near = 0.25 * rho * bickley(a / rho) + 2.25 * rho * bickley(a / (3.0 * rho))
    return np.maximum(NoL, 0.0) + np.where(rho > 0.0, near, 0.0)


#: subsurface_bickley3's rational fit of Ki_3 (exp(-y) (pi / 4 + a y + b y^2) / (1 + c y + e y^2), a =
#: pi / 4 (1 + c) - 1: Ki_3'(0) = -Ki_2(0) = -1)
BICKLEY3_FIT = (1.28824763, 0.10408297, 1.91348736, 0.45483162)


def bickley3(y):
    """glsl/subsurface.glsl's subsurface_bickley3: Ki_3(y) / pi by the fit."""
    y = np.minimum(np.asarray(y, np.float64), 80.0)  # far past the profile: as the GPU's guard
    a, b, c, e = BICKLEY3_FIT
    return np.exp(-y) * (0.25 * math.pi + y * (a + b * y)) / (math.pi * (1.0 + y * (c + e * y)))


def ramp_sized(NoL, d, curvature, size):
    """glsl/subsurface.glsl's subsurface_ramp_sized: ``ramp_channels`` averaged over n.l +- sqrt(3) / 2
    ``size`` (a light of angular radius asin(size): the box of its disc's variance), (..., 3); a size of
    at most 1e-4: the point's."""
    NoL = np.asarray(NoL, np.float64)
    size = np.asarray(size, np.float64)[..., None]
    point = ramp_channels(NoL, d, curvature)
    rho = np.minimum(np.asarray(d, np.float64) * np.asarray(curvature, np.float64)[..., None], 1.0)
    box = np.maximum(size, 1e-4) * (0.5 * math.sqrt(3.0))
    ramp = np.where(NoL >= box, NoL, np.where(NoL <= -box, 0.0, (NoL + box) ** 2 / (4.0 * box)))

    def antiderivative(x):
        a = np.abs(x)
        with np.errstate(divide="ignore", invalid="ignore"):
            part = (0.25 * rho * rho * (0.25 - bickley3(a / rho))
                    + 6.75 * rho * rho * (0.25 - bickley3(a / (3.0 * rho))))
        return np.where(rho > 0.0, np.where(x < 0.0, -part, part), 0.0)

    near = (antiderivative(NoL + box) - antiderivative(NoL - box)) / (2.0 * box)
    return np.where(size > 1e-4, ramp + near, point)


def curved_light(c, d, curvature, u):
    """glsl/subsurface.glsl's subsurface_curved_light: (..., 3) the irradiance's own curvature over the
    profile's spread (sigma^2 = 7 d^2 per axis), per unit irradiance, for a light at distance 1 / ``u``
    seen at cosine ``c`` on a surface of ``curvature``: sigma^2 (-(u + k c)(3 c u + k) + (1 - c^2)
    (7.5 c u^2 + 3 k u)), faded out within 4 widths of the terminator, widths held to 0.1."""
    c = np.asarray(c, np.float64)[..., None]
    k = np.maximum(np.asarray(curvature, np.float64), 0.0)[..., None]
    u = np.asarray(u, np.float64)[..., None]
    q = -(u + k * c) * (3.0 * c * u + k) + (1.0 - c * c) * (7.5 * c * u * u + 3.0 * k * u)
    reach = k + u
    rho = np.minimum(np.asarray(d, np.float64) * reach, 0.1)
    fade = np.clip(c / np.maximum(4.0 * rho, 1e-6), 0.0, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        sigma2 = np.where(reach > 0.0, 7.0 * rho * rho / np.where(reach > 0.0, reach * reach, 1.0), 0.0)
    return sigma2 * q * fade


# --- the random walk's reflectance (Cycles' subsurface_random_walk), tabulated ------------------------
#
# Cycles' Random Walk methods trace the camera's ray into the surface (refracted through a rough
# dielectric interface of the entry's IOR and roughness: subsurface_entry_bounce), walk it through a
# medium whose coefficients it derives from the albedo, the radius and the Anisotropy g
# (subsurface_random_walk_remap: a single-scattering albedo fitted so that the medium reflects about
# the albedo, an extinction 1 / (d (1 - g))), and light the point where it leaves by a Lambert BSDF
# there (subsurface_shader_data_setup). On a surface flat against the walk's reach the light leaving
# towards the camera is therefore the Lambert base's times R / albedo, R the medium's diffuse
# reflectance for the ray's entry direction: less than the albedo where the ray enters steeply (a deep
# first scattering), more where it grazes, more with a forward-scattering g. The engine multiplies the
# subsurface's light by that factor per channel (glsl/subsurface.glsl's subsurface_walk_lookup), from a
# table of R / albedo over the albedo, g and the entry cosine (WALK_TABLE, computed by walk_reflectance
# below, a Monte Carlo twin of Cycles' walk in a half-space) and the entry's directions (entry_weights).

#: Cycles' clamps of the Anisotropy and the IOR (bssrdf_setup)
WALK_G_MAX = 0.9
WALK_IOR_RANGE = (1.01, 3.8)
#: The table's nodes: albedos at (i / 16)^2 (dense where R / albedo changes fast; the first taken at
#: albedo 1e-4, the limit the factor tends to as the albedo, which multiplies it, vanishes), g every
#: 0.05 from 0 to WALK_G_MAX, entry cosines (k / 6)^2 and, last, a cosine-distributed (diffuse) entry
WALK_ALBEDO_NODES = 17
WALK_G_NODES = 19
WALK_MU_NODES = 7
WALK_SHIPPED = Path(__file__).with_name("subsurface_walk.npz")
#: Cycles' BSSRDF_MAX_BOUNCES, VOLUME_THROUGHPUT_EPSILON, the similarity level and the lowest
#: single-scattering albedo it walks with (subsurface_random_walk_coefficients' min_alpha)
WALK_MAX_BOUNCES = 256
WALK_THROUGHPUT_EPSILON = 1e-6
WALK_SIMILARITY_LEVEL = 9
WALK_MIN_ALPHA = 0.2


def walk_albedos() -> np.ndarray:
    """The table's albedo nodes (``WALK_ALBEDO_NODES``; the first, 0, walked at 1e-4)."""
    return (np.arange(WALK_ALBEDO_NODES) / (WALK_ALBEDO_NODES - 1.0)) ** 2


def walk_gs() -> np.ndarray:
    """The table's Anisotropy nodes, 0 .. WALK_G_MAX."""
    return np.arange(WALK_G_NODES) * (WALK_G_MAX / (WALK_G_NODES - 1.0))


def walk_mus() -> np.ndarray:
    """The table's entry cosines, (k / (WALK_MU_NODES - 1))^2: nodes even in sqrt(mu)."""
    return (np.arange(WALK_MU_NODES) / (WALK_MU_NODES - 1.0)) ** 2


def walk_remap(albedo, g):
    """Cycles' subsurface_random_walk_remap: the medium's single-scattering albedo for a surface
    ``albedo`` and Anisotropy ``g`` (clamped to [0, 0.999999] as Cycles does); its extinction is
    1 / (d (1 - g)) for a mean free path d."""
    albedo = np.asarray(albedo, np.float64)
    g = np.asarray(g, np.float64)
    p = [g ** k for k in range(8)]

    def poly(c):
        return sum(ck * pk for ck, pk in zip(c, p))

    a = poly((1.8260523782, -1.28451056436, -1.79904629312, 9.19393289202, -22.8215585862, 32.0234874259,
              -23.6264803333, 7.21067002658))
    b = 4.98511194385 + 0.127355959438 * np.exp(poly((0.0, 31.1491581433, -201.847017512, 841.576016723,
                                                       -2018.09288505, 2731.71560286, -1935.41424244,
                                                       559.009054474)))
    c = poly((1.09686102424, -0.394704063468, 1.05258115941, -8.83963712726, 28.8643230661, -46.8802913581,
              38.5402837518, -12.7181042538))
    d = poly((0.496310210422, 0.360146581622, -2.15139309747, 17.8896899217, -55.2984010333, 82.065982243,
              -58.5106008578, 15.8478295021))
    e = 4.23190299701 + 0.00310603949088 * np.exp(poly((0.0, 76.7316253952, -594.356773233, 2448.8834203,
                                                         -5576.68528998, 7116.60171912, -4763.54467887,
                                                         1303.5318055)))
    f = poly((2.40602999408, -2.51814844609, 9.18494908356, -79.2191708682, 259.082868209, -403.613804597,
              302.85712436, -87.4370473567))
    blend = albedo ** 0.25
    alpha = (1.0 - blend) * a * np.arctan(b * albedo) ** c + blend * d * np.arctan(e * albedo) ** f
    return np.clip(alpha, 0.0, 0.999999)


#: The ball the table's curvature slope is walked in: radius WALK_CONVEX_RADIUS d (rho = d / R = 1/28,
#: where the gain is still linear in rho: 1/113, 1/56 and 1/28 gave the same slope within the noise)
WALK_CONVEX_RADIUS = 28.0
#: The entry cosine the drift's last node (1: straight down, where the drift vanishes as its sine) is
#: walked at: the drift per unit sine is smooth there
WALK_DRIFT_LAST_MU = 0.98


def _walk(albedo: float, g: float, mu, paths: int, seed: int, convex_radius: float = 0.0):
    """Cycles' random walk (subsurface_random_walk without its guided sampling, which changes the
    variance, not the expectation) in a half-space (its surface the plane z = 0, d = 1: a half-space has
    no scale) for rays entering at cosines ``mu`` to the normal (an array: ``paths`` walks each) along
    +x: the distance to the next scattering exponential in the extinction, a Henyey-Greenstein
    direction of g for the first WALK_SIMILARITY_LEVEL bounces and beyond them isotropic with the
    similarity-reduced coefficients, the throughput times the single-scattering albedo at each
    scattering (raised to WALK_MIN_ALPHA as Cycles raises it, the throughput scaled down), a walk ended
    after WALK_MAX_BOUNCES (lost) or below WALK_THROUGHPUT_EPSILON; one channel (Cycles samples the
    three channels' distances with MIS: with radii far apart it loses about 1 % more of the widest
    channel to the bounce limit). (len(mu), paths) arrays: the throughput over the albedo where each
    walk leaves the half-space (0: lost), the x where it leaves, and (``convex_radius`` > 0) the
    throughput where it leaves the ball of that radius touching the plane at the entry (inside the
    half-space: every walk leaves it first, on the same random numbers)."""
    rng = np.random.default_rng(seed)
    g = min(max(float(g), 0.0), WALK_G_MAX)
    albedo = float(albedo)
    alpha = float(walk_remap(albedo, g))
    weight = 1.0 / albedo  # the throughput over the albedo (subsurface_random_walk_coefficients)
    if alpha < WALK_MIN_ALPHA:
        weight *= alpha / WALK_MIN_ALPHA
        alpha = WALK_MIN_ALPHA
    sigma_t = 1.0 / (1.0 - g)
    sigma_s = sigma_t * alpha
    sigma_t_star = sigma_t - g * sigma_s  # the similarity's (sigma_s (1 - g) scatters isotropically)
    alpha_star = sigma_s * (1.0 - g) / sigma_t_star
    mu = np.asarray(mu, np.float64).reshape(-1)
    m = np.repeat(mu, paths)
    count = m.size
    p = np.zeros((count, 3))
    d = np.stack([np.sqrt(np.maximum(1.0 - m * m, 0.0)), np.zeros(count), -m], -1)
    throughput = np.full(count, weight)
    out = np.zeros(count)
    exit_x = np.zeros(count)
    ball = np.zeros(count)
    inside = np.full(count, convex_radius > 0.0)  # not yet out of the ball
    centre = np.array([0.0, 0.0, -convex_radius])
    alive = np.arange(count)
    for bounce in range(WALK_MAX_BOUNCES):
        if not alive.size:
            break
        similar = bounce > WALK_SIMILARITY_LEVEL
        st, al, gg = (sigma_t_star, alpha_star, 0.0) if similar else (sigma_t, alpha, g)
        k = alive.size
        if bounce > 0:  # scatter: Cycles' phase_henyey_greenstein_sample about the direction
            u = rng.random((2, k))
            if gg >= 1e-3:
                s = (1.0 - gg * gg) / (1.0 - gg + 2.0 * gg * u[0])
                cos = (1.0 + gg * gg - s * s) / (2.0 * gg)
            else:
                cos = 1.0 - 2.0 * u[0]
            sin = np.sqrt(np.maximum(1.0 - cos * cos, 0.0))
            phi = 2.0 * math.pi * u[1]
            axis = d[alive]
            other = np.zeros_like(axis)
            other[np.abs(axis[:, 0]) > 0.9, 1] = 1.0
            other[np.abs(axis[:, 0]) <= 0.9, 0] = 1.0
            t1 = np.cross(axis, other)
            t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
            t2 = np.cross(axis, t1)
            d[alive] = (t1 * (sin * np.cos(phi))[:, None] + t2 * (sin * np.sin(phi))[:, None]
                        + axis * cos[:, None])
        t = -np.log1p(-rng.random(k)) / st
        if convex_radius > 0.0:  # out of the ball along this step: its far crossing of the sphere
            walking = alive[inside[alive]]
            o = p[walking] - centre
            b = np.sum(o * d[walking], axis=1)
            c = np.sum(o * o, axis=1) - convex_radius * convex_radius
            # inside (c <= 0 up to rounding): the root is real
            reach = -b + np.sqrt(np.maximum(b * b - c, 0.0))
            through = walking[t[inside[alive]] >= reach]
            ball[through] = throughput[through]
            inside[through] = False
        znew = p[alive, 2] + t * d[alive, 2]
        left = znew >= 0.0  # through the surface: the walk ends there (its transmittance over its pdf: 1)
        gone = alive[left]
        out[gone] = throughput[gone]
        # where the step crosses z = 0 (its direction points up there: d_z > 0)
        exit_x[gone] = p[gone, 0] + (-p[gone, 2] / d[gone, 2]) * d[gone, 0]
        stay = alive[~left]
        p[stay] += t[~left, None] * d[stay]
        throughput[stay] *= al
        alive = stay[throughput[stay] >= WALK_THROUGHPUT_EPSILON]
    shape = (len(mu), paths)
    return out.reshape(shape), exit_x.reshape(shape), ball.reshape(shape)


def walk_reflectance(albedo: float, g: float, mu, paths: int = 20000, seed: int = 0, spread: bool = False):
    """R / albedo of Cycles' random walk in a half-space for rays entering at cosines ``mu`` (``_walk``,
    ``paths`` walks each); ``spread``: also each mean's standard error."""
    out = _walk(albedo, g, mu, paths, seed)[0]
    if spread:
        return out.mean(axis=1), out.std(axis=1) / math.sqrt(paths)
    return out.mean(axis=1)


def walk_moments(albedo: float, g: float, mu, paths: int = 20000, seed: int = 0,
                 convex_radius: float = WALK_CONVEX_RADIUS):
    """(3, len(mu)) means and (3, len(mu)) standard errors, on the same walks as walk_reflectance's of
    the same seed (R unchanged): R / albedo; its first moment of the exit point along the entering
    ray's direction on the surface, R times the walk's mean drift in units of d, over the ray's sine
    sqrt(1 - mu^2) (the drift vanishes as the sine where the ray goes straight down: per unit sine
    it is smooth there); and the gain of R on a convex surface per unit rho = d / radius (the ball of
    radius ``convex_radius`` d: its R less the half-space's, times that radius; a convex surface's
    nearer boundary lets more walks out: 1-1.5 R per unit rho)."""
    mu = np.asarray(mu, np.float64).reshape(-1)
    out, exit_x, ball = _walk(albedo, g, mu, paths, seed, convex_radius)
    sine = np.sqrt(np.maximum(1.0 - mu * mu, 0.0))[:, None]
    # (mu = 1: no drift; WALK_DRIFT_LAST_MU walks the table's last node)
    drift = out * exit_x / np.maximum(sine, 1e-6)
    gain = (ball - out) * convex_radius
    parts = np.stack([out, drift, gain])
    return parts.mean(axis=2), parts.std(axis=2) / math.sqrt(paths)


#: Walks per node of the drift's and the convex gain's tables (their noise: ~0.1 % of the factor on a
#: surface whose rho is 0.02)
WALK_MOMENT_PATHS = 10000


def compute_walk_table(paths: int = 60000, log=None, moment_paths: int = WALK_MOMENT_PATHS,
                       reflectance: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Three float32 tables over the albedo, g and entry nodes (seeded per cell), the last entry node a
    cosine-distributed (diffuse) entry: (WALK_ALBEDO_NODES, WALK_G_NODES, WALK_MU_NODES + 1) R / albedo
    (walk_reflectance, ``paths`` walks each; ``reflectance``: that table given, as computed before);
    (.., WALK_MU_NODES) the drift's moment per unit sine (walk_moments, ``moment_paths`` walks each;
    its last node walked at WALK_DRIFT_LAST_MU; a diffuse entry's rays come from every azimuth: none);
    (.., WALK_MU_NODES + 1) the convex surface's gain per unit rho (walk_moments; entries grazing within
    the first free flight of a ball's surface leave through it nonlinearly in rho: the two first cosine
    nodes, 0 and 1/36, take the third's, 1/9). Minutes per thousand paths:
    scripts/subsurface_walk_table.py."""
    albedos, gs = walk_albedos(), walk_gs()
    out = np.zeros((WALK_ALBEDO_NODES, WALK_G_NODES, WALK_MU_NODES + 1), np.float32)
    drift = np.zeros((WALK_ALBEDO_NODES, WALK_G_NODES, WALK_MU_NODES), np.float32)
    gain = np.zeros((WALK_ALBEDO_NODES, WALK_G_NODES, WALK_MU_NODES + 1), np.float32)
    diffuse = np.sqrt((np.arange(paths) + 0.5) / paths)  # cosines of a cosine-weighted hemisphere
    diffuse_moments = np.sqrt((np.arange(moment_paths) + 0.5) / moment_paths)
    mus = np.maximum(walk_mus(), 1e-6)
    for i, albedo in enumerate(albedos):
        for j, g in enumerate(gs):
            seed = 1000 * i + j
            a = max(albedo, 1e-4)
            if reflectance is None:
                out[i, j, :WALK_MU_NODES] = walk_reflectance(a, g, mus, paths, seed)
                out[i, j, WALK_MU_NODES] = walk_reflectance(a, g, diffuse, 1, seed + 500000).mean()
            else:
                out[i, j] = reflectance[i, j]
            entries = np.append(mus[:-1], WALK_DRIFT_LAST_MU)
            means = walk_moments(a, g, entries, moment_paths, seed + 700000)[0]
            drift[i, j] = means[1]
            gain[i, j, 2:WALK_MU_NODES - 1] = means[2, 2:-1]
            gain[i, j, :2] = gain[i, j, 2]
            gain[i, j, WALK_MU_NODES - 1] = walk_moments(a, g, mus[-1:], moment_paths, seed + 800000)[0][2, 0]
            gain[i, j, WALK_MU_NODES] = walk_moments(a, g, diffuse_moments, 1, seed + 900000)[0][2].mean()
        if log is not None:
            log(f"albedo {albedo:.4f}: {np.round(out[i, :, 3], 3)}, drift {np.round(drift[i, 0], 3)}, "
                f"gain {np.round(gain[i, 0], 2)}")
    return out, drift, gain


@lru_cache(maxsize=1)
def walk_table() -> np.ndarray:
    """The shipped ``compute_walk_table`` (WALK_SHIPPED): (albedo, g, entry) R / albedo, float32."""
    if not WALK_SHIPPED.exists():
        raise FileNotFoundError(f"the random walk's table {WALK_SHIPPED.name} is missing: run "
                                "scripts/subsurface_walk_table.py")
    with np.load(WALK_SHIPPED) as data:
        out = np.asarray(data["walk"], np.float32)
    shape = (WALK_ALBEDO_NODES, WALK_G_NODES, WALK_MU_NODES + 1)
    if out.shape != shape:
        raise ValueError(f"{WALK_SHIPPED.name}: a table of {out.shape}, expected {shape}")
    return out


def _walk_part(name: str, entries: int) -> np.ndarray:
    """One of the shipped ``compute_walk_table``'s other tables (WALK_SHIPPED), float32."""
    with np.load(WALK_SHIPPED) as data:
        if name not in data.files:
            raise FileNotFoundError(f"the random walk's table {WALK_SHIPPED.name} has no {name}: run "
                                    "scripts/subsurface_walk_table.py")
        out = np.asarray(data[name], np.float32)
    shape = (WALK_ALBEDO_NODES, WALK_G_NODES, entries)
    if out.shape != shape:
        raise ValueError(f"{WALK_SHIPPED.name}: a {name} table of {out.shape}, expected {shape}")
    return out


@lru_cache(maxsize=1)
def walk_drift_table() -> np.ndarray:
    """The shipped drift's moment per unit sine (albedo, g, entry cosine): compute_walk_table's."""
    return _walk_part("drift", WALK_MU_NODES)


@lru_cache(maxsize=1)
def walk_gain_table() -> np.ndarray:
    """The shipped convex gain per unit rho (albedo, g, entry): compute_walk_table's."""
    return _walk_part("gain", WALK_MU_NODES + 1)


#: The entry's quadrature over Cycles' VNDF sampling disk (microfacet_ggx_sample_vndf, Heitz 2018):
#: the half t.x >= 0 (the other half mirrors the refracted rays across the plane of incidence, at the
#: same cosine to the normal), WALK_ENTRY_RINGS rings even in area times WALK_ENTRY_SPOKES angles
#: (against sampling the entry: 4 x 2 points 0.64 % off the factor at worst, as 4 x 4; 3 x 2 0.87 %,
#: 2 x 2 1.3 %; tests/test_subsurface_walk.py)
WALK_ENTRY_RINGS = 4
WALK_ENTRY_SPOKES = 2

#: The methods' codes in MaterialData's subsurface_walk row (w: the diffuse entry's share; y 0: no walk)
SKIN_DIFFUSE_SHARE = 0.5


def entry_disk() -> np.ndarray:
    """(WALK_ENTRY_RINGS x WALK_ENTRY_SPOKES, 2): the quadrature's points on the half disk, each of
    equal weight."""
    r = np.sqrt((np.arange(WALK_ENTRY_RINGS) + 0.5) / WALK_ENTRY_RINGS)
    phi = math.pi * ((np.arange(WALK_ENTRY_SPOKES) + 0.5) / WALK_ENTRY_SPOKES - 0.5)
    rr, pp = np.meshgrid(r, phi, indexing="ij")
    return np.stack([rr * np.cos(pp), rr * np.sin(pp)], -1).reshape(-1, 2)


def entry_cosines(cos_v, eta, alpha):
    """((..., points) x 3): the cosine to the normal of the camera's ray refracted into the surface at
    each of the quadrature's points (Cycles' subsurface_entry_bounce: a GGX microfacet normal of
    roughness alpha drawn from the view's visible normals, the ray refracted through it by 1 / eta),
    0 where it fails (a view at or below the horizon, a ray leaving above the surface); 1 where it
    does not (0 where it fails); and the cosine of its direction along the surface to the view's
    away from the viewer (its mirror image across the plane of incidence has the same: their
    sideways parts cancel) times its sine to the normal (-x: the ray's own component along the surface
    away from the viewer), 0 where it fails; the view at cosine ``cos_v``."""
    cos_v = np.asarray(cos_v, np.float64)[..., None]
    eta = np.asarray(eta, np.float64)[..., None]
    alpha = np.asarray(alpha, np.float64)[..., None]
    t = entry_disk()
    sin_v = np.sqrt(np.maximum(1.0 - cos_v * cos_v, 0.0))
    # the view stretched to the hemisphere's configuration (its y is 0: the plane of incidence is xz)
    length = np.sqrt(alpha * alpha * sin_v * sin_v + cos_v * cos_v)
    wx, wz = alpha * sin_v / np.maximum(length, 1e-30), cos_v / np.maximum(length, 1e-30)
    tx, ty = t[:, 0], t[:, 1]
    ty = (1.0 - 0.5 * (1.0 + wz)) * np.sqrt(np.maximum(1.0 - tx * tx, 0.0)) + 0.5 * (1.0 + wz) * ty
    tz = np.sqrt(np.maximum(1.0 - tx * tx - ty * ty, 0.0))
    tilted = wx * wx > 1e-7  # Cycles' frame: T1 = (0, 1, 0), T2 = wi_ x T1 = (-wz, 0, wx); else any
    hx = np.where(tilted, -wz * ty + wx * tz, tx)
    hy = np.where(tilted, tx, ty)
    hz = np.where(tilted, wx * ty + wz * tz, tz)
    hx, hy, hz = alpha * hx, alpha * hy, np.maximum(hz, 0.0)
    norm = np.sqrt(hx * hx + hy * hy + hz * hz)
    # a microfacet normal of no length (alpha 0 with the view below the horizon): n, as the GPU's
    none = norm <= 0.0
    safe = np.where(none, 1.0, norm)
    hx, hy = np.where(none, 0.0, hx / safe), np.where(none, 0.0, hy / safe)
    hz = np.where(none, 1.0, hz / safe)
    cos_hi = hx * sin_v + hz * cos_v
    neta = 1.0 / eta
    root = np.sqrt(np.maximum(1.0 - neta * neta * (1.0 - cos_hi * cos_hi), 0.0))
    nk = neta * cos_hi - np.maximum(root, 1e-7)
    wo_z = -neta * cos_v + nk * hz
    ok = (cos_v > 0.0) & (wo_z < 0.0)
    # along the surface: the view is (sin_v, 0, cos_v), away from the viewer is -x
    along = -(-neta * sin_v + nk * hx)
    return np.where(ok, -wo_z, 0.0), np.where(ok, 1.0, 0.0), np.where(ok, along, 0.0)


def entry_weights(cos_v, eta, alpha, diffuse_share, drift=False):
    """(..., WALK_MU_NODES + 1) the weights of the table's entry nodes for a view at ``cos_v`` entering
    through an interface of IOR ``eta`` (within WALK_IOR_RANGE) and GGX roughness ``alpha``: the
    refracted rays' cosines (entry_cosines) spread linearly in sqrt(mu) over the two nearest nodes, a
    failed ray none, times 1 - ``diffuse_share``; the last node (the diffuse entry) ``diffuse_share``
    (Random Walk (Skin): half its rays enter diffusely). ``drift``: also the drift's weights, each
    ray's times its component along the surface away from the viewer (the table holds the drift per
    unit sine; the diffuse entry's 0: its rays come from every azimuth)."""
    mu, ok, forward = entry_cosines(cos_v, eta, alpha)
    x = np.sqrt(mu) * (WALK_MU_NODES - 1.0)
    i = np.minimum(np.floor(x), WALK_MU_NODES - 2.0)
    f = x - i
    share = np.asarray(diffuse_share, np.float64)
    each = (1.0 - share)[..., None] * ok / mu.shape[-1]
    out = np.zeros(mu.shape[:-1] + (WALK_MU_NODES + 1,))
    along = np.zeros(mu.shape[:-1] + (WALK_MU_NODES + 1,))
    for k in range(WALK_MU_NODES):
        spread = each * (np.where(i == k, 1.0 - f, 0.0) + np.where(i == k - 1, f, 0.0))
        out[..., k] = spread.sum(-1)
        along[..., k] = (spread * forward).sum(-1)
    out[..., WALK_MU_NODES] = share
    return (out, along) if drift else out


def walk_lookup(albedo, g, table=None, nearest=False):
    """(..., 3, WALK_MU_NODES + 1): the table's R / albedo rows at each channel's ``albedo`` (..., 3)
    and ``g`` (...), bilinear between the nodes in sqrt(albedo) and g, both clamped to the table;
    ``nearest``: at the nearest node (glsl/subsurface.glsl's subsurface_walk_nearest)."""
    table = (walk_table() if table is None else table).astype(np.float64)
    x = np.sqrt(np.clip(np.asarray(albedo, np.float64), 0.0, 1.0)) * (WALK_ALBEDO_NODES - 1.0)
    y = np.clip(np.asarray(g, np.float64), 0.0, WALK_G_MAX) * ((WALK_G_NODES - 1.0) / WALK_G_MAX)
    y = np.broadcast_to(y[..., None], x.shape)
    if nearest:
        i = np.minimum(np.floor(x + 0.5).astype(int), WALK_ALBEDO_NODES - 1)
        j = np.minimum(np.floor(y + 0.5).astype(int), WALK_G_NODES - 1)
        return table[i, j]
    i0 = np.minimum(np.floor(x).astype(int), WALK_ALBEDO_NODES - 1)
    j0 = np.minimum(np.floor(y).astype(int), WALK_G_NODES - 1)
    i1, j1 = np.minimum(i0 + 1, WALK_ALBEDO_NODES - 1), np.minimum(j0 + 1, WALK_G_NODES - 1)
    fx, fy = (x - i0)[..., None], (y - j0)[..., None]
    return ((1.0 - fy) * ((1.0 - fx) * table[i0, j0] + fx * table[i1, j0])
            + fy * ((1.0 - fx) * table[i0, j1] + fx * table[i1, j1]))


def walk_factor(cos_v, albedo, walk, roughness=0.5, table=None, drift=False):
    """glsl/subsurface.glsl's subsurface_walk_at: (..., 3) the subsurface's light over its Lambert
    base, per channel of ``albedo``, for a view at ``cos_v`` and the material's ``walk`` row (walk_row:
    g, entry IOR, entry alpha (below 0: the base's ``roughness`` squared), diffuse share); 1 where the
    row has no walk (IOR 0: Christensen-Burley, whose disk reflects the albedo as Lambert does).
    ``drift``: also (..., 3) the walk's mean drift away from the viewer along the surface, in units of
    the mean free path d (the exit points' first moment over R: walk_drift_table) and (..., 3) its gain
    on a convex surface per unit rho over the factor (walk_gain_table); 0 without a walk."""
    walk = np.asarray(walk, np.float64)
    g, eta, alpha, share = walk[..., 0], walk[..., 1], walk[..., 2], walk[..., 3]
    base = np.clip(np.asarray(roughness, np.float64), 0.0, 1.0)
    alpha = np.where(alpha < 0.0, base * base, alpha)
    weights, along = entry_weights(cos_v, np.clip(eta, *WALK_IOR_RANGE), np.clip(alpha, 0.0, 1.0),
                                   np.clip(share, 0.0, 1.0), drift=True)
    rows = walk_lookup(albedo, g, table)
    factor = np.sum(rows * weights[..., None, :], axis=-1)
    walked = (eta > 0.0)[..., None]
    factor = np.where(walked, factor, 1.0)
    if not drift:
        return factor
    # the drift's and the gain's at the nearest node (smooth in both: a quarter of the GPU's reads)
    moments = walk_lookup(albedo, g, walk_drift_table(), nearest=True)
    moment = np.sum(moments * along[..., None, :WALK_MU_NODES], axis=-1)
    gain = np.sum(walk_lookup(albedo, g, walk_gain_table(), nearest=True) * weights[..., None, :], axis=-1)
    # a factor of 0 (an albedo of 0 reflects nothing): no drift or gain to speak of
    safe = np.maximum(factor, 1e-6)
    return (factor, np.where(walked & (factor > 1e-6), moment / safe, 0.0),
            np.where(walked & (factor > 1e-6), gain / safe, 0.0))


#: The rho = d / radius up to which the convex gain grows linearly (walk_moments: at rho 0.1 the ball's
#: gain is 0.97 of the linear one, at 0.2 0.72, at 1 0.17); beyond, it is held
WALK_GAIN_RHO = 0.1


def convex_gain(gain, d, curvature):
    """glsl/subsurface.glsl's subsurface_convex: (..., 3) the factor by which a convex surface of
    ``curvature`` (1/m) raises the walk's light, 1 + gain x rho, rho = d x curvature per channel held at
    WALK_GAIN_RHO."""
    rho = np.minimum(np.asarray(d, np.float64) * np.asarray(curvature, np.float64)[..., None], WALK_GAIN_RHO)
    return 1.0 + np.asarray(gain, np.float64) * rho


def drift_cosine(NoL, n, v, l, drift, d, curvature):
    """glsl/subsurface.glsl's subsurface_drift_cosine: (..., 3) n.l per channel where the walk leaves on
    average, ``drift`` (walk_factor's, units of d) times the mean free path ``d`` (m, (..., 3)) away from
    the viewer along the surface: n turns by the curvature times the distance, n.l by that times the
    light's cosine to the drift's direction (first order; the view along n: no direction, no drift)."""
    n, v, l = (np.asarray(x, np.float64) for x in (n, v, l))
    tangent = -(v - n * np.sum(n * v, axis=-1, keepdims=True))
    length = np.linalg.norm(tangent, axis=-1, keepdims=True)
    toward = np.sum(tangent * l, axis=-1, keepdims=True) / np.maximum(length, 1e-12)
    toward = np.where(length > 1e-6, toward, 0.0)
    # the profile's width over the radius of curvature, clamped as the ramp clamps it
    rho = np.minimum(np.asarray(d, np.float64) * np.asarray(curvature, np.float64)[..., None], 1.0)
    shift = np.asarray(drift, np.float64) * rho
    return np.asarray(NoL, np.float64)[..., None] + shift * toward


def walk_row(method: str, ior, level, subsurface_ior, anisotropy) -> np.ndarray:
    """(..., 4) MaterialData's subsurface_walk row of a Principled BSDF (glsl/node_subsurface.glsl's
    subsurface_walk_* functions, as Cycles' svm_node_closure_bsdf and bssrdf_setup set the BSSRDF up):
    g within [0, 0.9], the entry's IOR within [1.01, 3.8] (0: Christensen-Burley, no walk), its GGX
    alpha (-1: the base's Roughness squared, the Principled BSDF's Random Walk), the diffuse entry's
    share. Random Walk: the IOR as the Specular IOR Level adjusts it (F0 times 2 level, the IOR of that
    F0 within [0, 0.99], inverted where the IOR is below 1); Skin: the Subsurface IOR, alpha 1 and half
    the rays entering diffusely."""
    g = np.clip(np.asarray(anisotropy, np.float64), 0.0, WALK_G_MAX)
    ior = np.asarray(ior, np.float64)
    level = np.asarray(level, np.float64)
    low, high = WALK_IOR_RANGE
    if method == "BURLEY":
        parts = (g, 0.0 * g, 0.0 * g, 0.0 * g)
    elif method == "RANDOM_WALK_SKIN":
        parts = (g, np.clip(np.asarray(subsurface_ior, np.float64), low, high), 1.0 + 0.0 * g,
                 SKIN_DIFFUSE_SHARE + 0.0 * g)
    else:
        r = (ior - 1.0) / (ior + 1.0)
        s = np.sqrt(np.clip(r * r * 2.0 * level, 0.0, 0.99))
        adjusted = np.where(ior < 1.0, (1.0 - s) / (1.0 + s), (1.0 + s) / (1.0 - s))
        eta = np.where(level != 0.5, adjusted, ior)
        parts = (g, np.clip(eta, low, high), -1.0 + 0.0 * g, 0.0 * g)
    return np.stack(np.broadcast_arrays(*parts), -1)
