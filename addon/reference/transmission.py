"""Numpy twin of glsl/transmission.glsl's lobe math: the dielectric Fresnel split between
reflection and transmission, the refracted direction (Snell's law) and the GGX transmission lobe
(Walter et al. 2007, as Cycles' bsdf_microfacet_eval evaluates a glass closure's transmission).
Rows of vectors (..., 3), float64."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from .brdf import D_GGX, MIN_PERCEPTUAL_ROUGHNESS, F_Dielectric, V_SmithGGXCorrelated

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


def transmission_inner_spread(cos_v, cos_t, eta, alpha, spread):
    """transmission_inner_spread: how far (radians) the first crossing's rough lobe turns the view ray
    refracted in, ``spread`` alpha (1 - cos_v / (eta cos_t)), 0 where cos_t vanishes."""
    cos_v, cos_t, eta, alpha = (np.asarray(x, np.float64) for x in (cos_v, cos_t, eta, alpha))
    with np.errstate(divide="ignore", invalid="ignore"):
        turn = np.maximum(1.0 - cos_v / (eta * cos_t), 0.0)
    return np.where(cos_t > 1e-4, spread * alpha * turn, 0.0)


def transmission_exit_fraction(cos_i, eta, roughness, spread, fresnel=True):
    """transmission_exit_fraction: what crossing a closed object's far face from inside (relative IOR
    1 / eta) passes -- rough glass's glass_transmitted, smooth glass's (roughness at most the floor)
    and the Refraction BSDF's smooth fraction -- averaged over incidence angles theta +- s / sqrt(3),
    +- sqrt(3) s with s = ``spread`` radians (each angle folded at the normal and capped at grazing)."""
    cos_i, eta, roughness = np.broadcast_arrays(*(np.asarray(x, np.float64)
                                                  for x in (cos_i, eta, roughness)))
    c = np.clip(cos_i, 0.0, 1.0)
    sin_i = np.sqrt(1.0 - c * c)
    s = np.asarray(spread, np.float64)
    rough = np.asarray(fresnel) & (roughness > MIN_PERCEPTUAL_ROUGHNESS)
    total = 0.0
    for offset in (1.0 / np.sqrt(3.0), -1.0 / np.sqrt(3.0), np.sqrt(3.0), -np.sqrt(3.0)):
        cos_k = np.maximum(c * np.cos(s * offset) - sin_i * np.sin(s * offset), 0.0)
        smooth = transmission_fraction(cos_k, 1.0 / eta, fresnel)
        total = total + np.where(rough, glass_transmitted(roughness, cos_k, 1.0 / eta), smooth)
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
    undone), each at ``alpha_factor`` x alpha and times its face's glass_compensation, times the
    first crossing's spread's loss at the far face beyond the central ray's (``spread``: the programs'
    REFRACTION_EXIT_SPREAD, transmission_inner_spread); on the inside's side, the GGX reflection with
    the Fresnel from inside (times the far face's compensation). ``first``: the first crossing's
    fraction (what of the glass enters: inside = weight x tint x first)."""
    n, v, inner, exit_n, l = (np.asarray(x, np.float64) for x in (n, v, inner, exit_n, l))
    eta = np.asarray(eta, np.float64)
    a = np.asarray(alpha, np.float64) * alpha_factor
    inside = weight * tint * np.asarray(first, np.float64)
    NoL = _dot(exit_n, l)
    lobe, HoV = transmission_ggx(exit_n, -inner, l, 1.0 / eta, a)
    cos2 = -_dot(inner, exit_n)
    far_compensation = glass_compensation(roughness, cos2, 1.0 / eta, tint, fresnel)
    crossing = np.where(lobe > 0.0, transmission_fraction(HoV, 1.0 / eta, fresnel) * lobe, 0.0)
    far = inside * far_compensation * crossing
    u = transmission_direction(-l, -exit_n, eta)
    cos_in = _dot(u, exit_n)
    lobe2, HoV2 = transmission_ggx(n, v, -u, eta, a)
    crossings = transmission_fraction(HoV2, eta, fresnel) * transmission_fraction(-NoL, eta, fresnel)
    with np.errstate(divide="ignore", invalid="ignore"):
        near = np.where((cos_in > 0.0) & (lobe2 > 0.0),
                        tint * weight * crossings * lobe2 * (-NoL) / (eta * eta * cos_in), 0.0)
    near = near * glass_compensation(roughness, _dot(n, v), eta, tint, fresnel)
    inner_spread = transmission_inner_spread(_dot(n, v), -_dot(inner, n), eta, alpha, spread)
    central = transmission_exit_fraction(cos2, eta, roughness, 0.0, fresnel)
    spread_fraction = transmission_exit_fraction(cos2, eta, roughness, inner_spread, fresnel)
    with np.errstate(divide="ignore", invalid="ignore"):
        loss = np.where(central > 0.0, np.minimum(spread_fraction / central, 1.0), 1.0)
    through = tint * 0.5 * loss * (far + near)
    reflected, HoV_r = _reflect_ggx(exit_n, -inner, l, a)
    reflected = inside * reflection_tint * far_compensation * np.asarray(F_Dielectric(1.0 / eta, HoV_r),
                                                                          np.float64) * reflected
    reflected = np.where(fresnel, reflected, 0.0)
    return np.where(NoL < 0.0, through, reflected)


