"""Linearly transformed cosines for area lights' specular lobe: the fitted tables and the numpy
twin of glsl/ltc.glsl (Heitz, Dupuy, Hill & Neubelt 2016, "Real-Time Polygonal-Light Shading
with Linearly Transformed Cosines"; horizon clipping by Heitz & Hill 2017, "Real-time area
lighting: a journey from research to production"). Pure numpy: no ``bpy``, no ``gpu``.

**What it is.** A clamped cosine D_o(w) = max(w.z, 0) / pi moved by a 3 x 3 matrix M is the
distribution D(w) = D_o(M^-1 w / |M^-1 w|) |det M^-1| / |M^-1 w|^3; it still integrates to 1,
and its integral over a polygon P is D_o's over the polygon M^-1 P: a form factor, in closed form.
Each (n.v, roughness) cell gets the M whose D best matches the BRDF lobe normalised to 1,
f(v, l) (n.l) / E(mu, r) with E = integral of f (n.l) (F = 1, height-correlated Smith, brdf.py's
D_GGX or D_Beckmann; E is the engine's own albedo table, multiscatter.albedo_table(ndf,
"SMITH_CORRELATED")), so that  integral_P f (n.l) dl ~= E(mu, r) * ltc_integral(M^-1, P).
The table carries the lobe's shape only, not its magnitude.

**Frame.** Local to the shading point: z = n, x = the tangent towards v, y = z x x, so that
v = (sqrt(1 - mu^2), 0, mu). The lobe is symmetric about the xz plane, so
M^-1 = [[a, 0, b], [0, c, 0], [d, 0, e]]; D does not depend on M^-1's scale, and it is stored
with c = 1 as the four floats (a, b, d, e) = (m00, m02, m20, m22), m[row][column]. In GLSL
(column-major): ``mat3 Minv = mat3(vec3(a, 0, d), vec3(0, 1, 0), vec3(b, 0, e));`` so that
Minv * p = (a p.x + b p.z, p.y, d p.x + e p.z). Every fitted cell has det = ae - bd > 0
(tests/test_ltc.py), so M ~ adj(M^-1) = [[e, 0, -b], [0, ae - bd, 0], [-d, 0, a]] up to a
positive factor, which is how ``ltc_integral`` maps the mean direction back.

**Grids.** LTC table (LTC_SIZE = 64)^2 x 4 float32, [j, i]: row j <-> perceptual roughness
r = j / (N - 1) (fitted at max(r, MIN_PERCEPTUAL_ROUGHNESS)), column i <-> t = i / (N - 1) with
mu = n.v = 1 - t^2 (Heitz's sqrt(1 - cos) parametrisation, mu floored at MIN_COS); both ends on the
grid, bilinear lookup at (sqrt(1 - mu) (N - 1), r (N - 1)), clamped (``lookup``). Sphere table
(SPHERE_SIZE = 32)^2 float32, [j, i]: row j <-> |F| = j / (N - 1), column i <->
z = 2 i / (N - 1) - 1, bilinear at ((z + 1) / 2 (N - 1), |F| (N - 1)) (``sphere_lookup``); the
value is the form factor itself (not divided by |F|). Shipped in tables.npz as "ltc_GGX",
"ltc_BECKMANN", "ltc_sphere" (scripts/build_tables.py).

**Form factors.** ``polygon_form_factor_vector`` returns F = 1 / (2 pi) sum_i theta_i g_i (g_i
the unit normal of the plane through corners i, i + 1, theta_i the angle between them), oriented
towards the polygon whatever its winding: |F| <= 1 is the polygon's form factor towards a
surface facing F, F.z towards the surface of normal z when the polygon is wholly above its
horizon. glsl/lights.glsl's E_Area sums V = 1/2 sum theta_i g_i = pi F (irradiance L |V|).
Horizon clipping (``ltc_integral``): in the cosine space, the polygon is replaced by the
spherical cap of the same F, sin^2 sigma = |F| centred at z = F.z / |F|, whose clipped form
factor is Snyder's closed form (``cap_form_factor``), tabulated.

**Fitting** (``compute_ltc_table``). M = R(theta) [[p0, 0, p0 s], [0, p1, 0], [0, 0, 1]] (R the
rotation about y taking z to the lobe's axis) with four parameters (ln p0, ln p1, s, theta)
minimising Heitz et al.'s L3 error  integral |D - f (n.l) / E|^3, times a price on turning the
axis away from the BRDF lobe's mean direction, 1 + TILT_PENALTY (dtheta / alpha)^2 (Heitz et al.
fix the axis there; a clamped cosine has nothing behind its horizon, so a rough lobe tilted to
its mean direction lost its backward tail: see "the LTC family" below). The error is estimated
deterministically: the balance-heuristic combination of a stratified midpoint grid of the BRDF's
half-vector sampling (48 x 16) and a cosine grid (32 x 16) mapped by the current M (so the LTC's
own mass is always sampled), over the half space y >= 0. Nelder-Mead (written here, run on a
whole row in lockstep: a cell fitted alone follows the same path, bit for bit), twice from the
last result. Sweep: the roughest row from n.v = 1 (seeded with the cosine) towards grazing, each
cell from its neighbour; then each smoother row from the row above, its widths scaled by the
ratio of the alphas. The seeds are read back from the float32 table, so any cell can be refitted
alone (``seed_for``, ``fit_cells``). Both distributions: ~2 min each on one core.

**The estimate** (``lobe_integral``): E I is right only where the LTC has the BRDF's shape; a
ratio estimator takes the BRDF itself towards the light, exact for small lights, blended by I
towards E I, exact for a light that holds the whole lobe.

**Measured** (tests/test_ltc.py: ``area_specular`` against adaptive brute-force quadrature of
brdf.py's D V (n.l) over the polygon's area, 6 lights: small and large at the mirror direction,
off to the side, straddling the horizon, a triangle, a pentagon; n.v = 0.2, 0.5, 0.9). GGX, over
the lights receiving >= 1 % of E: worst / mean |relative error| 11 % / 1.0 % at r = 0.1,
25 % / 3.7 % at r = 0.3, 39 % / 8.9 % at r = 0.6, 18 % / 5.2 % at r = 1; worst |error| / E 0.2 %,
10 %, 11 %, 1.9 % (the axis fixed and E I alone: 9.6 / 0.9, 41 / 7.8, 57 / 17, 19 / 4.9 %; 0.3,
12.8, 18.9, 0.7 %). The large errors are lights straddling the horizon seen at n.v = 0.2 and
lights in the lobe's tails; a small light at the mirror direction is within 2e-4. Beckmann's
Gaussian peak is not a cosine's shape: a small light at the mirror direction gets 18-22 % too
little at r = 0.1 (1-3 % at r = 0.3; worst |error| / E 20 % at r = 0.1, 11 % at r = 0.6). Against
Cycles (tests/test_light_shapes.py, a white GGX metal sphere under each area shape): 1.1-1.5 % /
1.6-2.1 % / 1.2-1.4 % / 0.9-1.3 % at r = 0.1 / 0.3 / 0.6 / 1. The sphere approximation, for the
diffuse form factor (M = identity) of lights straddling the horizon: errors 0.0006-0.018 in form
factors 0.04-0.12 (-15 % to +7 %), 0.0009 for one almost wholly below (form factor 0.0009); its
table's interpolation error <= 0.029 (mean 7e-4); exact for lights wholly above. Fitted lobes
integrate to 1 (to the test's quadrature, 1e-4); the mass above the horizon is >= 0.997 along
r = 1, down to 0.995 at r = 0.75 and 0.990 at r = 0.5 at grazing incidence (0.96 and 0.89 with
the axis fixed).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from . import brdf, multiscatter

LTC_SIZE = 64
SPHERE_SIZE = 32
NDFS = ("GGX", "BECKMANN")

# --- the lobe to fit ---------------------------------------------------------------------------

# The quadrature of a cell's error: a stratified midpoint grid of the BRDF's half-vector sampling
# (BRDF_STRATA values of xi by AZIMUTHS azimuths) and one of the clamped cosine's, mapped by the
# current M (LTC_STRATA by AZIMUTHS), both over the half space y >= 0: the BRDF lobe and every LTC
# of the family are symmetric about the plane of n and v.
BRDF_STRATA = 48
LTC_STRATA = 32
AZIMUTHS = 16
NM_STEPS = (0.1, 0.02)  # Nelder-Mead runs per cell, each from the last one's result
#: The price of turning the lobe's axis away from the BRDF's mean direction by dtheta: the error
#: is multiplied by 1 + TILT_PENALTY dtheta^2 / alpha^2 (see ``_errors``).
TILT_PENALTY = 0.01
NM_ITERATIONS = 300
NM_XTOL = 1e-5
NM_FTOL = 1e-7


def _alpha(roughness):
    r = np.maximum(np.asarray(roughness, np.float64), brdf.MIN_PERCEPTUAL_ROUGHNESS)
    return r * r


def _terms(ndf: str):
    D = brdf.D_Beckmann if ndf == "BECKMANN" else brdf.D_GGX
    V = brdf.V_SmithBeckmannCorrelated if ndf == "BECKMANN" else brdf.V_SmithGGXCorrelated
    return D, V


def lobe(ndf: str, mu, alpha, l):
    """(f(v, l) (n.l), the density of l = reflect(-v, h) for h drawn by D(h) (n.h)) in the local
    frame, v = (sqrt(1 - mu^2), 0, mu): F = 1, height-correlated Smith, f = 0 below the horizon;
    both per solid angle over the whole sphere. l (..., 3) unit; mu, alpha broadcast with
    l[..., 0]."""
    D, V = _terms(ndf)
    mu = np.asarray(mu, np.float64)
    alpha = np.asarray(alpha, np.float64)
    hx, hy, hz = l[..., 0] + np.sqrt(np.maximum(1.0 - mu * mu, 0.0)), l[..., 1], l[..., 2] + mu
    hlen = np.sqrt(hx * hx + hy * hy + hz * hz)
    ok = hlen > 1e-12  # l = -v: no half vector
    NoL = l[..., 2]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        inv = 1.0 / np.where(ok, hlen, 1.0)
        NoH = hz * inv
        VoH = 0.5 * hlen  # v.h = (1 + v.l) / |v + l| = |v + l| / 2
        d = np.where(ok & (NoH > 0.0), D(NoH, np.maximum(1.0 - NoH * NoH, 0.0), alpha), 0.0)
        NoLs = np.maximum(NoL, 1e-12)
        f = np.where(NoL > 0.0, d * V(mu, NoLs, alpha) * NoLs, 0.0)
        pdf = d * np.maximum(NoH, 0.0) / (4.0 * np.maximum(VoH, 1e-12))
    return f, pdf


def _brdf_samples(ndf: str, mu: float, alpha: float) -> np.ndarray:
    """Directions l (K, 3) on the BRDF's stratified half-vector grid (y >= 0)."""
    xi = (np.arange(BRDF_STRATA) + 0.5) / BRDF_STRATA
    tan2 = alpha * alpha * (xi / (1.0 - xi) if ndf == "GGX" else -np.log1p(-xi))
    cos_t = 1.0 / np.sqrt(1.0 + tan2)
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    phi = (np.arange(AZIMUTHS) + 0.5) / AZIMUTHS * np.pi
    h = np.stack([np.outer(sin_t, np.cos(phi)), np.outer(sin_t, np.sin(phi)),
                  np.outer(cos_t, np.ones_like(phi))], axis=-1).reshape(-1, 3)
    v = np.array([np.sqrt(max(1.0 - mu * mu, 0.0)), 0.0, mu])
    return 2.0 * (h @ v)[:, None] * h - v


