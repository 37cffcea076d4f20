"""The Principled BSDF's Thin Film (glsl/thin_film.glsl's twin): the iridescent Fresnel of a film of
thickness d (nm) and IOR n2 over the dielectric or metallic base, as the Cycles of the Blender that
read the material evaluates it (kernel/closure/bsdf_util.h's fresnel_iridescence, bsdf_microfacet.h's
microfacet_fresnel), after Belcour & Barla 2017, "A Practical Extension to Microfacet Theory for the
Modeling of Varying Iridescence": the Airy series of the film's multiple reflections, summed in closed
form for its mean (the m = 0 term) and over the path differences m = 1..3 through the Fourier
transform of the colour matching functions (``sensitivity``), per polarisation, averaged.

Cycles' rules (``snapshot.THIN_FILM_RULES``) differ by version, in three places alone (their kernels
read side by side; the rest, the phases of the reflections, the 0.1 nm cutoff, the dielectric's F0
scaling and the albedo estimate, agree):

- the colour of the interference terms: Blender 5.0 reads the CIE 1931 functions' transform from a
  table (``sensitivity_table``), 4.2 and 4.5 evaluate Belcour & Barla's Gaussian fit of it in XYZ
  and turn the sum into RGB through the white point (``gaussian_sensitivity``);
- the metal: 5.0 puts the film over it too (its IOR from the F82 model: ``iridescence_metal``), 4.2
  and 4.5 leave it bare;
- the film's IOR blends to the air's below 1 nm (5.0) or 30 nm (4.2, 4.5): ``BLEND_NM``.

Pure numpy (no ``bpy``, no ``gpu``): arrays broadcast; cosines, thicknesses and IORs may be per point.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from ..scene.colour import XYZ_TO_RGB, XYZ_TO_RGB_4
from ..scene.snapshot import THIN_FILM_RULES

#: The sensitivity table's size and the path difference it covers (Cycles' THIN_FILM_TABLE_SIZE,
#: 0 .. 60 um).
TABLE_SIZE = 512
TABLE_END_NM = 60000.0
#: A film of this thickness (nm) or less is no film (Cycles' THINFILM_THICKNESS_CUTOFF).
THICKNESS_CUTOFF = 0.1
#: Below this thickness (nm) the film's IOR blends towards the air's, where the Airy summation no
#: longer applies, per rule of ``THIN_FILM_RULES`` (Cycles 4.2 and 4.5: 30 nm; 5.0: 1 nm)
BLEND_NM = {"CYCLES_4": 30.0, "CYCLES_5": 1.0}
SHIPPED = Path(__file__).with_name("thin_film_cmf.npz")


@lru_cache(maxsize=1)
def cmf_table() -> np.ndarray:
    """(512, 6) float64: the CIE 1931 XYZ functions' Fourier transform (Re X, Re Y, Re Z, Im X, Im Y,
    Im Z) at x = 2 pi D / 60 um = i / 511 (scripts/thin_film_table.py)."""
    return np.load(SHIPPED)["cmf"].astype(np.float64)


def sensitivity_table(xyz_to_rgb) -> np.ndarray:
    """(512, 2, 3) float32: the transform in the scene linear RGB of ``xyz_to_rgb`` (rows), real then
    imaginary part, normalised so that its first (DC) entry is 1 per channel (Cycles 5.0's
    ShaderManager::compute_thin_film_table: the colour matching functions of unit area)."""
    m = np.asarray(xyz_to_rgb, np.float64)
    table = cmf_table()
    re = table[:, :3] @ m.T
    im = table[:, 3:] @ m.T
    norm = 1.0 / re[0]
    return np.stack([re * norm, im * norm], axis=1).astype(np.float32)


#: Belcour & Barla's fit of the CIE 1931 XYZ functions' transform (their supplemental code, as Cycles
#: 4.2 and 4.5's iridescence_lookup_sensitivity holds it): per XYZ channel a Gaussian of amplitude
#: AMP sqrt(2 pi VAR) at frequency POS (per metre of path difference, in radians over 2 pi), X with a
#: second one (X2_*), all over NORM (so that each is about 1 at a path difference of 0)
GAUSSIAN_AMP = (5.4856e-13, 4.4201e-13, 5.2481e-13)
GAUSSIAN_POS = (1.6810e+06, 1.7953e+06, 2.2084e+06)
GAUSSIAN_VAR = (4.3278e+09, 9.3046e+09, 6.6121e+09)
GAUSSIAN_X2 = (1.64408e-8, 2.2399e+06, 4.5282e+09)  # X's second Gaussian: its weight, POS and VAR
GAUSSIAN_NORM = 1.0685e-7


def gaussian_rgb(xyz_to_rgb) -> np.ndarray:
    """(3, 3): Cycles 4.2 and 4.5's XYZ -> RGB for the film's sum: the sum (in XYZ of illuminant E) times
    the working space's white point in XYZ, then ``xyz_to_rgb``: the matrix xyz_to_rgb diag(white)
    with white = xyz_to_rgb^-1 (1, 1, 1) (Cycles' white_xyz), which maps XYZ (1, 1, 1) to RGB white."""
    m = np.asarray(xyz_to_rgb, np.float64)
    return m * np.linalg.solve(m, np.ones(3))[None, :]


def gaussian_sensitivity(opd, rgb_of_xyz) -> tuple[np.ndarray, np.ndarray]:
    """(re, im) (..., 3): Belcour & Barla's Gaussian fit of the colour matching functions' transform
    at path difference ``opd`` (nm), in RGB by ``rgb_of_xyz`` (``gaussian_rgb``), as Cycles 4.2 and
    4.5 evaluate it (no table: iridescence_lookup_sensitivity); the imaginary part is the fit's
    sine, so that re cos(m phi) + im sin(m phi) is Cycles' cos(POS phase + m phi) term."""
    phase = 2.0 * np.pi * 1e-9 * np.asarray(opd, np.float64)[..., None]  # radians per unit frequency
    pos, var = np.array(GAUSSIAN_POS), np.array(GAUSSIAN_VAR)
    amp = np.array(GAUSSIAN_AMP) * np.sqrt(2.0 * np.pi * var) * np.exp(-phase * phase * var)
    re, im = amp * np.cos(pos * phase), -amp * np.sin(pos * phase)
    weight, pos2, var2 = GAUSSIAN_X2
    amp2 = weight * np.exp(-phase[..., 0] * phase[..., 0] * var2)
    re[..., 0] += amp2 * np.cos(pos2 * phase[..., 0])
    im[..., 0] -= amp2 * np.sin(pos2 * phase[..., 0])
    m = np.asarray(rgb_of_xyz, np.float64)
    return (re @ m.T) / GAUSSIAN_NORM, (im @ m.T) / GAUSSIAN_NORM


def sensitivity(opd, table):
    """(re, im) (..., 3) of the sensitivity ``table`` at path difference ``opd`` (nm): Cycles 5.0's
    table (``sensitivity_table``) linearly interpolated as its lookup_table_read (x clamped to [0,
    1]), or, a (3, 3) matrix, Cycles 4.2 and 4.5's Gaussian fit in RGB by it (``gaussian_sensitivity``)."""
    if np.shape(table) == (3, 3):
        return gaussian_sensitivity(opd, table)
    x = np.clip(2.0 * np.pi * np.asarray(opd, np.float64) / TABLE_END_NM, 0.0, 1.0) * (TABLE_SIZE - 1)
    i = np.minimum(x.astype(np.int64), TABLE_SIZE - 1)
    j = np.minimum(i + 1, TABLE_SIZE - 1)
    t = (x - i)[..., None, None]
    rows = np.asarray(table, np.float64)
    value = (1.0 - t) * rows[i] + t * rows[j]
    return value[..., 0, :], value[..., 1, :]


def optical_cosine_sq(n, cos_i):
    """q^2 = n^2 cos^2(theta) of a layer of IOR ``n`` under the view at cosine ``cos_i`` from the air
    (Snell's invariant: n^2 - sin^2(theta_i) = (n - 1)(n + 1) + cos_i^2, for an IOR below 1/2 n^2 -
    (1 - cos_i)(1 + cos_i)); at most 0: total internal reflection into it. thin_film.glsl's
    optical_cosine_sq (its header says why optical cosines)."""
    n, cos_i = np.asarray(n, np.float64), np.asarray(cos_i, np.float64)
    return np.where(n < 0.5, n * n - (1.0 - cos_i) * (1.0 + cos_i), (n - 1.0) * (n + 1.0) + cos_i * cos_i)


def interface_polarized(qa, qb, na2, nb2):
    """(R_s, R_p, T_s, T_p, sign_s, sign_p): the interface from a layer of IOR^2 ``na2`` to one of
    ``nb2`` at optical cosines qa >= 0, qb > 0: the reflectances of the amplitudes r_s = (qa - qb) /
    (qa + qb), r_p = (nb2 qa - na2 qb) / (nb2 qa + na2 qb) (Cycles' fresnel_dielectric_polarized's,
    written with n cos), their transmittances 1 - R = 4 a b / (a + b)^2 and the amplitudes' signs
    (the phase shift 0 or pi). thin_film.glsl's interface_polarized."""
    qa, qb = np.asarray(qa, np.float64), np.asarray(qb, np.float64)
    out = []
    for a, b in ((qa, qb), (np.asarray(nb2, np.float64) * qa, np.asarray(na2, np.float64) * qb)):
        with np.errstate(divide="ignore", invalid="ignore"):  # a + b = 0: total internal reflection
            inv = 1.0 / (a + b)  # (the callers replace those rows)
            out.append(((a - b) * inv, 4.0 * (a * inv) * (b * inv)))
    (r_s, t_s), (r_p, t_p) = out
    return r_s * r_s, r_p * r_p, t_s, t_p, np.where(r_s >= 0.0, 1.0, -1.0), np.where(r_p >= 0.0, 1.0, -1.0)


def f82(cos_i, f0, b):
    """Cycles' fresnel_f82: Schlick's curve less b cos (1 - cos)^6, within [0, 1]."""
    cos_i = np.asarray(cos_i, np.float64)
    s = np.clip(1.0 - cos_i, 0.0, 1.0)
    s5 = s ** 5
    return np.clip(f0 + (1.0 - f0) * s5 - b * cos_i * s5 * s, 0.0, 1.0)


def f82_b(f0, f82_value):
    """Cycles' fresnel_f82_B: b of the F82 model whose value at cos = 1/7 is ``f82_value``."""
    f = 6.0 / 7.0
    f5 = f ** 5
    return (7.0 / (f5 * f)) * (f0 + (1.0 - f0) * f5 - f82_value)


def metal_ior(f0, b):
    """(n, k, g): a metal's complex IOR from its F0 and F82-tint b (Gulbrandsen 2014, "Artist
    Friendly Metallic Fresnel", with F0 as the reflectivity r and the F82 value g as the edge tint),
    as Cycles' microfacet_fresnel reads the Principled BSDF's metal under a film; F0 at most 0.999."""
    f0 = np.asarray(f0, np.float64)
    r = np.minimum(f0, 0.999)
    g = f82(1.0 / 7.0, f0, b)
    sqrt_r = np.sqrt(r)
    n = (1.0 + sqrt_r) / (1.0 - sqrt_r) * (1.0 - g) + (1.0 - r) / (1.0 + r) * g
    k = np.sqrt(np.maximum((r * (n + 1.0) ** 2 - (n - 1.0) ** 2) / (1.0 - r), 0.0))
    return n, k, g


def conductor_polarized(cos_i, eta1, sin2_view, n, k, f82_value):
    """(R, phase_s, phase_p): a metal of IOR n + ik under a medium of IOR ``eta1`` at cosine ``cos_i``
    (the view's sin^2 ``sin2_view`` = eta1^2 (1 - cos_i^2) by Snell's invariant; Cycles'
    fresnel_conductor_polarized, after Born & Wolf 14.4.1): its reflectance by the F82 model with F0
    recomputed against eta1 (both polarisations alike), and the complex phasors exp(i phi_s),
    exp(i phi_p) of the exact Fresnel amplitudes (re, im)."""
    cos_i = np.asarray(cos_i, np.float64)[..., None]
    eta1 = np.asarray(eta1, np.float64)[..., None]
    t1 = n * n - k * k - np.asarray(sin2_view, np.float64)[..., None]
    t2 = np.sqrt(t1 * t1 + (2.0 * n * k) ** 2)
    u2 = np.maximum(0.5 * (t2 + t1), 0.0)
    v2 = np.maximum(0.5 * (t2 - t1), 0.0)
    u, v = np.sqrt(u2), np.sqrt(v2)
    nr = n / eta1
    kr2 = (k / eta1) ** 2
    F0 = ((nr - 1.0) ** 2 + kr2) / ((nr + 1.0) ** 2 + kr2)
    R = f82(cos_i, F0, f82_b(F0, f82_value))

    def unit(re, im):
        mag = np.sqrt(re * re + im * im)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(mag == 0.0, 1.0, re / mag), np.where(mag == 0.0, 0.0, im / mag)

    phase_s = unit(-u2 - v2 + (eta1 * cos_i) ** 2, -2.0 * eta1 * cos_i * v)
    phase_p = unit(((n * n + k * k) * cos_i) ** 2 - eta1 * eta1 * (u2 + v2),
                   2.0 * eta1 * cos_i * (2.0 * n * k * u - (n * n - k * k) * v))
    return R, phase_s, phase_p


def airy(R12, T12, R23, T23, opd, phasor, table):
    """The film's reflectance (..., 3) for one polarisation (Belcour & Barla 2017, eq. 10; Cycles'
    iridescence_airy_summation): the series' mean R12 + T121^2 R23 / (1 - R12 R23) and its terms
    m = 1..3, each C_m times the sensitivity at m D turned by the reflections' phasor^m; with the
    transmittances T12 = T121 and T23 apart (thin_film.glsl's thin_film_airy: 1 - R12 R23 = T12 +
    R12 T23, C_0 = Rs - T121 = -T12 T23 / (1 - R12 R23))."""
    R12 = np.asarray(R12, np.float64)[..., None]
    T12 = np.asarray(T12, np.float64)[..., None]
    R23, T23 = np.asarray(R23, np.float64), np.asarray(T23, np.float64)
    if R23.ndim < R12.ndim:  # a dielectric's: one for every channel
        R23, T23 = R23[..., None], T23[..., None]
    r123 = np.sqrt(R12 * R23)
    # 0 only where both interfaces reflect all (a view at 90 degrees onto a base reflecting all):
    # 1e-30 keeps Rs and C_0 at 0 there (their numerators are 0)
    inv = 1.0 / np.maximum(T12 + R12 * T23, 1e-30)
    Rs = T12 * T12 * R23 * inv
    R = Rs + R12
    Cm = -T12 * T23 * inv
    re, im = (np.broadcast_to(np.asarray(c, np.float64), R.shape) for c in phasor)
    acc_re, acc_im = re, im
    for m in range(1, 4):
        Cm = Cm * r123
        s_re, s_im = sensitivity(m * np.asarray(opd, np.float64), table)
        R = R + Cm * 2.0 * (acc_re * s_re + acc_im * s_im)
        acc_re, acc_im = acc_re * re - acc_im * im, acc_re * im + acc_im * re
    return R


def _film_ior(thickness, film_ior, blend=BLEND_NM["CYCLES_5"]):
    """The film's IOR, blended towards the air's (1) by smoothstep(0, blend, d) below ``blend`` nm."""
    d = np.asarray(thickness, np.float64)
    t = np.clip(d / blend, 0.0, 1.0)
    return np.where(d < blend, 1.0 + (np.asarray(film_ior, np.float64) - 1.0) * t * t * (3.0 - 2.0 * t),
                    film_ior)


def iridescence_dielectric(cos_i, thickness, film_ior, eta, table, blend=BLEND_NM["CYCLES_5"]):
    """(..., 3): Cycles' fresnel_iridescence over a dielectric of IOR ``eta`` (air above)."""
    n2 = _film_ior(thickness, film_ior, blend)
    cos_i = np.abs(np.asarray(cos_i, np.float64))
    eta = np.asarray(eta, np.float64)
    q2sq, q3sq = optical_cosine_sq(n2, cos_i), optical_cosine_sq(eta, cos_i)
    tir = (q2sq <= 0.0) | (q3sq <= 0.0)  # total internal reflection at either interface
    q2, q3 = np.sqrt(np.where(tir, 1.0, q2sq)), np.sqrt(np.where(tir, 1.0, q3sq))
    R12s, R12p, T12s, T12p, ph12s, ph12p = interface_polarized(cos_i, q2, 1.0, n2 * n2)
    R23s, R23p, T23s, T23p, ph23s, ph23p = interface_polarized(q2, q3, n2 * n2, eta * eta)
    opd = 2.0 * np.asarray(thickness, np.float64) * q2  # 2 n2 d cos(theta_2)
    Rs = airy(R12s, T12s, R23s, T23s, opd, ((ph23s * -ph12s)[..., None], 0.0), table)
    Rp = airy(R12p, T12p, R23p, T23p, opd, ((ph23p * -ph12p)[..., None], 0.0), table)
    return np.where(tir[..., None], 1.0, np.clip(0.5 * (Rs + Rp), 0.0, 1.0))


def iridescence_metal(cos_i, thickness, film_ior, f0, b, table, blend=BLEND_NM["CYCLES_5"]):
    """(..., 3): Cycles' fresnel_iridescence over the Principled BSDF's metal of F0 ``f0`` and
    F82-tint b (its IOR from ``metal_ior``)."""
    n, k, g = metal_ior(f0, b)
    n2 = _film_ior(thickness, film_ior, blend)
    cos_i = np.abs(np.asarray(cos_i, np.float64))
    q2sq = optical_cosine_sq(n2, cos_i)
    tir = q2sq <= 0.0  # total internal reflection into the film
    q2 = np.sqrt(np.where(tir, 1.0, q2sq))
    R12s, R12p, T12s, T12p, ph12s, ph12p = interface_polarized(cos_i, q2, 1.0, n2 * n2)
    sin2_view = (1.0 - cos_i) * (1.0 + cos_i)
    R23, (ps_re, ps_im), (pp_re, pp_im) = conductor_polarized(q2 / n2, n2, sin2_view, n, k, g)
    opd = 2.0 * np.asarray(thickness, np.float64) * q2  # 2 n2 d cos(theta_2)
    Rs = airy(R12s, T12s, R23, 1.0 - R23, opd, (ps_re * -ph12s[..., None], ps_im * -ph12s[..., None]), table)
    Rp = airy(R12p, T12p, R23, 1.0 - R23, opd, (pp_re * -ph12p[..., None], pp_im * -ph12p[..., None]), table)
    return np.where(tir[..., None], 1.0, np.clip(0.5 * (Rs + Rp), 0.0, 1.0))


def dielectric_fresnel(cos_i, thickness, film_ior, eta, f0_tinted, table, blend=BLEND_NM["CYCLES_5"]):
    """The Principled BSDF's dielectric Fresnel under a film (Cycles' microfacet_fresnel,
    GENERALIZED_SCHLICK with a film): the iridescent Fresnel, each channel scaled towards the tinted
    F0 over the substrate's own F0 as it nears that F0 from 1 (no scaling where the substrate's
    F0 is below 1e-5 or the film reflects everything)."""
    F = iridescence_dielectric(cos_i, thickness, film_ior, eta, table, blend)
    eta = np.asarray(eta, np.float64)
    F0 = ((eta - 1.0) / (eta + 1.0)) ** 2
    scaled = (F0 > 1e-5)[..., None] & ~np.all(F == 1.0, axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.clip((F - 1.0) / (F0[..., None] - 1.0), 0.0, 1.0)
        factor = np.asarray(f0_tinted, np.float64) / F0[..., None]
        out = F * (1.0 + (factor - 1.0) * s)
    return np.where(scaled, out, F)


# --- the independent reference: the exact film over wavelengths ------------------------------------

def airy_spectral(lam_nm, cos_i, thickness, film_ior, eta3):
    """(..., L) the exact reflectance of a film of thickness d and IOR n2 between air and a substrate
    of (complex) IOR eta3 at each wavelength (Airy's summation of the film's reflections in closed
    form: r = (r12 + r23 e^{i delta}) / (1 + r12 r23 e^{i delta}), delta = 4 pi n2 d cos theta2 / lambda,
    per polarisation, unpolarised mean); no dispersion. For tests: the classic formula, independent
    of the Fourier-space summation above."""
    cos1 = np.asarray(cos_i, np.float64)[..., None]
    n2 = complex(film_ior)
    n3 = np.asarray(eta3, np.complex128)
    sin1 = np.sqrt(1.0 - cos1 * cos1)
    cos2 = np.sqrt(1.0 - (sin1 / n2) ** 2 + 0j)
    cos3 = np.sqrt(1.0 - (sin1 / n3) ** 2 + 0j)
    r12s = (cos1 - n2 * cos2) / (cos1 + n2 * cos2)
    r12p = (n2 * cos1 - cos2) / (n2 * cos1 + cos2)
    r23s = (n2 * cos2 - n3 * cos3) / (n2 * cos2 + n3 * cos3)
    r23p = (n3 * cos2 - n2 * cos3) / (n3 * cos2 + n2 * cos3)
    phase = np.exp(2j * (2.0 * np.pi / np.asarray(lam_nm, np.float64)) * n2 * thickness * cos2)
    rs = (r12s + r23s * phase) / (1.0 + r12s * r23s * phase)
    rp = (r12p + r23p * phase) / (1.0 + r12p * r23p * phase)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


# --- the Principled set's film (principled.glsl's hooks, thin_film.glsl's thin_film_at) -----------

@lru_cache(maxsize=None)
def engine_sensitivity(rule: str = "CYCLES_5"):
    """The sensitivity the engine draws under ``rule`` (``THIN_FILM_RULES``): Cycles 5.0's table in
    5.0's scene linear Rec. 709 (gpu_library.thin_film_table), or 4.2 and 4.5's Gaussian fit turned
    into 4.x's scene linear Rec. 709 (thin_film.glsl's SL_THIN_FILM_CYCLES_4, its matrix
    programs.Features' SL_THIN_FILM_RGB)."""
    if rule not in THIN_FILM_RULES:
        raise ValueError(f"unknown thin film rule {rule!r}; expected one of {THIN_FILM_RULES}")
    return gaussian_rgb(XYZ_TO_RGB_4) if rule == "CYCLES_4" else sensitivity_table(XYZ_TO_RGB)


def film_of(material) -> np.ndarray:
    """(..., 4): MaterialData's thin_film of a material (thickness at least 0, IOR at least 1e-5, as
    thin_film_at floors them), then the index of its rule in THIN_FILM_RULES (the GPU's define) and 0."""
    thickness = np.maximum(np.asarray(getattr(material, "thin_film_thickness", 0.0), np.float64), 0.0)
    ior = np.maximum(np.asarray(getattr(material, "thin_film_ior", 1.33), np.float64), 1e-5)
    rule = np.asarray(float(THIN_FILM_RULES.index(getattr(material, "thin_film_rule", "CYCLES_5"))))
    return np.stack(np.broadcast_arrays(thickness, ior, rule, np.zeros(())), axis=-1)


def _rule_of(film) -> str:
    """The rule of MaterialData's ``film`` (``film_of``: one per material, as one program has one define)."""
    index = np.unique(np.asarray(film)[..., 2])
    if len(index) != 1:
        raise ValueError(f"one thin film rule per evaluation, got indices {index}")
    return THIN_FILM_RULES[int(index[0])]


def has_film(film) -> np.ndarray:
    """Where the film is on (thicker than Cycles' THINFILM_THICKNESS_CUTOFF)."""
    return np.asarray(film)[..., 0] > THICKNESS_CUTOFF


def dielectric(film, eta, f0_tinted, cos_i):
    """``dielectric_fresnel`` for MaterialData's ``film`` (thin_film.glsl's F_ThinFilmTinted)."""
    film = np.asarray(film, np.float64)
    rule = _rule_of(film)
    return dielectric_fresnel(cos_i, film[..., 0], film[..., 1], eta, f0_tinted, engine_sensitivity(rule),
                              BLEND_NM[rule])


def metal(film, f0, b, cos_i):
    """``iridescence_metal`` for MaterialData's ``film`` (thin_film.glsl's F_ThinFilmMetal)."""
    film = np.asarray(film, np.float64)
    rule = _rule_of(film)
    return iridescence_metal(cos_i, film[..., 0], film[..., 1], f0, b, engine_sensitivity(rule),
                             BLEND_NM[rule])


def on_metal(film) -> np.ndarray:
    """thin_film.glsl's thin_film_on_metal: a film the material's rule puts over the metal too (5.0's)."""
    return has_film(film) & (np.asarray(film)[..., 2] == THIN_FILM_RULES.index("CYCLES_5"))