# --- rough glass's lost energy (Cycles' glass albedo tables) --------------------------------------

#: Side of the glass albedo tables (roughness, n.v, IOR), as Cycles' ggx_glass_E (16^3)
GLASS_SIZE = 16
GLASS_SHIPPED = Path(__file__).with_name("glass_albedo.npz")


def glass_z(eta):
    """The IOR axis of the glass tables: sqrt(|eta - 1| / (eta + 1)), F0^(1/4), for eta >= 1 (Cycles'
    microfacet_ggx_preserve_energy parametrises its tables so, covering every IOR, most finely 1-2)."""
    eta = np.asarray(eta, np.float64)
    return np.sqrt(np.abs(eta - 1.0) / (eta + 1.0))


def _vndf(alpha, wi, u1, u2):
    """GGX's visible normals for the view wi (..., 3) in the frame of normal z, at uniform (u1, u2)
    (Heitz 2018, "Sampling the GGX Distribution of Visible Normals", listing 1)."""
    vh = np.stack([alpha * wi[..., 0], alpha * wi[..., 1], wi[..., 2]], axis=-1)
    vh /= np.linalg.norm(vh, axis=-1, keepdims=True)
    lensq = vh[..., 0] ** 2 + vh[..., 1] ** 2
    # (the view along the normal: any tangent)
    inv = np.where(lensq > 0.0, 1.0 / np.sqrt(np.maximum(lensq, 1e-300)), 0.0)
    t1 = np.stack([np.where(lensq > 0.0, -vh[..., 1] * inv, 1.0), vh[..., 0] * inv, 0.0 * inv], axis=-1)
    t2 = np.cross(vh, t1)
    r = np.sqrt(u1)
    phi = 2.0 * np.pi * u2
    p1 = r * np.cos(phi)
    s = 0.5 * (1.0 + vh[..., 2])
    p2 = (1.0 - s) * np.sqrt(np.maximum(1.0 - p1 * p1, 0.0)) + s * r * np.sin(phi)
    p3 = np.sqrt(np.maximum(1.0 - p1 * p1 - p2 * p2, 0.0))
    nh = p1[..., None] * t1 + p2[..., None] * t2 + p3[..., None] * vh
    m = np.stack([alpha * nh[..., 0], alpha * nh[..., 1], np.maximum(nh[..., 2], 0.0)], axis=-1)
    return m / np.linalg.norm(m, axis=-1, keepdims=True)


def _lambda_ggx(cos_n, alpha):
    """Smith's Lambda for GGX at |cos_n| to the normal (Heitz 2014 eq. 72)."""
    c2 = np.maximum(cos_n * cos_n, 1e-300)
    return 0.5 * (np.sqrt(1.0 + alpha * alpha * np.maximum(1.0 / c2 - 1.0, 0.0)) - 1.0)