def _cosine_samples() -> np.ndarray:
    """Clamped-cosine distributed directions (K, 3) (y >= 0) on a stratified midpoint grid."""
    u = (np.arange(LTC_STRATA) + 0.5) / LTC_STRATA
    phi = (np.arange(AZIMUTHS) + 0.5) / AZIMUTHS * np.pi
    r = np.sqrt(u)
    return np.stack([np.outer(r, np.cos(phi)), np.outer(r, np.sin(phi)),
                     np.outer(np.sqrt(1.0 - u), np.ones_like(phi))], axis=-1).reshape(-1, 3)


# --- the LTC family --------------------------------------------------------------------------------
#
# Parameters q = (ln p0, ln p1, s, theta): M = R(theta) S, S = [[p0, 0, p0 s], [0, p1, 0], [0, 0, 1]],
# R(theta) the rotation about y that takes z to (sin theta, 0, cos theta). p0, p1 are the lobe's
# widths in and across the plane of incidence, s a shear in units of the width (Heitz et al.'s
# m11, m22, m13), and the axis theta. Heitz et al. fix the axis at the BRDF lobe's mean direction;
# but the clamped cosine's support is the hemisphere about its axis, so a rough lobe tilted there
# has nothing behind it (at r = 0.6, n.v = 0.77 the LTC fell to zero 60 degrees from the normal
# towards the viewer, where GGX is still a tenth of its peak), and a rough sphere under an area
# light lost its outer ring (14 % from Cycles). Here theta is fitted too, as a turn dtheta from
# the mean direction priced by 1 + TILT_PENALTY (dtheta / alpha)^2 (``_errors``): free for rough
# lobes, held near the mean direction for narrow ones, whose fits otherwise wander along a valley
# of nearly equal fits between the axis and the shear from one cell to the next.


