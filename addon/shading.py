"""The numpy twin of ``glsl/``: the same terms, function for function, vectorised over arrays.

Each function mirrors the GLSL function of the same name (inputs are arrays of shape (..., 3)
for vectors and (...) for scalars; evaluated in float64). Tests hold the GPU to this twin, and
the twin itself to closed forms and independent renderers. Pure numpy: no ``bpy``, no ``gpu``.
"""

from __future__ import annotations

import numpy as np

from .snapshot import Light, MaterialParams

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

def F_Schlick(f0, f90, LoH):
    """Eq. 1.11 (F90 = 1) / eq. 1.13 with p = 1/5, on l.h."""
    f0 = np.asarray(f0, np.float64)
    return f0 + (np.asarray(f90)[..., None] - f0) * pow5(1.0 - np.asarray(LoH))[..., None]


def D_GGX(NoH, NxH2, alpha):
    """Eq. 1.15 in the |n x h|^2 form."""
    a = NoH * alpha
    k = alpha / (NxH2 + a * a)
    return k * k * INV_PI


def V_SmithGGXCorrelated(NoV, NoL, alpha):
    """Eqs. 1.16-1.17 divided by 4 NoV NoL."""
    a2 = alpha * alpha
    lambda_v = NoL * np.sqrt(NoV * NoV * (1.0 - a2) + a2)
    lambda_l = NoV * np.sqrt(NoL * NoL * (1.0 - a2) + a2)
    return 0.5 / (lambda_v + lambda_l)


def Fd_Lambert():
    return INV_PI


def S_BlinnPhong(NoH, shininess):
    return np.power(np.maximum(NoH, 0.0), shininess)


def S_Phong(n, l, v, shininess):
    r = 2.0 * _dot(n, l)[..., None] * n - l
    return np.power(np.maximum(_dot(r, v), 0.0), shininess)


def half_vector(l, v, n):
    s = l + v
    len2 = _dot(s, s)
    safe = np.where(len2 > 1e-12, len2, 1.0)
    return np.where((len2 > 1e-12)[..., None], s / np.sqrt(safe)[..., None], n)


# --- lights (glsl/lights.glsl) -----------------------------------------------------------------

def E_Point(light: Light, p):
    d = np.asarray(light.position) - p
    d2 = np.maximum(_dot(d, d), MIN_DIST2)
    l = d / np.sqrt(d2)[..., None]
    return np.asarray(light.intensity) / d2[..., None], l


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


# --- models (glsl/model_*.glsl) ----------------------------------------------------------------

class Surface:
    """The twin of ``struct Surface``: arrays of points, normals, view directions + a material."""

    def __init__(self, p, n, v, material: MaterialParams):
        self.p = np.asarray(p, np.float64)
        self.n = np.asarray(n, np.float64)
        self.v = np.asarray(v, np.float64)
        self.NoV = np.maximum(_dot(self.n, self.v), MIN_COS)
        self.base_color = np.asarray(material.base_color, np.float64)
        self.diffuse_color = np.asarray(material.diffuse_color, np.float64)
        self.specular_color = np.asarray(material.specular_color, np.float64)
        self.ambient_color = np.asarray(material.ambient_color, np.float64)
        self.roughness = max(material.roughness, MIN_PERCEPTUAL_ROUGHNESS)
        self.alpha = self.roughness * self.roughness
        self.metalness = material.metalness
        self.shininess = max(material.shininess, 1e-4)
        self.f0_dielectric = material.f0


def blinn_phong_direct(s: Surface, l, E, factors):
    NoL = _dot(s.n, l)
    c_light = E * INV_PI
    h = half_vector(l, s.v, s.n)
    diffuse = s.diffuse_color * c_light * factors[0] * NoL[..., None]
    specular = s.specular_color * c_light * factors[1] * S_BlinnPhong(_dot(s.n, h), s.shininess)[..., None]
    return np.where((NoL > 0.0)[..., None], diffuse + specular, 0.0)


def phong_direct(s: Surface, l, E, factors):
    NoL = _dot(s.n, l)
    c_light = E * INV_PI
    diffuse = s.diffuse_color * c_light * factors[0] * NoL[..., None]
    specular = s.specular_color * c_light * factors[1] * S_Phong(s.n, l, s.v, s.shininess)[..., None]
    return np.where((NoL > 0.0)[..., None], diffuse + specular, 0.0)


def pbr_f0(s: Surface):
    return (1.0 - s.metalness) * s.f0_dielectric + s.metalness * s.base_color


def pbr_f90(f0):
    return saturate(50.0 * np.mean(f0))


def pbr_direct(s: Surface, l, E, factors):
    NoL = _dot(s.n, l)
    h = half_vector(l, s.v, s.n)
    NoH = saturate(_dot(s.n, h))
    NxH = np.cross(s.n, h)
    LoH = saturate(_dot(l, h))
    f0 = pbr_f0(s)
    F = F_Schlick(f0, np.full(np.shape(NoH), pbr_f90(f0)), LoH)
    D = D_GGX(NoH, _dot(NxH, NxH), s.alpha)
    V = V_SmithGGXCorrelated(s.NoV, np.maximum(NoL, 0.0), s.alpha)
    specular = F * (D * V)[..., None]
    diffuse = (1.0 - F) * s.base_color * (1.0 - s.metalness) * Fd_Lambert()
    out = (diffuse * factors[0] + specular * factors[1]) * E * NoL[..., None]
    return np.where((NoL > 0.0)[..., None], out, 0.0)


MODELS = {
    "BLINN_PHONG": (blinn_phong_direct, True),
    "PHONG": (phong_direct, True),
    "PBR": (pbr_direct, False),
}


def shade(model: str, s: Surface, lights: list[Light], ambient: float = 0.0):
    """Outgoing radiance (rgb) at every point of ``s``: the twin of mesh.frag.glsl's main()."""
    direct, ldr = MODELS[model]
    c = np.zeros(np.shape(s.p), np.float64)
    if ldr:
        c = c + s.ambient_color * ambient  # eq. 1.4
    for light in lights:
        E, l = light_irradiance(light, s.p)
        c = c + direct(s, l, E, (light.diffuse_factor, light.specular_factor))
    return np.clip(c, 0.0, 1.0) if ldr else c