def glass_albedo_samples(roughness: float, mu, eta: float, strata: int = 64,
                         transmitted: bool = False) -> np.ndarray:
    """The single-scattering GGX glass lobe's albedo (reflection and transmission, the exact
    dielectric Fresnel at each microfacet, Smith's height-correlated masking) for light arriving at
    n.v = ``mu`` (an array) on glass of relative IOR ``eta``, perceptual ``roughness``: what Cycles'
    cycles_precompute integrates for ggx_glass_E (eval / pdf of bsdf_microfacet_ggx_sample: G2 / G1
    for the Fresnel-chosen side, 0 where the direction leaves on the wrong side). A deterministic
    quadrature: visible normals at the midpoints of a ``strata`` x ``strata`` grid. ``transmitted``:
    the transmitted part alone."""
    alpha = roughness * roughness
    mu = np.atleast_1d(np.asarray(mu, np.float64))
    u = (np.arange(strata) + 0.5) / strata
    u1, u2 = (x.ravel() for x in np.meshgrid(u, u, indexing="ij"))
    wi = np.stack([np.sqrt(1.0 - mu * mu), 0.0 * mu, mu], axis=-1)[:, None, :]  # (M, 1, 3)
    m = _vndf(alpha, np.broadcast_to(wi, (len(mu), len(u1), 3)), u1[None], u2[None])
    c = np.sum(wi * m, axis=-1)  # h.v > 0 for a visible normal
    F = F_Dielectric(eta, np.maximum(c, 0.0))
    g1 = 1.0 / (1.0 + _lambda_ggx(mu, alpha))[:, None]
    wr = 2.0 * c[..., None] * m - wi
    # the refracted direction (Snell's law at the microfacet; where F = 1 none)
    k = np.maximum(1.0 - (1.0 - c * c) / (eta * eta), 0.0)
    wt = -wi / eta + (c / eta - np.sqrt(k))[..., None] * m
    lam_i = _lambda_ggx(mu, alpha)[:, None]
    out = 0.0
    sides = ((wt, 1.0 - F, True),) if transmitted else ((wr, F, False), (wt, 1.0 - F, True))
    for w, share, below in sides:
        cos_o = w[..., 2]
        valid = (cos_o < 0.0) if below else (cos_o > 0.0)
        g2 = 1.0 / (1.0 + lam_i + _lambda_ggx(cos_o, alpha))
        out = out + np.where(valid, share * g2 / g1, 0.0)
    return out.mean(axis=1)


def compute_glass_albedo_tables(size: int = GLASS_SIZE, strata: int = 128,
                                 log=None) -> dict[str, np.ndarray]:
    """Cycles' four glass tables on its grid (roughness, n.v, z = i / (size - 1), each clamped as
    cycles_precompute clamps them: roughness and n.v >= 1e-4, z in [1e-4, 0.99], the IOR
    (1 + z^2) / (1 - z^2)): ``E`` and ``E_inv`` (size, size, size) indexed [z, mu, roughness], the
    albedo entering glass of that IOR and leaving it (1 / IOR); ``Eavg`` and ``Eavg_inv`` (size, size)
    indexed [z, roughness], 2 int mu E(mu) dmu (Gauss-Legendre over mu, 24 nodes); ``T`` and ``T_inv``
    as ``E`` and ``E_inv``, the transmitted part of the albedo alone."""
    grid = np.arange(size) / (size - 1)
    nodes, weights = np.polynomial.legendre.leggauss(24)
    mus = 0.5 * (nodes + 1.0)
    out = {"E": np.zeros((size, size, size)), "E_inv": np.zeros((size, size, size)),
           "Eavg": np.zeros((size, size)), "Eavg_inv": np.zeros((size, size)),
           "T": np.zeros((size, size, size)), "T_inv": np.zeros((size, size, size))}
    for iz, z in enumerate(np.clip(grid, 1e-4, 0.99)):
        ior = (1.0 + z * z) / (1.0 - z * z)
        for ir, r in enumerate(np.clip(grid, 1e-4, 1.0)):
            for suffix, eta in (("", ior), ("_inv", 1.0 / ior)):
                mu = np.clip(grid, 1e-4, 1.0)
                out["E" + suffix][iz, :, ir] = glass_albedo_samples(r, mu, eta, strata)
                out["T" + suffix][iz, :, ir] = glass_albedo_samples(r, mu, eta, strata, transmitted=True)
                e = glass_albedo_samples(r, mus, eta, strata)
                # 2 int_0^1 mu E dmu = sum w mu E (the nodes on [-1, 1] halved onto [0, 1])
                out["Eavg" + suffix][iz, ir] = np.sum(weights * mus * e)
        if log is not None:
            log(f"IOR node {iz + 1}/{size} (IOR {ior:.4g})")
    return {name: np.clip(t, 0.0, 1.0).astype(np.float32) for name, t in out.items()}


def write_glass_albedo_tables(path: Path, strata: int = 128, log=None) -> tuple[str, ...]:
    """compute_glass_albedo_tables written to ``path`` (a .npz, replaced whole once complete); the
    tables' names."""
    tables = compute_glass_albedo_tables(strata=strata, log=log)
    partial = path.with_name(f".{path.stem}.partial.npz")
    np.savez_compressed(partial, strata=np.int64(strata), **tables)
    partial.replace(path)
    return tuple(tables)