def _minv(q: np.ndarray) -> np.ndarray:
    """M^-1 (..., 3, 3) of parameters q (..., 4)."""
    p0, p1, s = np.exp(q[..., 0]), np.exp(q[..., 1]), q[..., 2]
    c, sn = np.cos(q[..., 3]), np.sin(q[..., 3])
    out = np.zeros(q.shape[:-1] + (3, 3))
    # inv(S) = [[1/p0, 0, -s], [0, 1/p1, 0], [0, 0, 1]], M^-1 = inv(S) R^T
    out[..., 0, 0] = c / p0 - s * sn
    out[..., 0, 2] = -sn / p0 - s * c
    out[..., 1, 1] = 1.0 / p1
    out[..., 2, 0] = sn
    out[..., 2, 2] = c
    return out


def _m(q: np.ndarray) -> np.ndarray:
    """M (..., 3, 3) = R(theta) S of parameters q (..., 4)."""
    p0, p1, s = np.exp(q[..., 0]), np.exp(q[..., 1]), q[..., 2]
    c, sn = np.cos(q[..., 3]), np.sin(q[..., 3])
    out = np.zeros(q.shape[:-1] + (3, 3))
    out[..., 0, 0], out[..., 0, 2] = c * p0, c * p0 * s + sn
    out[..., 1, 1] = p1
    out[..., 2, 0], out[..., 2, 2] = -sn * p0, -sn * p0 * s + c
    return out


def entries_from_params(q: np.ndarray) -> np.ndarray:
    """The stored (a, b, d, e) = (m00, m02, m20, m22) of M^-1 scaled so that m11 = 1."""
    m = _minv(q) * np.exp(q[..., 1])[..., None, None]
    return np.stack([m[..., 0, 0], m[..., 0, 2], m[..., 2, 0], m[..., 2, 2]], axis=-1)


def params_from_entries(entries: np.ndarray) -> np.ndarray:
    """q of stored entries: the inverse of ``entries_from_params`` (d = p1 sin theta,
    e = p1 cos theta, and [a, b] R = [p1 / p0, -s p1])."""
    e = np.asarray(entries, np.float64)
    a, b, d, ee = e[..., 0], e[..., 1], e[..., 2], e[..., 3]
    p1 = np.hypot(d, ee)
    c, sn = ee / p1, d / p1
    inv_p0 = (a * c - b * sn) / p1
    s = -(a * sn + b * c) / p1
    return np.stack([-np.log(inv_p0), np.log(p1), s, np.arctan2(d, ee)], axis=-1)


def minv_from_entries(entries) -> np.ndarray:
    """M^-1 (..., 3, 3) = [[a, 0, b], [0, 1, 0], [d, 0, e]] of stored entries (a, b, d, e)."""
    e = np.asarray(entries, np.float64)
    minv = np.zeros(e.shape[:-1] + (3, 3))
    minv[..., 0, 0], minv[..., 0, 2], minv[..., 1, 1] = e[..., 0], e[..., 1], 1.0
    minv[..., 2, 0], minv[..., 2, 2] = e[..., 2], e[..., 3]
    return minv


def ltc_direction(entries, w) -> np.ndarray:
    """ltc.glsl's ltc_direction: M w / |M w| (..., 3) for the LTC of stored entries (a, b, d, e) at
    directions ``w`` of the clamped cosine's space, M = adj(M^-1) = [[e, 0, -b], [0, ae - bd, 0],
    [-d, 0, a]]."""
    e = np.asarray(entries, np.float64)
    w = np.asarray(w, np.float64)
    a, b, d, f = e[..., 0], e[..., 1], e[..., 2], e[..., 3]
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    out = np.stack([f * x - b * z, (a * f - b * d) * y, a * z - d * x], -1)
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def ltc_density(minv: np.ndarray, w: np.ndarray, floor=0.0) -> np.ndarray:
    """D(w) = D_o(M^-1 w / |M^-1 w|) |det M^-1| / |M^-1 w|^3, D_o = max(z, floor) / pi; w (..., 3)
    unit, minv (3, 3) or broadcastable (..., 3, 3) (any scale: D does not depend on it). ``floor``
    (0: the clamped cosine's own): ``density_floor``'s, for a small light."""
    y = np.einsum("...ij,...j->...i", minv, w)
    len2 = np.maximum(np.sum(y * y, axis=-1), 1e-24)  # ltc.glsl's: len2^1.5 a normal float32
    cosine = np.maximum(y[..., 2] / np.sqrt(len2), floor)
    return cosine * np.abs(np.linalg.det(minv)) / (np.pi * len2 * np.sqrt(len2))


