"""The numpy twin of ``glsl/``: the same terms, function for function, vectorised over arrays.

Each function mirrors the GLSL function of the same name (inputs are arrays of shape (..., 3)
for vectors and (...) for scalars; evaluated in float64). Tests hold the GPU to this twin, and
the twin itself to closed forms and independent renderers. Pure numpy: no ``bpy``, no ``gpu``.
"""

from __future__ import annotations

import numpy as np

from .snapshot import Light, MaterialParams, Terms

DEFAULT_TERMS = Terms()
PI = np.pi
INV_PI = 1.0 / np.pi
MIN_PERCEPTUAL_ROUGHNESS = 0.045
MIN_COS = 1e-4
MIN_DIST2 = 1e-4


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
    """Exact unpolarised dielectric Fresnel (Walter et al. 2007, eq. 22); 1 under total reflection."""
    c = np.abs(np.asarray(cos_i, np.float64))
    g2 = np.asarray(eta, np.float64) ** 2 - 1.0 + c * c
    g = np.sqrt(np.maximum(g2, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (g - c) / (g + c)
        b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
        f = 0.5 * a * a * (1.0 + b * b)
    return np.where(g2 <= 0.0, 1.0, f)


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


# --- lights (glsl/lights.glsl) -----------------------------------------------------------------

def E_Point(light: Light, p):
    d = np.asarray(light.position) - p
    d2 = _dot(d, d)
    l = d / np.sqrt(np.maximum(d2, 1e-30))[..., None]  # unit, or 0 for a light exactly at p
    return np.asarray(light.intensity) / np.maximum(d2, MIN_DIST2)[..., None], l


def E_Spot(light: Light, p):
    E, l = E_Point(light, p)
    cos_theta = _dot(-l, np.asarray(light.direction))
    t = saturate((cos_theta - light.spot_cos_half) * light.spot_smooth)
    return E * (t * t * (3.0 - 2.0 * t))[..., None], l


def E_Sun(light: Light, p):
    shape = np.shape(p)
    l = np.broadcast_to(-np.asarray(light.direction, np.float64), shape)
    return np.broadcast_to(np.asarray(light.intensity, np.float64), shape), l


def E_Area(light: Light, p):
    E, l = E_Point(light, p)
    return E * np.maximum(_dot(-l, np.asarray(light.direction)), 0.0)[..., None], l


def light_irradiance(light: Light, p):
    """(E, l): irradiance on a surface facing the light (W/m^2, rgb) and the unit light direction."""
    return {"POINT": E_Point, "SPOT": E_Spot, "SUN": E_Sun, "AREA": E_Area}[light.kind](light, p)


# --- models (glsl/surface.glsl, pbr_terms.glsl, multiscatter.glsl, model_*.glsl) ----------------

class Surface:
    """The twin of ``struct Surface``: arrays of points, normals, view directions + a material.

    The material's numbers may be scalars or per-point arrays ((N,) for scalars, (N, 3) for
    colours), so sweeps can vary the material from point to point.
    """

    def __init__(self, p, n, v, material: MaterialParams):
        f64 = np.float64
        self.p = np.asarray(p, f64)
        self.n = np.asarray(n, f64)
        self.v = np.asarray(v, f64)
        self.NoV = np.maximum(_dot(self.n, self.v), MIN_COS)
        self.base_color = np.asarray(material.base_color, f64)
        self.diffuse_color = np.asarray(material.diffuse_color, f64)
        self.specular_color = np.asarray(material.specular_color, f64)
        self.ambient_color = np.asarray(material.ambient_color, f64)
        self.emission = np.asarray(material.emission, f64)
        self.roughness = np.maximum(np.asarray(material.roughness, f64), MIN_PERCEPTUAL_ROUGHNESS)
        self.alpha = self.roughness * self.roughness
        self.metalness = np.asarray(material.metalness, f64)
        self.metal3 = self.metalness[..., None]  # for mixing colours
        self.shininess = np.maximum(np.asarray(material.shininess, f64), 1e-4)
        self.f0_dielectric = np.asarray(material.f0, f64)
        self.f0 = (1.0 - self.metal3) * self.f0_dielectric[..., None] + self.metal3 * self.base_color
        f90 = np.asarray(material.f90, f64)
        self.f90 = np.where(f90 >= 0.0, f90, np.clip(50.0 * np.mean(self.f0, axis=-1), 0.0, 1.0))
        self.fresnel_p = np.maximum(np.asarray(material.fresnel_p, f64), 1e-3)
        sqrt_f0 = np.sqrt(np.minimum(self.f0_dielectric, 0.99))
        self.eta = (1.0 + sqrt_f0) / (1.0 - sqrt_f0)
        self.has_complex_ior = material.ior_n is not None and material.ior_k is not None
        self.ior_n = np.asarray(material.ior_n if self.has_complex_ior else (1.0, 1.0, 1.0), f64)
        self.ior_k = np.asarray(material.ior_k if self.has_complex_ior else (0.0, 0.0, 0.0), f64)


def blinn_phong_direct(s: Surface, l, E, factors, terms: Terms = DEFAULT_TERMS):
    NoL = _dot(s.n, l)
    c_light = E * INV_PI
    h = half_vector(l, s.v, s.n)
    NoH = _dot(s.n, h)
    diffuse = s.diffuse_color * c_light * factors[0] * NoL[..., None]
    if terms.normalized_blinn_phong:
        lobe = S_BlinnPhongNormalized(NoH, s.shininess) * NoL
        specular = s.specular_color * E * factors[1] * lobe[..., None]
    else:
        specular = s.specular_color * c_light * factors[1] * S_BlinnPhong(NoH, s.shininess)[..., None]
    return np.where((NoL > 0.0)[..., None], diffuse + specular, 0.0)


def phong_direct(s: Surface, l, E, factors, terms: Terms = DEFAULT_TERMS):
    NoL = _dot(s.n, l)
    c_light = E * INV_PI
    diffuse = s.diffuse_color * c_light * factors[0] * NoL[..., None]
    specular = s.specular_color * c_light * factors[1] * S_Phong(s.n, l, s.v, s.shininess)[..., None]
    return np.where((NoL > 0.0)[..., None], diffuse + specular, 0.0)


def pbr_fresnel(s: Surface, LoH, terms: Terms):
    f90 = np.broadcast_to(s.f90, np.shape(LoH))
    if terms.fresnel == "SCHLICK_SG":
        return F_SchlickSG(s.f0, f90, LoH)
    if terms.fresnel == "SCHLICK_GENERAL":
        return F_SchlickGeneral(s.f0, f90, s.fresnel_p, LoH)
    if terms.fresnel == "EXACT":
        dielectric = _rgb_scalar(F_Dielectric(s.eta, LoH))
        if s.has_complex_ior:
            metal = F_Conductor(s.ior_n, s.ior_k, LoH)
        else:
            metal = F_Schlick(s.base_color, np.ones(np.shape(LoH)), LoH)
        return dielectric + s.metal3 * (metal - dielectric)
    return F_Schlick(s.f0, f90, LoH)


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


def pbr_diffuse(s: Surface, F, NoV, NoL, NoH, LoH, LoV, terms: Terms):
    rho = s.base_color * (1.0 - s.metal3)
    if terms.diffuse == "BURLEY":
        return rho * _rgb_scalar(Fd_Burley(NoV, NoL, LoH, s.roughness))
    if terms.diffuse == "BURLEY_RENORMALIZED":
        return rho * _rgb_scalar(Fd_BurleyRenormalized(NoV, NoL, LoH, s.roughness))
    if terms.diffuse == "OREN_NAYAR":
        denom = np.sqrt(np.maximum((1.0 - NoL * NoL) * (1.0 - NoV * NoV), 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_phi = np.where(denom > 1e-6, np.clip((LoV - NoL * NoV) / denom, -1.0, 1.0), 1.0)
        return Fd_OrenNayar(rho, NoV, NoL, cos_phi, s.roughness)
    if terms.diffuse == "GGX_HAMMON":
        return Fd_GGXHammon(rho, NoV, NoL, NoH, LoV, s.alpha)
    return (1.0 - F) * rho * Fd_Lambert()


def specular_energy_compensation(s: Surface, terms: Terms):
    """Turquin 2019: 1 + F0 (1 / E(mu_o) - 1), E from addon/multiscatter.py's table."""
    if not terms.multiscatter:
        return np.ones(np.shape(s.NoV) + (3,))
    from .multiscatter import albedo_table, interpolate

    table = albedo_table(terms.ndf, terms.visibility)
    E = np.maximum(interpolate(table, s.NoV, np.broadcast_to(s.roughness, np.shape(s.NoV))), 1e-3)
    return 1.0 + s.f0 * _rgb_scalar(1.0 / E - 1.0)


def principled_direct(s: Surface, NoL, NoH, NxH2, LoH):
    """glsl/principled.glsl's principled_direct without E, NoL and the light factors: (diffuse,
    specular) f for the Principled set."""
    from . import multiscatter as M

    D = D_GGX(NoH, NxH2, s.alpha)
    V = V_SmithGGXCorrelated(s.NoV, NoL, s.alpha)
    rough = np.broadcast_to(s.roughness, np.shape(s.NoV))
    E_mu = np.maximum(M.interpolate(M.albedo_table("GGX", "SMITH_CORRELATED"), s.NoV, rough), 1e-3)
    e_avg = M.interpolate_1d(M.average_albedo(), rough)
    F0m = np.minimum(s.base_color, 1.0)
    metal = (M.principled_compensation(F0m + (1.0 - F0m) / 21.0, _rgb_scalar(E_mu), _rgb_scalar(e_avg))
             * F_Schlick(F0m, np.ones(np.shape(LoH)), LoH))
    Md = M.principled_compensation(M.principled_fss(s.eta), E_mu, e_avg)
    dielectric = Md * F_Dielectric(s.eta, LoH)
    specular = (s.metal3 * metal + (1.0 - s.metal3) * _rgb_scalar(dielectric)) * _rgb_scalar(D * V)
    ratio = (s.eta - 1.0) / (s.eta + 1.0)
    S = M.interpolate_s(M.principled_s_table(), rough, s.NoV, np.broadcast_to(np.sqrt(np.abs(ratio)),
                                                                                np.shape(s.NoV)))
    layer = np.where(s.eta > 1.0, E_mu * Md * (ratio * ratio + S * (1.0 - ratio * ratio)), 0.0)
    diffuse = s.base_color * (1.0 - s.metal3) * _rgb_scalar(np.clip(1.0 - layer, 0.0, 1.0)) * INV_PI
    return diffuse, specular


def pbr_direct(s: Surface, l, E, factors, terms: Terms = DEFAULT_TERMS):
    NoL = _dot(s.n, l)
    NoL_pos = np.maximum(NoL, 0.0)
    h = half_vector(l, s.v, s.n)
    NoH = saturate(_dot(s.n, h))
    NxH = np.cross(s.n, h)
    LoH = saturate(_dot(l, h))
    LoV = _dot(l, s.v)
    if terms.principled:
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            diffuse, specular = principled_direct(s, NoL_pos, NoH, _dot(NxH, NxH), LoH)
            out = (diffuse * factors[0] + specular * factors[1]) * E * NoL_pos[..., None]
        return np.where((NoL > 0.0)[..., None], out, 0.0)
    F = pbr_fresnel(s, LoH, terms)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        D = pbr_distribution(NoH, _dot(NxH, NxH), s.alpha, terms)
        V = pbr_visibility(s.NoV, NoL_pos, NoH, LoH, s.alpha, terms)
        specular = F * _rgb_scalar(D * V) * specular_energy_compensation(s, terms)
        diffuse = pbr_diffuse(s, F, s.NoV, NoL_pos, NoH, LoH, LoV, terms)
        out = (diffuse * factors[0] + specular * factors[1]) * E * NoL_pos[..., None]
    return np.where((NoL > 0.0)[..., None], out, 0.0)


MODELS = {
    "BLINN_PHONG": (blinn_phong_direct, True),
    "PHONG": (phong_direct, True),
    "PBR": (pbr_direct, False),
}


def shade(model: str, s: Surface, lights: list[Light], ambient: float = 0.0,
          terms: Terms = DEFAULT_TERMS):
    """Outgoing radiance (rgb) at every point of ``s``: the twin of mesh.frag.glsl's main()."""
    direct, ldr = MODELS[model]
    c = np.zeros(np.shape(s.p), np.float64)
    c = c + s.emission
    if ldr:
        c = c + s.ambient_color * ambient  # eq. 1.4
    for light in lights:
        E, l = light_irradiance(light, s.p)
        c = c + direct(s, l, E, (light.diffuse_factor, light.specular_factor), terms)
    return np.clip(c, 0.0, 1.0) if ldr else c