@lru_cache(maxsize=1)
def glass_albedo_tables() -> dict[str, np.ndarray]:
    """The shipped glass tables (scripts/glass_albedo_table.py), computed where the file is missing."""
    try:
        with np.load(GLASS_SHIPPED, allow_pickle=False) as data:
            return {name: data[name] for name in data.files}
    except (OSError, ValueError):
        return compute_glass_albedo_tables()


def _lerp_grid(x, size):
    """Index and fraction of x in [0, 1] on the grid i / (size - 1) (Cycles' lookup_table_read)."""
    t = np.clip(np.asarray(x, np.float64), 0.0, 1.0) * (size - 1)
    i0 = np.minimum(np.floor(t).astype(int), size - 2)
    return i0, t - i0


def _glass_lookup(name, roughness, mu, eta):
    """Table ``name`` (E or T; its _inv table for eta < 1) read trilinearly at (roughness, mu, eta)
    as Cycles' lookup_table_read_3D reads its glass tables."""
    tables = glass_albedo_tables()
    roughness, mu, eta = np.broadcast_arrays(*(np.asarray(x, np.float64) for x in (roughness, mu, eta)))
    inv = eta < 1.0
    z = glass_z(np.where(inv, 1.0 / eta, eta))
    size = tables["E"].shape[0]
    (r0, fr), (m0, fm), (z0, fz) = (_lerp_grid(x, size) for x in (roughness, mu, z))
    out = 0.0
    for dz, dm, dr in np.ndindex(2, 2, 2):
        w = (fz if dz else 1.0 - fz) * (fm if dm else 1.0 - fm) * (fr if dr else 1.0 - fr)
        at = (z0 + dz, m0 + dm, r0 + dr)
        out = out + w * np.where(inv, tables[name + "_inv"][at], tables[name][at])
    return out


def glass_albedo(roughness, mu, eta):
    """(E, Eavg): glsl/transmission.glsl's glass_albedo, the tables read trilinearly (bilinearly for
    Eavg) as Cycles' microfacet_ggx_preserve_energy reads them: eta < 1 (leaving) from the inverse
    tables at 1 / eta."""
    tables = glass_albedo_tables()
    roughness, mu, eta = np.broadcast_arrays(*(np.asarray(x, np.float64) for x in (roughness, mu, eta)))
    inv = eta < 1.0
    size = tables["E"].shape[0]
    (r0, fr), (z0, fz) = (_lerp_grid(x, size) for x in (roughness, glass_z(np.where(inv, 1.0 / eta, eta))))
    Eavg = 0.0
    for dz, dr in np.ndindex(2, 2):
        w = (fz if dz else 1.0 - fz) * (fr if dr else 1.0 - fr)
        at = (z0 + dz, r0 + dr)
        Eavg = Eavg + w * np.where(inv, tables["Eavg_inv"][at], tables["Eavg"][at])
    return _glass_lookup("E", roughness, mu, eta), Eavg


def glass_transmitted(roughness, mu, eta):
    """glsl/transmission.glsl's glass_transmitted: T / E, the transmitted share of what the compensated
    rough glass closure scatters for light arriving at n.v = mu."""
    return _glass_lookup("T", roughness, mu, eta) / np.maximum(_glass_lookup("E", roughness, mu, eta), 1e-3)


def glass_compensation(roughness, mu, eta, tint=1.0, fresnel=True):
    """glsl/transmission.glsl's glass_compensation: what Cycles' microfacet_ggx_preserve_energy
    multiplies a Multiscatter GGX glass closure by, 1 + Fms (1 - E) / E (its energy_scale 1 / E times
    the darkening), Fms = Fss Eavg / (1 - Fss (1 - Eavg)) (Kulla & Conty 2017) with Fss the
    transmission tint (bsdf_microfacet_setup_fresnel_generalized_schlick); per channel where ``tint``
    is (..., 3); 1 without Fresnel (the Refraction BSDF)."""
    E, Eavg = glass_albedo(roughness, mu, eta)
    E = np.maximum(E, 1e-3)
    # a tint above 1 (a Glass BSDF's Color) is no average Fresnel: at 1 the darkening is none, and the
    # formula's denominator stays positive
    Fss = np.clip(np.asarray(tint, np.float64), 0.0, 1.0)
    if Fss.ndim:
        E, Eavg = E[..., None], Eavg[..., None]
    Fms = Fss * Eavg / (1.0 - Fss * (1.0 - Eavg))
    return np.where(fresnel, 1.0 + Fms * (1.0 - E) / E, 1.0)


# --- the first crossing's rays through a curved far face -------------------------------------------

#: glsl/transmission.glsl's EXIT_RAYS
EXIT_RAYS = 8