def _cells(ndf: str, mu: np.ndarray, roughness: np.ndarray) -> dict:
    """The fixed part of each cell's quadrature, stacked: the BRDF samples (B, K_b) and the
    lobe's value and density there, normalised by E (the engine's albedo-table quadrature, finer
    than this grid), and the cosine grid the LTC samples are mapped from."""
    alpha = _alpha(roughness)
    E = np.array([multiscatter.directional_albedo(ndf, "SMITH_CORRELATED", [m], r)[0]
                  for m, r in zip(mu, roughness)])
    lb = np.stack([_brdf_samples(ndf, m, a) for m, a in zip(mu, alpha)])
    fb, pb = lobe(ndf, mu[:, None], alpha[:, None], lb)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(pb > 0.0, fb / pb, 0.0)
    mean = np.sum(ratio[..., None] * lb, axis=1)  # the lobe's mean direction (its y cancels)
    return {"ndf": ndf, "mu": mu, "alpha": alpha, "E": E, "wo": _cosine_samples(),
            "theta": np.arctan2(mean[:, 0], mean[:, 2]),
            "bx": np.ascontiguousarray(lb[..., 0]), "by": np.ascontiguousarray(lb[..., 1]),
            "bz": np.ascontiguousarray(lb[..., 2]), "bf": fb / E[:, None], "bp": pb}


def _l3(D, f, density):
    """sum |D - f|^3 / density over the last axis (a sample neither strategy draws counts 0)."""
    diff = np.abs(D - f)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sum(np.where(density > 0.0, diff * diff * diff / density, 0.0), axis=-1)