def transmission_lambda(cos_n, alpha):
    """transmission_lambda: Smith's Lambda for isotropic GGX (Heitz 2014 eq. 72)."""
    return _lambda_ggx(np.asarray(cos_n, np.float64), alpha)


def transmission_exit_normal(sin_v, cos_v, alpha, k):
    """transmission_exit_normal: visible normal ``k`` of EXIT_RAYS (Heitz 2018, listing 1, the view in
    the xz plane) in the frame (x the view along the surface, y, n), rows (..., 3)."""
    sin_v, cos_v, alpha = (np.asarray(x, np.float64) for x in (sin_v, cos_v, alpha))
    vh = np.stack([alpha * sin_v, 0.0 * sin_v, cos_v], axis=-1)
    vh = vh / np.linalg.norm(vh, axis=-1, keepdims=True)
    r = np.sqrt((k // 4 + 0.5) * 0.5)
    phi = 2.0 * np.pi * (k % 4 + 0.5) * 0.25
    a = r * np.cos(phi)
    s = 0.5 * (1.0 + vh[..., 2])
    b = (1.0 - s) * np.sqrt(max(1.0 - a * a, 0.0)) + s * r * np.sin(phi)
    c = np.sqrt(np.maximum(1.0 - a * a - b * b, 0.0))
    nh = np.stack([c * vh[..., 0] - b * vh[..., 2], a + 0.0 * b, b * vh[..., 0] + c * vh[..., 2]], axis=-1)
    m = np.stack([alpha * nh[..., 0], alpha * nh[..., 1], np.maximum(nh[..., 2], 0.0)], axis=-1)
    return m / np.linalg.norm(m, axis=-1, keepdims=True)


def transmission_exit_ray(n, v, eta, alpha, k, fresnel=True):
    """transmission_exit_ray: (direction inside, weight) of ray ``k`` of the first crossing into glass of
    relative IOR eta, rows (..., 3)."""
    n, v = np.asarray(n, np.float64), np.asarray(v, np.float64)
    eta, alpha = np.asarray(eta, np.float64), np.asarray(alpha, np.float64)
    NoV = _dot(n, v)
    x = v - n * NoV[..., None]
    len2 = _dot(x, x)
    other = np.where((np.abs(n[..., 2]) < 0.9)[..., None], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    any_x = np.cross(n, other)
    any_x = any_x / np.linalg.norm(any_x, axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.where((len2 > 1e-12)[..., None], x / np.sqrt(np.maximum(len2, 1e-300))[..., None], any_x)
    ml = transmission_exit_normal(np.sqrt(np.maximum(1.0 - NoV * NoV, 0.0)), NoV, alpha, k)
    m = x * ml[..., :1] + np.cross(n, x) * ml[..., 1:2] + n * ml[..., 2:]
    d = transmission_direction(-v, m, eta)
    cos_d = -_dot(d, n)
    lambda_v = transmission_lambda(NoV, alpha)
    weight = transmission_fraction(_dot(v, m), eta, fresnel) * (1.0 + lambda_v) / (
        1.0 + lambda_v + transmission_lambda(cos_d, alpha))
    return d, np.where((_dot(d, d) > 0.0) & (cos_d > 0.0), weight, 0.0)


def transmission_exit_quadrature(dirs, points, normals, weights, exit_p, l, eta, alpha, light_position=None,
                                 fresnel=True):
    """transmission_exit_quadrature: the rays' far lobes towards the light (``light_position`` (..., 3)
    for a light with a position, else the sun's direction ``l``), averaged; ``dirs``, ``points``,
    ``normals`` (EXIT_RAYS, ..., 3) and ``weights`` (EXIT_RAYS, ...) as transmission_exit_rays leaves
    them."""
    total = 0.0
    eta = np.asarray(eta, np.float64)
    for d, q, n2, w in zip(dirs, points, normals, weights):
        lk, scale = np.asarray(l, np.float64), 1.0
        if light_position is not None:
            to_light = light_position - q
            d2 = np.maximum(_dot(to_light, to_light), 1e-4)
            lk = to_light / np.sqrt(d2)[..., None]
            to_exit = light_position - exit_p
            scale = np.maximum(_dot(to_exit, to_exit), 1e-4) / d2
        lobe, HoV = transmission_ggx(n2, -d, lk, 1.0 / eta, alpha)
        value = w * scale * transmission_fraction(HoV, 1.0 / eta, fresnel) * lobe
        total = total + np.where((w > 0.0) & (lobe > 0.0), value, 0.0)
    return total / EXIT_RAYS