def _errors(data: dict, idx: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The L3 error  integral |D - f (n.l) / E|^3  of parameters q = (ln p0, ln p1, s, dtheta)
    (m, 4), dtheta the axis's turn from the mean direction of the cells idx (m) of ``_cells``: the
    balance-heuristic estimate from the BRDF's samples and the LTC's own (the cosine grid mapped by
    this M), Heitz et al.'s error, times the tilt's price."""
    nb, nl = data["bx"].shape[1], len(data["wo"])
    dtheta = q[:, 3]
    q = np.concatenate([q[:, :3], (data["theta"][idx] + dtheta)[:, None]], axis=-1)
    minv = _minv(q)
    det = (minv[:, 0, 0] * minv[:, 2, 2] - minv[:, 0, 2] * minv[:, 2, 0]) * minv[:, 1, 1]
    # the LTC at the BRDF's samples
    bx, by, bz = data["bx"][idx], data["by"][idx], data["bz"][idx]
    y0 = minv[:, 0, 0, None] * bx + minv[:, 0, 2, None] * bz
    y1 = minv[:, 1, 1, None] * by
    y2 = minv[:, 2, 0, None] * bx + minv[:, 2, 2, None] * bz
    len2 = y0 * y0 + y1 * y1 + y2 * y2
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        Db = np.maximum(y2, 0.0) * (np.abs(det) / np.pi)[:, None] / (len2 * len2)
    err = _l3(Db, data["bf"][idx], nb * data["bp"][idx] + nl * Db)
    # the LTC's samples w = M w_o / |M w_o|, where D = D_o(w_o) |det M^-1| |M w_o|^3
    wo = data["wo"]
    mw = np.einsum("mij,kj->mki", _m(q), wo)
    length = np.linalg.norm(mw, axis=-1)
    w = mw / length[..., None]
    Dl = (wo[:, 2] / np.pi)[None, :] * np.abs(det)[:, None] * length ** 3
    fl, pl = lobe(data["ndf"], data["mu"][idx, None], data["alpha"][idx, None], w)
    err += _l3(Dl, fl / data["E"][idx, None], nb * pl + nl * Dl)
    # the axis may turn away from the mean direction, at a price that grows as the lobe narrows:
    # a narrow lobe has a valley of nearly equal fits along the axis and the shear, and without it
    # the fits jumped along the valley from cell to cell (a table that cannot be interpolated)
    tilt = TILT_PENALTY / np.maximum(data["alpha"][idx], 1e-3) ** 2
    return err * (1.0 + tilt * dtheta * dtheta)


def _nelder_mead(fun, x0: np.ndarray, step: float) -> np.ndarray:
    """Nelder-Mead (standard coefficients 1, 2, 1/2, 1/2) run on B independent problems in
    lockstep: fun(idx, points (m, n)) -> values (m,) for problems idx. Each problem's sequence of
    points depends on its own values only, so a problem fitted alone follows the same path. Stops
    per problem when its simplex is within NM_XTOL and its values within NM_FTOL relative, or
    after NM_ITERATIONS."""
    B, n = x0.shape
    simplex = np.repeat(x0[:, None, :], n + 1, axis=1)
    for k in range(n):
        simplex[:, k + 1, k] += step
    all_idx = np.arange(B)
    values = fun(np.repeat(all_idx, n + 1), simplex.reshape(-1, n)).reshape(B, n + 1)
    active = np.ones(B, bool)
    for _ in range(NM_ITERATIONS):
        order = np.argsort(values, axis=1, kind="stable")
        simplex = np.take_along_axis(simplex, order[..., None], axis=1)
        values = np.take_along_axis(values, order, axis=1)
        spread = np.abs(simplex[:, 1:] - simplex[:, :1]).max(axis=(1, 2))
        fspread = values[:, -1] - values[:, 0]
        active &= ~((spread <= NM_XTOL) & (fspread <= NM_FTOL * np.abs(values[:, 0])))
        ia = all_idx[active]
        if len(ia) == 0:
            break
        s, fv = simplex[ia], values[ia]
        centroid = s[:, :n].mean(axis=1)
        worst = s[:, n]
        xr = 2.0 * centroid - worst
        fr = fun(ia, xr)
        expand = fr < fv[:, 0]
        accept_r = (~expand) & (fr < fv[:, n - 1])
        outside = (~expand) & (~accept_r) & (fr < fv[:, n])
        inside = (~expand) & (~accept_r) & (~outside)
        x2 = np.where(expand[:, None], 3.0 * centroid - 2.0 * worst,
                      np.where(outside[:, None], 0.5 * (centroid + xr), 0.5 * (centroid + worst)))
        need = ~accept_r
        f2 = np.full(len(ia), np.inf)
        if need.any():
            f2[need] = fun(ia[need], x2[need])
        new_x, new_f = xr.copy(), fr.copy()
        take2 = (expand & (f2 < fr)) | (outside & (f2 <= fr)) | (inside & (f2 < fv[:, n]))
        new_x[take2], new_f[take2] = x2[take2], f2[take2]
        shrink = (outside | inside) & ~take2
        keep = ~shrink
        s[keep, n], fv[keep, n] = new_x[keep], new_f[keep]
        if shrink.any():
            si = np.nonzero(shrink)[0]
            pts = 0.5 * (s[si, :1] + s[si, 1:])  # (k, n, n)
            s[si, 1:] = pts
            fv[si, 1:] = fun(np.repeat(ia[si], n), pts.reshape(-1, n)).reshape(len(si), n)
        simplex[ia], values[ia] = s, fv
    best = np.argmin(values, axis=1)
    return simplex[all_idx, best]


def fit_cells(ndf: str, mu, roughness, seeds):
    """Fit the LTC of each (mu, roughness) from its seed (ln p0, ln p1, s, theta) (m, 4), all
    cells at once in lockstep: Nelder-Mead minimisations of ``_errors``, one per step of NM_STEPS,
    each from the last one's result. Returns (table entries (m, 4) float32, parameters q (m, 4)
    with theta last, E (m,))."""
    mu = np.atleast_1d(np.asarray(mu, np.float64))
    roughness = np.broadcast_to(np.asarray(roughness, np.float64), mu.shape)
    q = np.array(seeds, np.float64).reshape(len(mu), 4)
    data = _cells(ndf, mu, roughness)
    q[:, 3] -= data["theta"]  # the seeds' axes, fitted as a turn from each cell's mean direction
    for step in NM_STEPS:
        q = _nelder_mead(lambda idx, pts: _errors(data, idx, pts), q, step)
    q = np.concatenate([q[:, :3], (data["theta"] + q[:, 3])[:, None]], axis=-1)
    return entries_from_params(q).astype(np.float32), q, data["E"]


def table_grid(size: int = LTC_SIZE) -> tuple[np.ndarray, np.ndarray]:
    """(mu of each column, roughness of each row): column i <-> t = i / (size - 1), mu = 1 - t^2
    (floored at MIN_COS); row j <-> r = j / (size - 1) (fitted at max(r, MIN_PERCEPTUAL_ROUGHNESS))."""
    t = np.arange(size) / (size - 1)
    return np.maximum(1.0 - t * t, brdf.MIN_COS), np.arange(size) / (size - 1)


IDENTITY_SEED = np.zeros(4)  # p0 = p1 = 1, s = 0, theta = 0: the first cell's (n.v = 1, r = 1) seed


def seed_for(table: np.ndarray, j: int, i: int) -> np.ndarray:
    """The seed of cell (j, i) as the build uses it, from the (float32) table entries already
    fitted: the last row (r = 1) from its left neighbour (the first cell from the identity), every
    other row from the cell above it (rougher), its widths scaled by the ratio of the alphas."""
    size = table.shape[0]
    if j == size - 1:
        return IDENTITY_SEED.copy() if i == 0 else params_from_entries(table[j, i - 1])
    _, rough = table_grid(size)
    q = params_from_entries(table[j + 1, i])
    q[:2] += np.log(_alpha(rough[j]) / _alpha(rough[j + 1]))
    return q


@lru_cache(maxsize=4)
def compute_ltc_table(ndf: str, size: int = LTC_SIZE) -> np.ndarray:
    """(size, size, 4) float32: [j, i] = (a, b, d, e) of M^-1 (normalised to m11 = 1) for
    roughness row j and mu column i (``table_grid``), fitted as the module's "Fitting" says: the
    roughest row cell by cell from n.v = 1, then each smoother row from the row above, its cells
    fitted together in lockstep."""
    mu, rough = table_grid(size)
    table = np.zeros((size, size, 4), np.float32)
    j = size - 1
    for i in range(size):  # the roughest row along mu, each cell from its neighbour
        table[j, i] = fit_cells(ndf, mu[i:i + 1], rough[j], seed_for(table, j, i)[None])[0][0]
    for j in range(size - 2, -1, -1):
        seeds = np.stack([seed_for(table, j, i) for i in range(size)])
        table[j] = fit_cells(ndf, mu, rough[j], seeds)[0]
    return table


# --- horizon clipping by a sphere (Heitz & Hill 2017) ---------------------------------------------

def cap_form_factor(sin2_sigma, z) -> np.ndarray:
    """Form factor (integral of max(w.z, 0) / pi) of a spherical cap of angular radius sigma whose
    centre is at cos(angle to the normal) = z, clipped by the horizon: sin^2 sigma z when the cap
    is wholly above (z >= sin sigma), 0 wholly below, in between Snyder 1996's closed form
    (as in Lagarde & de Rousiers 2014, "Moving Frostbite to PBR", eq. 15)."""
    s2 = np.clip(np.asarray(sin2_sigma, np.float64), 0.0, 1.0)
    z = np.clip(np.asarray(z, np.float64), -1.0, 1.0)
    s2, z = np.broadcast_arrays(s2, z)
    sin_s = np.sqrt(s2)
    partial = np.abs(z) < sin_s
    zp = np.where(partial, z, 0.0)
    sp = np.where(partial, s2, 1.0)
    sin_w = np.sqrt(1.0 - zp * zp)
    cot_s = np.sqrt(1.0 - sp) / np.sqrt(sp)  # x in Snyder's notation
    y = -cot_s * zp / sin_w  # -cot sigma cot omega, |y| < 1 inside the partial range
    g = sin_w * np.sqrt(np.maximum(1.0 - y * y, 0.0))
    clipped = ((zp * np.arccos(np.clip(y, -1.0, 1.0)) - cot_s * g) * sp + np.arctan2(g, cot_s)) / np.pi
    return np.where(partial, clipped, np.where(z >= sin_s, s2 * z, 0.0))


def sphere_grid(size: int = SPHERE_SIZE) -> tuple[np.ndarray, np.ndarray]:
    """(|F| of each row, z of each column): row j <-> |F| = j / (size - 1), column i <->
    z = 2 i / (size - 1) - 1."""
    g = np.arange(size) / (size - 1)
    return g, 2.0 * g - 1.0


@lru_cache(maxsize=2)
def compute_sphere_table(size: int = SPHERE_SIZE) -> np.ndarray:
    """(size, size) float32: [j, i] = the horizon-clipped form factor of the cap with
    sin^2 sigma = |F| = j / (size - 1) centred at z = 2 i / (size - 1) - 1 (``sphere_grid``)."""
    length, z = sphere_grid(size)
    return cap_form_factor(length[:, None], z[None, :]).astype(np.float32)


def sphere_lookup(table: np.ndarray, length, z) -> np.ndarray:
    """Bilinear lookup of ``compute_sphere_table`` at |F| = length, z (clamped to the grid)."""
    n = table.shape[0]
    x = np.clip((np.asarray(z, np.float64) + 1.0) * 0.5 * (n - 1), 0.0, n - 1.0)
    y = np.clip(np.asarray(length, np.float64) * (n - 1), 0.0, n - 1.0)
    return _bilinear(table.astype(np.float64), x, y)


def _bilinear(t: np.ndarray, x, y) -> np.ndarray:
    """t[j, i, ...] at column coordinate x, row coordinate y (in texels, already clamped)."""
    n_rows, n_cols = t.shape[:2]
    i0, j0 = np.floor(x).astype(int), np.floor(y).astype(int)
    i1, j1 = np.minimum(i0 + 1, n_cols - 1), np.minimum(j0 + 1, n_rows - 1)
    trailing = (1,) * (t.ndim - 2)
    tx = np.reshape(x - i0, np.shape(x) + trailing)
    ty = np.reshape(y - j0, np.shape(y) + trailing)
    top = t[j0, i0] * (1.0 - tx) + t[j0, i1] * tx
    bottom = t[j1, i0] * (1.0 - tx) + t[j1, i1] * tx
    return top * (1.0 - ty) + bottom * ty


# --- evaluation (the twin of glsl/ltc.glsl) --------------------------------------------------------

def lookup(table: np.ndarray, mu, roughness) -> np.ndarray:
    """Bilinear lookup of an LTC table at n.v = mu, perceptual roughness: (..., 4) entries
    (a, b, d, e); column coordinate sqrt(1 - mu) (N - 1), row roughness (N - 1), clamped."""
    n = table.shape[0]
    t = np.sqrt(np.clip(1.0 - np.asarray(mu, np.float64), 0.0, 1.0))
    x = np.clip(t * (n - 1), 0.0, n - 1.0)
    y = np.clip(np.asarray(roughness, np.float64) * (n - 1), 0.0, n - 1.0)
    x, y = np.broadcast_arrays(x, y)
    return _bilinear(table.astype(np.float64), x, y)


def polygon_form_factor(offsets, to_centre):
    """V = 1/2 sum theta_i g_i of the polygon of corners ``offsets`` ((n, 3), or (..., n, 3) per
    point) from its centre, seen from the points at -to_centre from it, oriented towards the
    polygon (glsl/lights.glsl's polygon_form_factor with the identity map; with an LTC's M^-1,
    offsets and to_centre mapped first). The corners' cross products as the shader forms them:
    (t + oa) x (t + ob) = t x (ob - oa) + oa x ob."""
    offsets = np.asarray(offsets, np.float64)
    to_centre = np.asarray(to_centre, np.float64)
    V = np.zeros(np.broadcast_shapes(np.shape(to_centre), offsets.shape[:-2] + (3,)))
    for i in range(offsets.shape[-2]):
        oa, ob = offsets[..., i - 1, :], offsets[..., i, :]
        c = np.cross(to_centre, ob - oa) + np.cross(oa, ob)
        sin = np.linalg.norm(c, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            cosine = np.sum((to_centre + oa) * (to_centre + ob), axis=-1)
            edge = c * (np.arctan2(sin, cosine) / sin)[..., None]
        V = V + np.where((sin > 0.0)[..., None], edge, 0.0)
    V = 0.5 * V
    return np.where((np.sum(V * to_centre, axis=-1) < 0.0)[..., None], -V, V)


def polygon_form_factor_vector(corners) -> np.ndarray:
    """F = 1 / (2 pi) sum_i theta_i g_i = V / pi of a planar polygon, corners (..., n, 3) relative
    to the shading point (any frame, any winding): theta_i the angle between corners i and i + 1,
    g_i the unit normal of the plane through them. F is oriented towards the polygon (the integral
    of w / pi over the directions w it subtends), |F| its form factor towards a surface facing F,
    F.z its form factor towards a surface of normal z when it lies wholly above that surface's
    horizon. ``polygon_form_factor`` about the corners' mean (the light's centre, for the
    symmetric polygons the shaders make, and for their images under a linear map)."""
    p = np.asarray(corners, np.float64)
    centre = p.mean(axis=-2)
    return polygon_form_factor(p - centre[..., None, :], centre) / np.pi


def ltc_integral(minv_entries, corners_local, sphere: np.ndarray | None = None, jitter=None,
                 with_length: bool = False):
    """The integral over a polygon of the LTC of entries (a, b, d, e) (..., 4), corners
    (..., n, 3) in the local frame (z = n, x = the tangent towards v): the polygon is mapped by
    M^-1, its vector form factor F taken there and clipped to the horizon by the sphere of the same
    F (``sphere_lookup``): a form factor in [0, 1]. Entries (1, 0, 0, 1) (M = identity) give the
    clipped diffuse form factor. ``jitter`` (roundings, unit directions (..., 3)), for tests: the
    mapped corners moved along the directions (alternately +-) by that many float32 roundings of
    each coordinate's product with M^-1, and F by as many of its terms (sum theta_i / 2 pi): the
    errors float32 leaves there, to measure how far they move the result
    (tests/test_stability.py)."""
    sphere = sphere_table() if sphere is None else sphere
    m = np.asarray(minv_entries, np.float64)
    a, b, d, e = (m[..., k, None] for k in range(4))
    p = np.asarray(corners_local, np.float64)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    mapped = np.stack([a * x + b * z, y, d * x + e * z], axis=-1)
    if jitter is not None:  # each mapped coordinate a product with M^-1's row: as many roundings of it
        roundings, direction = jitter
        unit = roundings * float(np.finfo(np.float32).eps) / 2.0
        rows = np.stack([np.hypot(a, b), np.ones_like(a), np.hypot(d, e)], axis=-1)  # (..., 1, 3)
        sign = np.where(np.arange(p.shape[-2]) % 2 == 0, 1.0, -1.0)[:, None]  # corners apart
        mapped = mapped + (unit * rows * np.linalg.norm(p, axis=-1, keepdims=True) * sign
                           * np.asarray(direction, np.float64)[..., None, :])
    F = polygon_form_factor_vector(mapped)
    if jitter is not None:
        nxt = np.roll(mapped, -1, axis=-2)
        angles = np.arctan2(np.linalg.norm(np.cross(mapped, nxt), axis=-1), np.sum(mapped * nxt, axis=-1))
        F = F + (unit * angles.sum(axis=-1) / (2.0 * np.pi))[..., None] * np.asarray(direction, np.float64)
    length = np.linalg.norm(F, axis=-1)
    safe = np.where(length > 0.0, length, 1.0)
    out = np.where(length > 0.0, sphere_lookup(sphere, np.minimum(length, 1.0), F[..., 2] / safe), 0.0)
    return (out, np.minimum(length, 1.0)) if with_length else out


#: Below this length of the mapped polygon's vector form factor (fading out linearly towards it)
#: a light's density is floored at its mean over the polygon (``density_floor``).
SMALL_POLYGON = 0.1


def density_floor(form_factor, length):
    """The cosine a light's density is floored at (``ltc_density``) where its polygon, mapped by
    M^-1, is small: the mean over it, I / |F| (the cap of the same vector form factor F: z when
    wholly above the horizon, the clipped integral's own across it), faded out as |F| grows to
    SMALL_POLYGON (ltc.glsl's ltc_density_floor, with the measurements). The density at the light's
    direction alone is 0 below the cosine's horizon, where the clipped cap still holds some of it,
    and far below the mean where the lobe's tail is steep: the ratio estimator (``lobe_integral``)
    overshot such tails 3-30x under a small light."""
    length = np.asarray(length, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        own = np.where(length > 0.0, np.asarray(form_factor) / np.where(length > 0.0, length, 1.0), 0.0)
    return own * np.clip(1.0 - length / SMALL_POLYGON, 0.0, 1.0)


def shading_frame(n, v):
    """(x, y, z) unit axes (..., 3) of the local frame: z = n, x = the tangent towards v (any
    tangent when v is along n), y = z x x; and mu = n.v floored at MIN_COS."""
    z = np.asarray(n, np.float64)
    v = np.asarray(v, np.float64)
    NoV = np.sum(z * v, axis=-1)
    t = v - NoV[..., None] * z
    tlen = np.linalg.norm(t, axis=-1)
    other = np.where((np.abs(z[..., 0]) < 0.9)[..., None], np.array([1.0, 0.0, 0.0]),
                     np.array([0.0, 1.0, 0.0]))
    fallback = np.cross(other, z)
    fallback /= np.linalg.norm(fallback, axis=-1, keepdims=True)
    x = np.where((tlen > 1e-9)[..., None], t / np.where(tlen > 1e-9, tlen, 1.0)[..., None], fallback)
    return x, np.cross(z, x), z, np.clip(NoV, brdf.MIN_COS, 1.0)


#: The most the lobe's shape correction may scale the LTC's integral, in units of the albedo
#: (``lobe_integral``): where the light's direction lies beyond the fitted cosine's horizon but the
#: light reaches into the lobe the ratio is unbounded. Measured against Cycles (glsl/ltc.glsl's
#: comment): 1.5 is the best of 1, 1.5, 2 and 10 on the area-light tests.
MAX_SHAPE_RATIO = 1.5


def lobe_integral(form_factor, albedo, lobe_at_mean, density_at_mean):
    """The specular integral over a polygon, int_P f (n.l), from the LTC's integral I over it
    (``form_factor``) and the albedo E: E I would be right if the LTC were the BRDF's shape; it
    is not, in the tails of rough lobes. A ratio estimator takes the BRDF itself towards the light
    (its irradiance-weighted direction l, well conditioned where the lobe's own mean direction
    M F is not), c = f (n.l) / D there, exact for a small light (I -> D dw);
    a light that holds the whole lobe (I -> 1) is E exactly. The two limits are blended by I:
    I (c + (E - c) I), with c <= MAX_SHAPE_RATIO E. Against Cycles, a white GGX metal sphere at
    roughness 0.6 under a square light: E I (axis fixed) 14 %, this 1.4 % (tests/test_light_shapes.py)."""
    I = np.asarray(form_factor, np.float64)
    E = np.asarray(albedo, np.float64)
    D = np.asarray(density_at_mean, np.float64)
    c = np.minimum(np.asarray(lobe_at_mean, np.float64) / np.maximum(D, 1e-30), MAX_SHAPE_RATIO * E)
    return I * (c + (E - c) * np.minimum(I, 1.0))


def mean_direction(minv_entries, corners_local) -> np.ndarray:
    """The LTC's own mean direction over a polygon, M F (F the vector form factor of the polygon mapped by
    M^-1, mapped back by M; unit, local frame): where closures.glsl's glossy_ltc_ratio takes a
    Beckmann or Ashikhmin-Shirley lobe for ``lobe_integral``'s ratio (beside 16 points of the light:
    ``glossy_ratio``), in place of the light's irradiance-weighted direction."""
    minv = minv_from_entries(minv_entries)
    mapped = np.einsum("...ij,...kj->...ki", minv, np.asarray(corners_local, np.float64))
    d = np.linalg.solve(minv, polygon_form_factor_vector(mapped)[..., None])[..., 0]
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def glossy_ratio(minv_entries, corners_local, lobe, integral, length):
    """closures.glsl's glossy_ltc_ratio for a rectangle of ``corners_local`` (4, 3; corners 0-1 and 0-3 its
    sides, local frame): (sum f w, sum D w) over the 16 points of lights.glsl's polygon_point
    (closures.polygon_points) and the cosine's mean direction (``mean_direction``) weighted as their mean
    w, its density floored as there (``density_floor`` of ``integral``, ``length``); ``lobe(dirs)`` gives
    f (n.l) at unit directions (K, 3). ``lobe_integral`` takes their ratio."""
    from . import closures

    corners = np.asarray(corners_local, np.float64)
    minv = minv_from_entries(minv_entries)
    dirs, w = closures.polygon_points(corners.mean(0), 0.5 * (corners[1] - corners[0]),
                                      0.5 * (corners[3] - corners[0]), 4)
    mean = mean_direction(minv_entries, corners)
    w_mean = float(w.mean())
    f = float((lobe(dirs) * w).sum()) + w_mean * float(lobe(mean[None])[0])
    floor = density_floor(integral, length)
    D = float((ltc_density(minv, dirs) * w).sum()) + w_mean * float(ltc_density(minv, mean, floor))
    return f, D


def area_specular(p, n, v, corners, roughness, ndf: str = "GGX", light_normal=None) -> np.ndarray:
    """The specular integral  int_P f(v, l) (n.l) dl  (F = 1, height-correlated Smith) of a
    polygon P: ``lobe_integral`` of the LTC's integral over P, the albedo E(mu, r) (multiscatter's
    albedo table) and the BRDF and the LTC towards the polygon's irradiance-weighted direction. p, n,
    v (..., 3): shading
    points, unit normals, unit directions towards the viewer; corners (k, 3) or (..., k, 3) in
    the same (world) frame; light_normal (3,) or (..., 3), optional: the emitting side of a
    one-sided light (0 behind it)."""
    x, y, z, mu = shading_frame(n, v)
    rel = np.asarray(corners, np.float64) - np.asarray(p, np.float64)[..., None, :]
    local = np.stack([np.sum(rel * x[..., None, :], axis=-1), np.sum(rel * y[..., None, :], axis=-1),
                      np.sum(rel * z[..., None, :], axis=-1)], axis=-1)
    entries = lookup(ltc_table(ndf), mu, roughness)
    form_factor, length = ltc_integral(entries, local, with_length=True)
    E = multiscatter.interpolate(multiscatter.albedo_table(ndf, "SMITH_CORRELATED"), mu, roughness)
    F = polygon_form_factor_vector(local)  # the light's irradiance-weighted direction l
    l = F / np.maximum(np.linalg.norm(F, axis=-1, keepdims=True), 1e-300)
    density = ltc_density(minv_from_entries(entries), l, density_floor(form_factor, length))
    out = lobe_integral(form_factor, E, lobe(ndf, mu, _alpha(roughness), l)[0], density)
    if light_normal is not None:
        front = np.sum(-rel.mean(axis=-2) * np.asarray(light_normal, np.float64), axis=-1) > 0.0
        out = np.where(front, out, 0.0)
    return out


# --- the shipped tables ------------------------------------------------------------------------------

def ltc_table(ndf: str, size: int = LTC_SIZE) -> np.ndarray:
    """``compute_ltc_table``, shipped in tables.npz as "ltc_<ndf>"."""
    return multiscatter._table(f"ltc_{ndf}", (size, size, 4), lambda: compute_ltc_table(ndf, size))


def sphere_table(size: int = SPHERE_SIZE) -> np.ndarray:
    """``compute_sphere_table``, shipped in tables.npz as "ltc_sphere"."""
    return multiscatter._table("ltc_sphere", (size, size), lambda: compute_sphere_table(size))


def compute_all() -> dict[str, np.ndarray]:
    """The LTC tables by their names in ``tables.npz``."""
    out = {f"ltc_{ndf}": compute_ltc_table(ndf) for ndf in NDFS}
    out["ltc_sphere"] = compute_sphere_table()
    return out
