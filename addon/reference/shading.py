"""The numpy twin of ``glsl/``'s lights and shading models: ``lights.glsl``, ``surface.glsl``,
``pbr_terms.glsl``, ``multiscatter.glsl``, ``principled.glsl`` and ``model_*.glsl``, function for
function, vectorised over arrays; the BRDF terms they compose are in ``brdf.py``, the tables in
``multiscatter.py`` (imports read one way: brdf -> multiscatter -> shading).

Inputs are arrays of shape (..., 3) for vectors and (...) for scalars, evaluated in float64. Tests
hold the GPU to this twin, and the twin itself to closed forms and independent renderers. Pure
numpy: no ``bpy``, no ``gpu``.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..scene.snapshot import LOBES, Light, MaterialParams, Terms
from . import anisotropy, environment, ltc, subsurface, thin_film, transmission
from . import multiscatter as M
from . import sheen as sheen_table
from .brdf import (
    D_GGX,
    INV_PI,
    MIN_COS,
    MIN_PERCEPTUAL_ROUGHNESS,
    F_Conductor,
    F_Dielectric,
    F_Schlick,
    F_SchlickGeneral,
    F_SchlickSG,
    Fd_Burley,
    Fd_BurleyRenormalized,
    Fd_GGXHammon,
    Fd_Lambert,
    Fd_OrenNayar,
    S_BlinnPhong,
    S_BlinnPhongNormalized,
    S_Phong,
    V_SmithGGXCorrelated,
    _dot,
    _rgb_scalar,
    half_vector,
    pbr_distribution,
    pbr_visibility,
    pow5,
    saturate,
)
from .closures import vogel_disc

DEFAULT_TERMS = Terms()
PRINCIPLED_TERMS = Terms(principled=True)
MIN_DIST2 = 1e-4


# --- lights (glsl/lights.glsl) -----------------------------------------------------------------

def E_Point(light: Light, p):
    d = np.asarray(light.position) - p
    d2 = _dot(d, d)
    l = d / np.sqrt(np.maximum(d2, 1e-30))[..., None]  # unit, or 0 for a light exactly at p
    r = light.sphere_radius
    falloff = d2 + (r * r if light.soft_falloff else 0.0)
    return np.asarray(light.intensity) / np.maximum(falloff, MIN_DIST2)[..., None], l


def size_lobe_weights(theta, alpha):
    """(alpha_wide, wide_weight, point_weight) of a light of angular radius ``theta`` (half-vector
    space) against a lobe of width ``alpha`` (lights.glsl's size_lobe_weights)."""
    theta = np.minimum(theta, 0.25 * np.pi)  # no light spans more than the hemisphere
    k2 = theta * theta / np.maximum(alpha * alpha, 1e-12)
    wide_weight = 1.0 / (1.0 + k2)
    point_weight = (1.0 - wide_weight) / (1.0 + 0.5 * np.pi * np.sqrt(k2) + k2)
    return np.sqrt(alpha * alpha + theta * theta), wide_weight, point_weight


def _unit(v):
    return v / np.sqrt(np.maximum(_dot(v, v), 1e-30))[..., None]


def _unit_or(v, fallback):
    """``v`` normalised, or ``fallback`` where it is too short to have a direction (lights.glsl's
    representative points)."""
    len2 = _dot(v, v)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where((len2 > 1e-30)[..., None], v / np.sqrt(len2)[..., None], fallback)


#: Between these k = theta / alpha the physically based model turns from the representative point
#: to the linearly transformed cosines over a sphere light's disc (lights.glsl).
SPHERE_LTC_FROM = 0.1
SPHERE_LTC_FULL = 0.2
#: Beyond this k the disc is a 16-gon, below it an octagon (lights.glsl's SPHERE_FINE_K).
SPHERE_FINE_K = 2.0
SPHERE_COARSE_SIDES = 8


def sphere_light_theta(light: Light, p):
    """The sphere light's angular radius in half-vector space seen from ``p``, r / (2 d')."""
    to_light = np.asarray(light.position) - p
    radius = light.sphere_radius
    d2 = _dot(to_light, to_light) + (radius * radius if light.soft_falloff else 0.0)
    return radius * 0.5 / np.sqrt(np.maximum(d2, 1e-8))


def sphere_light_specular(light: Light, p, r_dir, alpha):
    """(direction, alpha_wide, wide_weight, point_weight): a sphere light's specular lobe as
    glsl/lights.glsl's sphere_light_specular mixes it -- the representative point (Karis 2013)
    renormalised by 1 + (pi/2) k + k^2, and the lobe widened in quadrature, k = theta / alpha."""
    return sphere_light_nearest(light, p, r_dir), *size_lobe_weights(sphere_light_theta(light, p), alpha)


def sphere_light_nearest(light: Light, p, r_dir):
    """lights.glsl's sphere_light_nearest: the unit direction from ``p`` to the sphere light's point
    nearest the ray along ``r_dir`` (Karis 2013's representative point)."""
    to_light = np.asarray(light.position) - p
    radius = light.sphere_radius
    centre_to_ray = _dot(to_light, r_dir)[..., None] * r_dir - to_light
    gap = np.sqrt(_dot(centre_to_ray, centre_to_ray))
    with np.errstate(divide="ignore", invalid="ignore"):
        edge = to_light + centre_to_ray * (radius / gap)[..., None]
    closest = np.where((gap > radius)[..., None], edge, _dot(to_light, r_dir)[..., None] * r_dir)
    return _unit_or(closest, r_dir)


def E_Spot(light: Light, p):
    E, l = E_Point(light, p)
    cos_theta = _dot(-l, np.asarray(light.direction))
    t = saturate((cos_theta - light.spot_cos_half) * light.spot_smooth)
    return E * (t * t * (3.0 - 2.0 * t))[..., None], l


def E_Sun(light: Light, p):
    shape = np.shape(p)
    l = np.broadcast_to(-np.asarray(light.direction, np.float64), shape)
    return np.broadcast_to(np.asarray(light.intensity, np.float64), shape), l


AREA_ELLIPSE_SIDES = 16
#: Radius scale of a 16-gon with the area of its circle: sqrt(2 pi / (n sin(2 pi / n))).
ELLIPSE_SCALE = math.sqrt(2.0 * math.pi / (AREA_ELLIPSE_SIDES * math.sin(2.0 * math.pi / AREA_ELLIPSE_SIDES)))
#: Beyond this many equal-area radii an area light is a point emitter of intensity I cos (lights.glsl).
AREA_FAR_FIELD = 200.0


def area_offsets(light: Light) -> np.ndarray:
    """(n, 3): the area light's polygon (a disk or ellipse: a 16-gon of its area) relative to its centre."""
    x = np.asarray(light.axis_x, np.float64)
    y = np.cross(-np.asarray(light.direction, np.float64), x)
    hx, hy = light.half_size
    if light.ellipse:
        phi = 2.0 * np.pi * np.arange(AREA_ELLIPSE_SIDES) / AREA_ELLIPSE_SIDES
        uv = ELLIPSE_SCALE * np.stack([np.cos(phi), np.sin(phi)], -1)
    else:
        uv = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    return uv[:, :1] * hx * x + uv[:, 1:] * hy * y


def sphere_offsets(light: Light, p, sides: int = AREA_ELLIPSE_SIDES) -> np.ndarray:
    """(..., 16, 3): a sphere light seen from the points ``p`` as the disc through its centre facing
    each point with the same solid angle, relative to its centre (lights.glsl's sphere_polygon):
    radius r with soft falloff, r d / sqrt(d^2 - r^2) for the sphere (89.4 degrees inside it)."""
    to_centre = np.asarray(light.position, np.float64) - p
    d2 = _dot(to_centre, to_centre)
    r = light.sphere_radius
    gap = np.maximum(np.maximum(d2 - r * r, 1e-4 * d2), 1e-30)
    radius = r if light.soft_falloff else r * np.sqrt(d2 / gap)
    w = to_centre / np.sqrt(np.maximum(d2, 1e-30))[..., None]
    other = np.where((np.abs(w[..., :1]) < 0.9), [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    x = _unit_or(np.cross(other, w), other)  # p at the centre (w = 0): any frame
    y = np.cross(w, x)
    phi = 2.0 * np.pi * np.arange(sides) / sides
    scale_n = math.sqrt(2.0 * math.pi / (sides * math.sin(2.0 * math.pi / sides)))  # the n-gon of its area
    uv = scale_n * np.stack([np.cos(phi), np.sin(phi)], -1)
    scale = np.asarray(radius)[..., None, None]
    return scale * (uv[:, :1] * x[..., None, :] + uv[:, 1:] * y[..., None, :])


def sphere_far_field(light: Light, d2):
    """Seen from farther than AREA_FAR_FIELD radii, a sphere light is shaded from its centre and
    its nearest point (lights.glsl's sphere_far_field)."""
    return (light.sphere_radius * AREA_FAR_FIELD) ** 2 < d2


polygon_form_factor = ltc.polygon_form_factor  # (lights.glsl's polygon_form_factor, one twin for both)


SPREAD_GAUSS = 1.0 / math.sqrt(3.0)  # 2-point Gauss-Legendre nodes on [-1, 1]


def spread_weight(light: Light, tan_a):
    """W(a) = max(tan h - tan a, 0) / (tan h - h): the emitter's radiance scale towards a
    direction at angle a from its normal under its Spread (lights.glsl's spread_weight)."""
    tan_h, norm = light.spread_terms
    return np.maximum(tan_h - np.asarray(tan_a), 0.0) * norm


def area_spread(light: Light, to_centre, lobe=None):
    """(W's mean, offsets, to_centre) of what of an area light reaches the points at -to_centre
    from its centre through its spread (lights.glsl's area_spread): the light's box clipped to
    the square of half-size z tan h about each point's foot on its plane, offsets (..., n, 3)
    about the clipped centre (a rectangle's corners repeated to an ellipse's n: zero edges add
    nothing; an ellipse the square holds whole is kept), and W's mean over it as a surface facing
    the light receives it, by 2 x 2 Gauss points per quarter about the foot -- an ellipse's W
    times each point's cell's share inside it (the share of a clipped ellipse's box it lights).
    ``lobe`` = (M^-1, x, y, z), the LTC and its shading frame: W's mean for the specular lobe,
    weighted by the LTC's density instead, is returned fourth."""
    normal = np.asarray(light.direction, np.float64)
    x_axis = np.asarray(light.axis_x, np.float64)
    y_axis = np.cross(-normal, x_axis)
    q = -np.asarray(to_centre, np.float64)
    z = _dot(q, normal)
    foot = np.stack([_dot(q, x_axis), _dot(q, y_axis)], axis=-1)
    R = (z * light.spread_terms[0])[..., None]
    half = np.asarray(light.half_size, np.float64)
    holds_all = np.all(foot - R <= -half, axis=-1) & np.all(foot + R >= half, axis=-1)
    lo, hi = np.maximum(-half, foot - R), np.minimum(half, foot + R)
    empty = np.any(hi <= lo, axis=-1) | (z <= 0.0)
    centre = 0.5 * (lo + hi)
    size = 0.5 * (hi - lo)
    uv = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    corners = np.repeat(uv, AREA_ELLIPSE_SIDES // 4, axis=0) if light.ellipse else uv
    rect = (corners[:, :1] * size[..., None, :1]) * x_axis + (corners[:, 1:] * size[..., None, 1:]) * y_axis
    keep = holds_all[..., None, None]
    offsets = np.where(keep, area_offsets(light), rect)
    shift = centre[..., :1] * x_axis + centre[..., 1:] * y_axis
    clipped_to_centre = np.where(holds_all[..., None], to_centre, to_centre + shift)
    split = np.clip(foot, lo, hi)
    total = np.zeros(np.shape(z))
    weights = np.zeros(np.shape(z))
    lobe_total = np.zeros(np.shape(z))
    lobe_weights = np.zeros(np.shape(z))
    for i in range(4):
        a = np.stack([(split if i & 1 else lo)[..., 0], (split if i & 2 else lo)[..., 1]], -1)
        b = np.stack([(hi if i & 1 else split)[..., 0], (hi if i & 2 else split)[..., 1]], -1)
        extent = b - a
        ok = (extent[..., 0] > 0.0) & (extent[..., 1] > 0.0)
        for j in range(4):
            g = np.array([SPREAD_GAUSS if j & 1 else -SPREAD_GAUSS, SPREAD_GAUSS if j & 2 else -SPREAD_GAUSS])
            d = 0.5 * (a + b + extent * g) - foot
            r2 = _dot(d, d) + z * z
            with np.errstate(divide="ignore", invalid="ignore"):
                w = np.where(ok, z * z / (r2 * r2) * extent[..., 0] * extent[..., 1], 0.0)
                tan_a = np.where(ok, np.sqrt(_dot(d, d)) / np.where(z > 0.0, z, 1.0), 0.0)
            W = spread_weight(light, tan_a)
            if light.ellipse:  # the share of the point's cell inside the ellipse: the coverage of
                # a box by the boundary's tangent line, its signed distance over the box's width
                q2 = 0.5 * (a + b + extent * g) / half
                rho = np.sqrt(_dot(q2, q2))
                across = 0.5 * (np.abs(q2[..., 0]) * extent[..., 0] / half[0]
                                + np.abs(q2[..., 1]) * extent[..., 1] / half[1])
                with np.errstate(divide="ignore", invalid="ignore"):
                    cover = np.clip(0.5 + (1.0 - rho) * rho / np.where(across > 0.0, across, 1.0), 0.0, 1.0)
                cover = np.where(across > 0.0, cover, (rho < 1.0).astype(np.float64))
                W = W * cover
                w_mean = w * np.where(holds_all, cover, 1.0)  # the ellipse itself: W's mean over it
            else:
                w_mean = w
            total = total + w * W
            weights = weights + w_mean
            if lobe is not None:  # the LTC's density towards the point over its cell's solid angle
                minv, fx, fy, fz = lobe
                at = 0.5 * (a + b + extent * g)
                to_point = _unit(to_centre + at[..., :1] * x_axis + at[..., 1:] * y_axis)
                local = np.stack([_dot(to_point, fx), _dot(to_point, fy), _dot(to_point, fz)], axis=-1)
                with np.errstate(divide="ignore", invalid="ignore"):
                    lobe_w = np.where(ok, ltc.ltc_density(minv, local) * w * np.sqrt(r2)
                                      / np.where(z > 0.0, z, 1.0), 0.0)
                    share = np.where(w > 0.0, w_mean / np.where(w > 0.0, w, 1.0), 0.0)
                lobe_total = lobe_total + lobe_w * W
                lobe_weights = lobe_weights + lobe_w * share
    with np.errstate(divide="ignore", invalid="ignore"):
        mean = np.where((weights > 0.0) & ~empty, total / np.where(weights > 0.0, weights, 1.0), 0.0)
        lobe_mean = np.where(lobe_weights > 0.0, lobe_total / np.where(lobe_weights > 0.0, lobe_weights, 1.0),
                             mean)
    lobe_mean = np.where(empty, 0.0, lobe_mean)
    if lobe is None:
        return mean, offsets, clipped_to_centre
    return mean, offsets, clipped_to_centre, lobe_mean


def area_light_area(light: Light) -> float:
    hx, hy = light.half_size
    return 4.0 * hx * hy * (np.pi / 4.0 if light.ellipse else 1.0)


def area_far_field(light: Light, d2):
    """Seen from farther than AREA_FAR_FIELD equal-area radii, a light is shaded as a point."""
    area = area_light_area(light)
    return (area > 0.0) & (area * AREA_FAR_FIELD ** 2 < np.pi * d2)


def E_Area(light: Light, p):
    """The polygon's vector form factor V = 1/2 sum theta_i g_i: E = L |V|, l = V / |V|; beyond
    AREA_FAR_FIELD equal-area radii a point of intensity I cos (lights.glsl)."""
    to_centre = np.asarray(light.position, np.float64) - p
    d2 = _dot(to_centre, to_centre)
    normal = np.asarray(light.direction, np.float64)
    area = area_light_area(light)
    spread, offsets, clipped = (area_spread(light, to_centre) if light.spread_terms[1] > 0.0
                                else (1.0, area_offsets(light), to_centre))
    V = polygon_form_factor(offsets, clipped)
    length = np.linalg.norm(V, axis=-1)
    front = _dot(-to_centre, normal) > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        l = np.where((length > 0.0)[..., None], V / length[..., None], _unit(to_centre))
    E = np.asarray(light.intensity) / max(area, 1e-12) * np.where(front, length * spread, 0.0)[..., None]
    far = area_far_field(light, d2)
    l_far = _unit(to_centre)
    cos_a = _dot(-l_far, normal)
    if light.spread_terms[1] > 0.0:  # the point emitter's profile under its spread
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_a = cos_a * spread_weight(light, np.sqrt(np.maximum(1.0 - cos_a * cos_a, 0.0)) / cos_a)
    E_far = np.asarray(light.intensity) * (np.where(front, cos_a, 0.0) / np.maximum(d2, MIN_DIST2))[..., None]
    return np.where(far[..., None], E_far, E), np.where(far[..., None], l_far, l)


def light_window(light: Light, p):
    """The light's reach as a window on its irradiance (lights.glsl light_window): (1 - (d/r)^4)^2,
    0 from r on; 1 for a light that reaches everywhere."""
    if not math.isfinite(light.influence):
        return np.ones(np.shape(p)[:-1])
    d = np.asarray(light.position) - p
    x = _dot(d, d) / light.influence ** 2
    return saturate(1.0 - x * x) ** 2


def light_irradiance(light: Light, p):
    """(E, l): irradiance on a surface facing the light (W/m^2, rgb) and the unit light direction."""
    E, l = {"POINT": E_Point, "SPOT": E_Spot, "SUN": E_Sun, "AREA": E_Area}[light.kind](light, p)
    if light.kind != "SUN":
        E = E * light_window(light, p)[..., None]
    return E, l


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
        self.specular_tint = np.maximum(np.asarray(material.specular_tint, f64), 0.0)
        # the Principled BSDF's upper layers (the Principled set's: upper_layers), clamped as Cycles
        self.coat_weight = np.maximum(np.asarray(material.coat_weight, f64), 0.0)
        self.coat_roughness = np.clip(np.asarray(material.coat_roughness, f64), 0.0, 1.0)
        self.coat_ior = np.maximum(np.asarray(material.coat_ior, f64), 1.0)
        self.coat_tint = np.maximum(np.asarray(material.coat_tint, f64), 0.0)
        self.sheen = (np.maximum(np.asarray(material.sheen_weight, f64), 0.0)[..., None]
                      * np.maximum(np.asarray(material.sheen_tint, f64), 0.0))
        self.sheen_roughness = np.clip(np.asarray(material.sheen_roughness, f64), 0.0, 1.0)
        self.thin_film = thin_film.film_of(material)  # MaterialData's thin_film (thin_film.film_of)
        # the subsurface (glsl/subsurface.glsl): its weight, mean free path and the surface's curvature
        # (which the mesh program measures; 0 unless a caller sets it); a node graph's translucent lobe
        self.subsurface = np.clip(np.asarray(material.subsurface_weight, f64), 0.0, 1.0)
        self.subsurface_radius = subsurface.mean_free_path(
            material.subsurface_radius, material.subsurface_scale, material.subsurface_method,
            np.clip(self.base_color, 0.0, 1.0), material.subsurface_ior)
        self.curvature = np.zeros(np.shape(self.NoV))
        # the random walk's light over its Lambert base at the view (subsurface.walk_factor), of the
        # base colour within [0, 1]; 1 where no material has a subsurface (its table is not read)
        self.subsurface_walk = np.ones(np.shape(self.NoV) + (3,))
        # and its mean drift away from the viewer (units of the mean free path) and gain on a convex
        # surface per unit rho (walk_factor's)
        self.subsurface_drift = np.zeros(np.shape(self.NoV) + (3,))
        self.subsurface_gain = np.zeros(np.shape(self.NoV) + (3,))
        if np.any(self.subsurface > 0.0):
            walk = subsurface.walk_row(material.subsurface_method, material.ior, material.specular_ior_level,
                                       material.subsurface_ior, material.subsurface_anisotropy)
            self.subsurface_walk, self.subsurface_drift, self.subsurface_gain = subsurface.walk_factor(
                _dot(self.n, self.v), np.clip(self.base_color, 0.0, 1.0), walk, material.roughness,
                drift=True)
        self.translucent = np.zeros(3)
        # the anisotropic GGX lobe (x, y, alpha_x, alpha_y) of a node graph's anisotropic BSDF (its tangent is
        # per fragment: ``with_anisotropy``), None for the round lobe
        self.aniso = None
        # transmission (glsl/transmission.glsl's transmission_at): the glass share of the non-metallic
        # part, its weight of the whole surface, IOR (floored as pack_material floors it), the tint of
        # each crossing, the dielectric reflection's tint, whether the Fresnel splits the light
        self.transmission_share = np.clip(np.asarray(material.transmission_weight, f64), 0.0, 1.0)
        self.transmission_weight = self.transmission_share * (1.0 - self.metalness)
        self.transmission_eta = np.maximum(np.asarray(material.transmission_ior, f64), 1e-5)
        self.transmission_tint = np.maximum(np.asarray(material.transmission_tint, f64), 0.0)
        self.reflection_tint = np.maximum(np.asarray(material.reflection_tint, f64), 0.0)
        self.transmission_fresnel = bool(material.transmission_fresnel)


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
    if terms.diffuse == "LAYERED":
        return rho * _rgb_scalar(np.clip(1.0 - principled_layers(s, terms).layer, 0.0, 1.0) * INV_PI)
    return (1.0 - F) * rho * Fd_Lambert()


def specular_energy_compensation(s: Surface, terms: Terms):
    """Turquin 2019: 1 + F0 (1 / E(mu_o) - 1), E from addon/reference/multiscatter.py's table."""
    if not terms.multiscatter:
        return np.ones(np.shape(s.NoV) + (3,))
    table = M.albedo_table(terms.ndf, terms.visibility)
    E = np.maximum(M.interpolate(table, s.NoV, np.broadcast_to(s.roughness, np.shape(s.NoV))), 1e-3)
    return 1.0 + s.f0 * _rgb_scalar(1.0 / E - 1.0)


@dataclass
class PrincipledLayers:
    """surface.glsl's PrincipledLayers: the metal and dielectric lobes' multiple-scattering
    compensation (rgb), the dielectric layer's albedo estimate (rgb) and its largest channel, which
    the base below loses; F82-tint's b and the tinted dielectric F0."""

    metal_M: np.ndarray
    dielectric_M: np.ndarray
    albedo: np.ndarray
    layer: np.ndarray
    metal_b: np.ndarray
    dielectric_f0: np.ndarray


def F82_tint_b(f0, tint):
    """principled.glsl's F82_tint_b (Cycles' fresnel_f82tint_B): F82-tint's b, the Schlick curve
    times ``tint`` at cos = 1/7 solved for b in Schlick - b cos (1 - cos)^6."""
    f = 6.0 / 7.0
    f5 = pow5(f)
    f0 = np.asarray(f0, np.float64)
    return (f0 + (1.0 - f0) * f5) * (7.0 / (f5 * f)) * (1.0 - np.asarray(tint, np.float64))


def F_F82Tint(f0, b, cos_i):
    """principled.glsl's F_F82Tint (Cycles' fresnel_f82): Schlick less b cos (1 - cos)^6, in [0, 1]."""
    cos_i = np.asarray(cos_i, np.float64)
    s = saturate(1.0 - cos_i)
    s5 = pow5(s)
    f0 = np.asarray(f0, np.float64)
    return np.clip(f0 + (1.0 - f0) * _rgb_scalar(s5) - np.asarray(b) * _rgb_scalar(cos_i * s5 * s), 0.0, 1.0)


def F_DielectricTinted(eta, f0_tinted, cos_i):
    """principled.glsl's F_DielectricTinted (Cycles' generalized Schlick with a negative exponent):
    from the tinted F0 to 1 as the exact Fresnel of ``eta`` goes from its own F0 to 1."""
    eta = np.asarray(eta, np.float64)
    f0 = ((eta - 1.0) / (eta + 1.0)) ** 2
    s = saturate((F_Dielectric(eta, cos_i) - f0) / (1.0 - f0))
    f0_tinted = np.asarray(f0_tinted, np.float64)
    return f0_tinted + (1.0 - f0_tinted) * _rgb_scalar(s)


def principled_layers_at(NoV, roughness, base_color, eta, tint, lobe=("GGX", "SMITH_CORRELATED")):
    """principled.glsl's principled_layers_at: the two lobes' compensation and the dielectric layer's
    albedo estimate E M mix(F0 tint, 1, S) at the view (``PrincipledLayers``), each lobe's average
    Fresnel as Cycles' Principled BSDF takes it with the Specular Tint ``tint``; E of the lobe
    ``lobe`` (the Principled set's GGX with Smith; the LAYERED diffuse's program's), Eavg GGX's."""
    rough = np.broadcast_to(roughness, np.shape(NoV))
    E_mu = np.maximum(M.interpolate(M.albedo_table(*lobe), NoV, rough), 1e-3)
    e_avg = M.interpolate_1d(M.average_albedo(), rough)
    F0m = np.minimum(base_color, 1.0)
    eta = np.asarray(eta, np.float64)
    tint = np.asarray(tint, np.float64)
    ratio = (eta - 1.0) / (eta + 1.0)
    f0 = ratio * ratio
    metal_b = F82_tint_b(F0m, np.minimum(tint, 1.0))
    metal_Fss = F0m + (1.0 - F0m) / 21.0 - metal_b / 126.0
    s_avg = saturate((M.principled_fss(eta) - f0) / (1.0 - f0))
    f0_tinted = np.clip(_rgb_scalar(f0) * tint, 0.0, 1.0)
    dielectric_Fss = f0_tinted + (1.0 - f0_tinted) * _rgb_scalar(s_avg)
    metal_M = M.principled_compensation(metal_Fss, _rgb_scalar(E_mu), _rgb_scalar(e_avg))
    dielectric_M = M.principled_compensation(dielectric_Fss, _rgb_scalar(E_mu), _rgb_scalar(e_avg))
    z = np.broadcast_to(np.sqrt(np.abs(ratio)), np.shape(NoV))
    S = _rgb_scalar(M.interpolate_s(M.principled_s_table(), rough, NoV, z))
    albedo = np.where(_rgb_scalar(eta > 1.0),
                      _rgb_scalar(E_mu) * dielectric_M * (f0_tinted + (1.0 - f0_tinted) * S), 0.0)
    return PrincipledLayers(metal_M, dielectric_M, albedo, albedo.max(axis=-1), metal_b, f0_tinted)


def principled_layers(s: Surface, terms: Terms = PRINCIPLED_TERMS) -> PrincipledLayers:
    """``principled_layers_at`` of ``s`` (surface.glsl's make_surface): its Specular Tint in the
    Principled set, white in the LAYERED diffuse's programs."""
    tint = s.specular_tint if terms.principled else np.ones(3)
    p = principled_layers_at(s.NoV, s.roughness, s.base_color, s.eta, tint, terms.lobe)
    if terms.principled and "THIN_FILM" in LOBES and np.any(thin_film.has_film(s.thin_film)):
        # thin_film.glsl's thin_film_at: the layer's albedo E M F(n.v) under the film
        film = thin_film.has_film(s.thin_film)
        E_mu = np.maximum(M.interpolate(M.albedo_table(*terms.lobe), s.NoV,
                                        np.broadcast_to(s.roughness, np.shape(s.NoV))), 1e-3)
        F = thin_film.dielectric(s.thin_film, s.eta, p.dielectric_f0, s.NoV)
        p.albedo = np.where(film[..., None], _rgb_scalar(E_mu) * p.dielectric_M * F, p.albedo)
        p.layer = p.albedo.max(axis=-1)
    return p


def principled_specular_tint(s: Surface, LoH):
    """What multiplies D V in the Principled set's specular lobe (principled.glsl): its metal
    (F82-tint) and dielectric (tinted) lobes' Fresnel and compensation, weighted by metalness."""
    p = principled_layers(s)
    metal = p.metal_M * F_F82Tint(np.minimum(s.base_color, 1.0), p.metal_b, LoH)
    dielectric = p.dielectric_M * F_DielectricTinted(s.eta, p.dielectric_f0, LoH)
    if "THIN_FILM" in LOBES and np.any(thin_film.has_film(s.thin_film)):  # principled.glsl's film
        film = thin_film.has_film(s.thin_film)[..., None]
        F = thin_film.dielectric(s.thin_film, s.eta, p.dielectric_f0, LoH)
        dielectric = np.where(film, p.dielectric_M * F, dielectric)
        F0m = np.broadcast_to(np.minimum(s.base_color, 1.0), np.shape(metal))
        metal = np.where(thin_film.on_metal(s.thin_film)[..., None],
                         p.metal_M * thin_film.metal(s.thin_film, F0m, p.metal_b, LoH), metal)
    dielectric = dielectric * s.reflection_tint  # the Glass BSDF's Color (transmission.glsl)
    return s.metal3 * metal + (1.0 - s.metal3) * dielectric


@dataclass
class UpperLayers:
    """What the Principled BSDF's upper layers make of a surface at its view (surface.glsl's
    make_surface): what they leave the base (rgb), the coat as a surface of its own (None: no coat)
    and the sheen's lobe (None: no sheen)."""

    below: np.ndarray
    coat: Surface | None
    sheen: SheenLobe | None
    coat_weight: np.ndarray | float = 0.0  # the coat's lobe weight: Coat Weight x what the sheen leaves it


@dataclass
class SheenLobe:
    """surface.glsl's SheenLobe: its colour (weight x tint x albedo), normal, frame and M^-1
    entries as ltc.glsl's."""

    color: np.ndarray
    n: np.ndarray
    x_axis: np.ndarray
    y_axis: np.ndarray
    m: np.ndarray


def with_anisotropy(s: Surface, tangent, stretch) -> Surface:
    """``s`` with its specular lobes anisotropic (surface.glsl's make_surface with SL_ANISOTROPY): the
    lobe of the tangent and stretch k (MaterialData's anisotropy row) about the normal, from the
    material's alpha; the isotropic stand-ins' roughness (alpha_x alpha_y)^(1/4), floored."""
    a = copy.copy(s)
    a.aniso = anisotropy.lobe(s.n, tangent, s.alpha, stretch)
    a.roughness = np.maximum(anisotropy.roughness(a.aniso[2], a.aniso[3]), MIN_PERCEPTUAL_ROUGHNESS)
    a.alpha = a.roughness * a.roughness
    return a


def coat_surface(s: Surface) -> Surface:
    """principled.glsl's coat_at and coat_surface: the coat as a black dielectric surface of its
    own roughness (floored as the base's) and IOR, the surface's normal (a node graph's own coat
    normal is the GPU's alone), without upper layers of its own."""
    c = copy.copy(s)
    c.roughness = np.maximum(s.coat_roughness, MIN_PERCEPTUAL_ROUGHNESS)
    c.alpha = c.roughness * c.roughness
    c.base_color = np.zeros(3)
    c.metalness = np.zeros(np.shape(s.metalness))
    c.metal3 = c.metalness[..., None]
    c.eta = s.coat_ior
    c.specular_tint = np.ones(3)
    c.coat_weight = np.zeros(np.shape(s.coat_weight))
    c.sheen = np.zeros(3)
    c.thin_film = s.thin_film * np.array([0.0, 1.0, 1.0, 1.0])  # the film lies on the base, under the coat
    c.reflection_tint = np.ones(3)  # no Glass BSDF's Color on the coat
    if s.aniso is not None:  # Cycles' coat is round (principled.glsl's anisotropic_none)
        c.aniso = anisotropy.lobe(s.n, np.zeros(3), c.alpha, 1.0)
    return c


def coat_transmittance(s: Surface, coat: Surface):
    """principled.glsl's coat_transmittance: 1 - the coat's weighted albedo (its largest channel),
    times the tint's absorption along the view's refracted path, mixed in by the weight."""
    w = s.coat_weight
    below = saturate(1.0 - w * principled_layers(coat).layer)
    sin2_t = (1.0 - coat.NoV * coat.NoV) / (coat.eta * coat.eta)
    depth = 1.0 / np.sqrt(np.maximum(1.0 - sin2_t, MIN_COS * MIN_COS))
    transmitted = s.coat_tint ** _rgb_scalar(depth)
    return _rgb_scalar(below) * (1.0 + _rgb_scalar(w) * (transmitted - 1.0))


def upper_layers(s: Surface) -> UpperLayers | None:
    """The Principled BSDF's upper layers at ``s``'s view (surface.glsl's make_surface with
    SL_COAT, SL_SHEEN): None where it has neither (no weight above 0 anywhere)."""
    coat = coat_surface(s) if "COAT" in LOBES and np.any(s.coat_weight > 1e-5) else None
    has_sheen = "SHEEN" in LOBES and np.any(s.sheen > 1e-5)
    if coat is None and not has_sheen:
        return None
    below = np.ones(np.shape(s.NoV) + (3,))
    n = s.n
    if coat is not None:
        below = below * coat_transmittance(s, coat)
    sheen = None
    coat_weight = s.coat_weight
    if has_sheen:
        sheen = sheen_at(n, s.v, s.sheen_roughness, s.sheen)
        left = saturate(1.0 - sheen.color.max(axis=-1))  # the sheen's layering weight: coat and base
        below = below * _rgb_scalar(left)
        coat_weight = coat_weight * left
    return UpperLayers(below, coat, sheen, coat_weight)


def sheen_at(n, v, roughness, color) -> SheenLobe:
    """principled.glsl's sheen_at: the LTC (a, b) and albedo at (n.v, roughness in [1e-3, 1]) from
    the sheen table (``sheen.lookup``), the frame's tangent towards v; no sheen where the fit has no
    lobe (|a| or the albedo below 1e-5)."""
    NoV = _dot(n, v)
    fit = sheen_table.lookup(NoV, np.clip(np.broadcast_to(roughness, np.shape(NoV)), 1e-3, 1.0))
    lobe = (np.abs(fit[..., 0]) >= 1e-5) & (fit[..., 2] >= 1e-5)
    x_axis = v - n * NoV[..., None]
    other = np.where((np.abs(n[..., :1]) < 0.9), [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    x_axis = np.where((_dot(x_axis, x_axis) > 1e-18)[..., None], x_axis, np.cross(other, n))
    x_axis = _unit(x_axis)
    a = np.where(lobe, fit[..., 0], 1.0)
    m = np.stack([np.ones_like(a), fit[..., 1] / a, np.zeros_like(a), 1.0 / a], axis=-1)
    albedo = np.where(lobe, fit[..., 2], 0.0)
    return SheenLobe(np.asarray(color) * _rgb_scalar(albedo), np.asarray(n), x_axis, np.cross(n, x_axis), m)


def sheen_direct(sheen: SheenLobe, l):
    """principled.glsl's sheen_direct: the sheen's f (n.l) towards l per unit irradiance."""
    local = np.stack([_dot(l, sheen.x_axis), _dot(l, sheen.y_axis), _dot(l, sheen.n)], axis=-1)
    return sheen.color * _rgb_scalar(ltc.ltc_density(ltc.minv_from_entries(sheen.m), local))


#: principled.glsl's SHEEN_WORLD_SAMPLES: directions of the sheen's lobe the world is read in.
SHEEN_WORLD_SAMPLES = 16


def sunless_roughness(first_clamped: int) -> float:
    """ibl.glsl's env_sunless_roughness: the first level's roughness made without the suns (levels from
    ``first_clamped`` on), the floor where the world has none."""
    if first_clamped >= environment.PREFILTER_LEVELS:
        return MIN_PERCEPTUAL_ROUGHNESS
    return MIN_PERCEPTUAL_ROUGHNESS if first_clamped == 0 else environment.level_roughness(first_clamped)


def sheen_environment(sheen: SheenLobe, read, floor_roughness: float, count: int = SHEEN_WORLD_SAMPLES):
    """principled.glsl's sheen_environment: the mean over ``count`` directions of the sheen's LTC (Vogel's
    disc lifted to the clamped cosine, mapped by M) of ``read(l, roughness)``, the prefiltered world at
    each sample's footprint roughness (``anisotropy.sample_roughness``), no smoother than
    ``floor_roughness``."""
    minv = ltc.minv_from_entries(sheen.m)
    total = 0.0
    for i in range(count):
        d = vogel_disc(i, count)
        w = np.array([d[0], d[1], math.sqrt(max(1.0 - d @ d, 0.0))])
        local = ltc.ltc_direction(sheen.m, w)
        rough = np.maximum(anisotropy.sample_roughness(ltc.ltc_density(minv, local), count), floor_roughness)
        l = local[..., :1] * sheen.x_axis + local[..., 1:2] * sheen.y_axis + local[..., 2:] * sheen.n
        total = total + read(l, rough)
    return total / count


def pbr_specular_tint(s: Surface, LoH, terms: Terms):
    """model_pbr.glsl's pbr_specular_tint: F with the energy compensation, or the Principled set's."""
    if terms.principled:
        return principled_specular_tint(s, LoH)
    return pbr_fresnel(s, LoH, terms) * specular_energy_compensation(s, terms)


def pbr_lobe(s: Surface, l, terms: Terms):
    """model_pbr.glsl's pbr_lobe: D V (n.l) with F = 1 towards l (the Principled set: GGX, Smith)."""
    terms = DEFAULT_TERMS if terms.principled else terms
    NoL, NoL_pos, NoH, NxH, LoH = _light_geometry(s, l)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if s.aniso is not None:  # principled.glsl's principled_DV
            out = anisotropic_DV(s, l) * NoL_pos
        else:
            out = (pbr_distribution(NoH, _dot(NxH, NxH), s.alpha, terms)
                   * pbr_visibility(s.NoV, NoL_pos, NoH, LoH, s.alpha, terms) * NoL_pos)
    return np.where(NoL > 0.0, out, 0.0)


def anisotropic_DV(s: Surface, l):
    """anisotropy.glsl's anisotropic_DV: the anisotropic lobe's D V towards l (meaningful where
    n.l > 0: the callers mask the rest)."""
    h = half_vector(l, s.v, s.n)
    return anisotropy.D(h, s.n, *s.aniso) * anisotropy.V(s.v, l, s.n, *s.aniso, NoV=s.NoV)


def _light_geometry(s: Surface, l):
    """n.l, max(n.l, 0), n.h, n x h and l.h for the half vector of l and the view."""
    NoL = _dot(s.n, l)
    h = half_vector(l, s.v, s.n)
    return NoL, np.maximum(NoL, 0.0), saturate(_dot(s.n, h)), np.cross(s.n, h), saturate(_dot(l, h))


def principled_direct(s: Surface, NoL, NoH, NxH2, LoH, l=None):
    """glsl/principled.glsl's principled_direct without E, NoL and the light factors: (diffuse,
    specular) f for the Principled set (towards ``l``, which the anisotropic lobe needs)."""
    if s.aniso is not None:  # principled_DV
        DV = anisotropic_DV(s, l)
    else:
        DV = D_GGX(NoH, NxH2, s.alpha) * V_SmithGGXCorrelated(s.NoV, NoL, s.alpha)
    specular = principled_specular_tint(s, LoH) * _rgb_scalar(DV)
    layer = principled_layers(s).layer
    diffuse = s.base_color * (1.0 - s.metal3) * _rgb_scalar(np.clip(1.0 - layer, 0.0, 1.0)) * INV_PI
    diffuse = diffuse * _rgb_scalar(1.0 - s.subsurface)  # the rest scatters below (subsurface_direct)
    diffuse = diffuse * _rgb_scalar(1.0 - s.transmission_share)  # the glass's share transmits instead
    return diffuse, specular


def subsurface_walk_curved(s: Surface):
    """glsl/subsurface.glsl's subsurface_walk_curved: the walk's factor at the view, raised by the
    surface's convexity (subsurface.convex_gain)."""
    return s.subsurface_walk * subsurface.convex_gain(s.subsurface_gain, s.subsurface_radius, s.curvature)


def subsurface_light_shape(light: Light, p):
    """glsl/subsurface.glsl's subsurface_light_shape: ((...), (...)) the sine of the angular radius of
    the sphere the light is seen as from ``p`` (a point or spot's radius r over d (a sphere) or
    sqrt(d^2 + r^2) (soft falloff: a disc); an area light's disc of its area times the cosine at the
    light over pi; 0 for a sun and a true point) and 1 / its distance (a sun's 0)."""
    to_light = np.asarray(light.position, np.float64) - np.asarray(p, np.float64)
    d2 = _dot(to_light, to_light)
    if light.kind == "SUN":
        return np.zeros_like(d2), np.zeros_like(d2)
    disc = 1.0 if light.soft_falloff else 0.0
    with np.errstate(invalid="ignore", divide="ignore"):
        if light.kind == "AREA":
            facing = np.where(d2 > 0.0, np.maximum(_dot(np.asarray(light.direction, np.float64), -to_light)
                                                   / np.sqrt(d2), 0.0), 0.0)
            r2 = area_light_area(light) * facing / np.pi
            disc = 1.0
        else:
            r2 = np.full_like(d2, light.sphere_radius ** 2)
        sine = np.where(r2 > 0.0, np.sqrt(np.minimum(r2 / np.maximum(d2 + disc * r2, 1e-30), 1.0)), 0.0)
        return sine, np.where(d2 > 0.0, 1.0 / np.sqrt(d2), 0.0)


def subsurface_direct(s: Surface, l, size=0.0, inverse_distance=0.0):
    """glsl/subsurface.glsl's subsurface_direct: the subsurface's f (n.l) towards l per unit irradiance,
    under a light of angular radius asin(``size``) at 1 / ``inverse_distance`` (subsurface_light_shape;
    a sun: 0)."""
    layer = principled_layers(s).layer
    weight = (1.0 - s.metalness) * np.clip(1.0 - layer, 0.0, 1.0) * s.subsurface * INV_PI
    # under what the glass's share leaves (Cycles' svm_node_closure_bsdf weighs the subsurface by
    # 1 - Transmission Weight, as the diffuse)
    weight = weight * (1.0 - s.transmission_share)
    color = s.base_color * _rgb_scalar(weight) * subsurface_walk_curved(s)  # the walk's reflectance
    # n.l where the walk leaves on average, per channel (its drift away from the viewer)
    NoL = subsurface.drift_cosine(_dot(s.n, l), s.n, s.v, l, s.subsurface_drift, s.subsurface_radius,
                                  s.curvature)
    size = np.broadcast_to(size, np.shape(s.NoV))
    falloff = (subsurface.ramp_sized(NoL, s.subsurface_radius, s.curvature, size)
               + subsurface.curved_light(_dot(s.n, l), s.subsurface_radius, s.curvature,
                                         np.broadcast_to(inverse_distance, np.shape(s.NoV))))
    return color * np.maximum(falloff, 0.0)


def _transmission_crossing(s: Surface, l, eta, alpha):
    """transmission.glsl's transmission_crossing: the GGX transmission lobe times its Fresnel."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        lobe, HoV = transmission.transmission_ggx(s.n, s.v, l, eta, alpha)
        crossing = transmission.transmission_fraction(HoV, eta, s.transmission_fresnel)
    return np.where(lobe > 0.0, crossing * lobe, 0.0)


def transmission_light(s: Surface, l, E, factors, light: Light | None = None):
    """glsl/transmission.glsl's transmission_light: a light's radiance through the surface from behind
    it (n.l < 0) per unit irradiance E: the glass's weight, tint, Fresnel at h.v and GGX lobe, times
    the lobe's compensation (transmission.glass_compensation at the view); a sphere light (``light``
    a point or spot light with a radius) widens the lobe by its angular radius in the transmission
    lobe's half-vector space."""
    eta = np.broadcast_to(s.transmission_eta, np.shape(s.NoV))
    alpha = np.broadcast_to(s.alpha, np.shape(s.NoV))
    if light is not None and light.sphere_radius > 0.0:
        h = s.v + eta[..., None] * l
        theta = 2.0 * sphere_light_theta(light, s.p) * eta / np.sqrt(np.maximum(_dot(h, h), 1e-8))
        theta = np.minimum(theta, 0.25 * np.pi)  # (size_lobe_weights' cap)
        # the lobe widened in quadrature, at most 1 (Cycles' bsdf_microfacet_ggx_setup)
        lobe = _transmission_crossing(s, l, eta, np.minimum(np.sqrt(alpha * alpha + theta * theta), 1.0))
    else:
        lobe = _transmission_crossing(s, l, eta, alpha)
    weight = np.where((s.transmission_weight > 0.0) & (_dot(s.n, l) < 0.0) & (lobe > 0.0),
                      s.transmission_weight * lobe * factors[1], 0.0)
    tint = s.transmission_tint * np.ones(np.shape(s.NoV) + (3,))
    compensation = transmission.glass_compensation(s.roughness, s.NoV, eta, tint,
                                                   np.asarray(s.transmission_fresnel)[..., None])
    return tint * compensation * _rgb_scalar(weight) * E


def pbr_direct(s: Surface, l, E, factors, terms: Terms = DEFAULT_TERMS):
    NoL, NoL_pos, NoH, NxH, LoH = _light_geometry(s, l)
    LoV = _dot(l, s.v)
    if terms.principled:
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            diffuse, specular = principled_direct(s, NoL_pos, NoH, _dot(NxH, NxH), LoH, l)
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


def env_split_sum(s: Surface, terms: Terms):
    """ibl.glsl's env_split_sum: (E, B) of the program's D and V at the view (the Principled set:
    GGX with Smith); at the roughness floor a perfect mirror, E = 1, B = (1 - n.v)^5."""
    rough = np.broadcast_to(s.roughness, np.shape(s.NoV))
    table = M.split_sum_table(*terms.lobe)
    mirror = rough <= MIN_PERCEPTUAL_ROUGHNESS
    return (np.where(mirror, 1.0, M.interpolate(table[..., 0], s.NoV, rough)),
            np.where(mirror, (1.0 - s.NoV) ** 5, M.interpolate(table[..., 1], s.NoV, rough)))


def shade_uniform_environment(s: Surface, radiance, terms: Terms = DEFAULT_TERMS, weights=(1.0, 1.0),
                              ao=1.0, specular_ao=1.0):
    """model_pbr.glsl's shade_environment (principled.glsl's principled_environment for the
    Principled set) under a world of constant ``radiance`` (rgb): the prefiltered radiance is the
    radiance itself times the specular occlusion ``specular_ao``, the irradiance pi times it
    times the diffuse occlusion ``ao`` (split sum)."""
    L = np.asarray(radiance, np.float64) * _rgb_scalar(specular_ao)
    irradiance = np.pi * np.asarray(radiance, np.float64) * _rgb_scalar(ao)

    def surface_light(surface, w):
        prefiltered = L
        if surface.aniso is not None:  # the anisotropic lobe's samples of the constant
            levels = environment.PREFILTER_LEVELS  # (no suns split off a constant)
            prefiltered = anisotropic_prefiltered(surface, lambda l, rough: L, levels, terms)
        return shade_environment(surface, prefiltered, irradiance, terms, w)

    return _under_upper_layers(s, terms, weights, surface_light, lambda sheen: irradiance * INV_PI)


def shade_environment(s: Surface, prefiltered, irradiance, terms: Terms = DEFAULT_TERMS, weights=(1.0, 1.0),
                      sampled=None):
    """model_pbr.glsl's shade_environment (principled.glsl's principled_environment for the
    Principled set), occlusion applied by the caller: the split sum's specular, its lobe's albedo
    F0 (E - B) + F90 B (Karis 2013) times the ``prefiltered`` radiance; or (``sampled``, World
    Specular: Sampled) that lobe sampled against the world (``env_sampled_specular``); the
    diffuse lobe lit by the ``irradiance`` and weighted by what the split-sum lobe left."""
    E, B = env_split_sum(s, terms)
    base = s.base_color * (1.0 - s.metal3)
    if terms.principled:
        p = principled_layers(s)
        F0m = np.minimum(s.base_color, 1.0)
        metal = p.metal_M * (F0m * _rgb_scalar(E - B) + _rgb_scalar(B))
        # F82-tint's edge term at the view (principled.glsl's principled_environment)
        c6 = pow5(1.0 - s.NoV) * (1.0 - s.NoV)
        metal = np.maximum(metal - p.metal_M * p.metal_b * _rgb_scalar(s.NoV * c6 * E), 0.0)
        if "THIN_FILM" in LOBES and np.any(thin_film.on_metal(s.thin_film)):  # the film's at the view
            F0m = np.broadcast_to(F0m, np.shape(metal))
            film = p.metal_M * thin_film.metal(s.thin_film, F0m, p.metal_b, s.NoV) * _rgb_scalar(E)
            metal = np.where(thin_film.on_metal(s.thin_film)[..., None], film, metal)
        specular = (s.metal3 * metal + (1.0 - s.metal3) * p.albedo * s.reflection_tint) * prefiltered
        if sampled is not None:
            specular = np.broadcast_to(sampled, np.shape(specular))
        # the subsurface's share: its walk's reflectance over the Lambert base (principled_environment)
        walked = 1.0 + _rgb_scalar(s.subsurface) * (s.subsurface_walk - 1.0)
        diffuse = base * walked * _rgb_scalar(np.clip(1.0 - p.layer, 0.0, 1.0)) * irradiance * INV_PI
        diffuse = diffuse * _rgb_scalar(1.0 - s.transmission_share)  # (principled_environment)
        return diffuse * weights[0] + specular * weights[1]
    albedo = s.f0 * _rgb_scalar(E - B) + _rgb_scalar(s.f90 * B)
    specular = albedo * prefiltered if sampled is None else np.asarray(sampled, np.float64)
    if terms.multiscatter:
        # Fdez-Aguera 2019, eq. 16-18: light scattered more than once leaves as Fms Ems of the irradiance
        Ems = _rgb_scalar(1.0 - E)
        Favg = s.f0 + (1.0 - s.f0) / 21.0
        Fms_Ems = albedo * Favg * Ems / (1.0 - Ems * Favg)
        specular = specular + Fms_Ems * irradiance * INV_PI
        albedo = albedo + Fms_Ems
    if terms.diffuse == "LAYERED":
        weight = _rgb_scalar(np.clip(1.0 - principled_layers(s, terms).layer, 0.0, 1.0))
    else:
        weight = np.clip(1.0 - albedo, 0.0, 1.0)
    diffuse = base * weight * irradiance * INV_PI
    return diffuse * weights[0] + specular * weights[1]


def _under_upper_layers(s: Surface, terms: Terms, weights, surface_light, sheen_light):
    """model_pbr.glsl's shade_environment: ``surface_light(surface, weights)``, the world's light
    from a surface's own lobes, and in the Principled set under its upper layers (``upper_layers``:
    the base times what they leave it, the coat's own lobe, the sheen's colour times
    ``sheen_light(its lobe)``, the radiance it sees)."""
    c = surface_light(s, weights)
    upper = upper_layers(s) if terms.principled else None
    if upper is None:
        return c
    c = c * upper.below
    if upper.coat is not None:
        c = c + _rgb_scalar(upper.coat_weight) * surface_light(upper.coat, (0.0, weights[1]))
    if upper.sheen is not None:
        c = c + upper.sheen.color * sheen_light(upper.sheen) * weights[0]
    return c


def env_dominant_direction(n, r, alpha):
    """ibl.glsl's env_dominant_direction: where a GGX lobe's reflected energy peaks, off the
    mirror direction ``r`` towards the normal as the surface roughens (Lagarde & de Rousiers
    2014, listing 22)."""
    smoothness = (1.0 - np.asarray(alpha, np.float64))[..., None]
    d = n + (r - n) * (smoothness * (np.sqrt(smoothness) + (1.0 - smoothness)))
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def shade_image_environment(s: Surface, maps: environment.WorldMaps, terms: Terms = DEFAULT_TERMS,
                            samples: int = 0, diffuse: str = "MAP", weights=(1.0, 1.0), ao=1.0,
                            specular_ao=1.0, memo: dict | None = None, prefilter_samples: int | None = None):
    """model_pbr.glsl's shade_environment under an image world (``environment.world_maps``): the
    prefiltered radiance read in the lobe's dominant direction (the mirror direction at the
    roughness floor) or, with ``samples``, the lobe sampled (World Specular: Sampled); the
    irradiance from the map (``diffuse`` "MAP": the exact convolution of the 64 texels wide level,
    evaluated at n) or the nine spherical harmonics ("SH9"); the diffuse occlusion ``ao`` and the
    specular's ``specular_ao`` as the occlusion pass gives them. ``memo``: where the same points
    are shaded with several term sets, the irradiance and the prefiltered radiance (which depend
    on the points and the roughness alone) computed once; ``prefilter_samples``: the lobe samples
    of each prefiltered level (``environment.PREFILTER_SAMPLES`` if None)."""
    memo = {} if memo is None else memo

    def surface_light(surface, w):  # the coat's own split sum or samples: a memo of its own
        own = memo if surface is s else memo.setdefault(("coat",), {})
        return _image_environment(surface, maps, terms, samples, diffuse, w, ao, specular_ao, own,
                                  prefilter_samples)

    def sheen_light(sheen):
        def read(l, rough):
            return environment.prefiltered_radiance(maps.whole, maps.clamped, l, rough, maps.first_clamped,
                                                    prefilter_samples)

        return sheen_environment(sheen, read, sunless_roughness(maps.first_clamped)) * _rgb_scalar(ao)

    return _under_upper_layers(s, terms, weights, surface_light, sheen_light)


def _image_environment(s: Surface, maps: environment.WorldMaps, terms: Terms, samples: int, diffuse: str,
                       weights, ao, specular_ao, memo: dict, prefilter_samples: int | None):
    """shade_image_environment of the surface's own lobes."""
    if ("irradiance", diffuse) not in memo:
        if diffuse == "SH9":
            memo["irradiance", diffuse] = environment.sh9_irradiance(maps.sh, s.n)
        else:
            level = maps.level(environment.IRRADIANCE_WIDTH)
            memo["irradiance", diffuse] = environment.irradiance(level, s.n)
    irradiance = memo["irradiance", diffuse] * _rgb_scalar(ao)
    if samples:
        sampled = env_sampled_specular(s, maps.whole, maps.clamped, samples, maps.first_clamped, terms)
        return shade_environment(s, 0.0, irradiance, terms, weights, sampled * _rgb_scalar(specular_ao))
    if "prefiltered" not in memo and s.aniso is not None:  # the anisotropic lobe's samples
        def read(l, rough):
            return environment.prefiltered_radiance(maps.whole, maps.clamped, l, rough, maps.first_clamped,
                                                    prefilter_samples)

        memo["prefiltered"] = anisotropic_prefiltered(s, read, maps.first_clamped, terms)
    if "prefiltered" not in memo:
        d, rough = _split_sum_direction(s)
        memo["prefiltered"] = environment.prefiltered_radiance(maps.whole, maps.clamped, d, rough,
                                                               maps.first_clamped, prefilter_samples)
    return shade_environment(s, memo["prefiltered"] * _rgb_scalar(specular_ao), irradiance, terms, weights)


def _split_sum_direction(s: Surface):
    """Where the round split sum reads the prefiltered world (model_pbr.glsl's shade_environment_surface):
    the lobe's dominant direction, the mirror direction at the roughness floor; and its roughness."""
    r = 2.0 * s.NoV[..., None] * s.n - s.v
    rough = np.broadcast_to(s.roughness, np.shape(s.NoV))
    d = np.where((rough > MIN_PERCEPTUAL_ROUGHNESS)[..., None],
                 env_dominant_direction(s.n, r, np.broadcast_to(s.alpha, np.shape(s.NoV))), r)
    return d, rough


def anisotropic_environment(s: Surface, read, first_clamped: int):
    """anisotropy.glsl's anisotropic_environment: the lobe's albedo (the mean G2 / G1(v) over
    ``anisotropy.WORLD_ALBEDO`` of its visible normals) times the mean radiance it sees: ``read(l,
    roughness)``, the prefiltered world at each strip's (``anisotropy.strips``, ``strip_sample``) direction
    and footprint roughness, weighted by G2 / G1(v), kept on the side of the suns' split (levels from
    ``first_clamped`` on made without them) that the lobe's own roughness takes."""
    x, y, ax, ay = s.aniso
    suns = world_sun_specular(anisotropy.roughness(ax, ay), first_clamped)[..., None]
    levels = environment.PREFILTER_LEVELS

    def level_roughness(k):  # (ibl.glsl's env_level_roughness: level 0 at the roughness floor)
        return MIN_PERCEPTUAL_ROUGHNESS if k == 0 else environment.level_roughness(k)

    r0, r1 = level_roughness(max(first_clamped - 1, 0)), level_roughness(min(first_clamped, levels - 1))
    seen = anisotropy.view(s.n, s.v, s.NoV, x, y, ax, ay)
    shape = np.shape(s.NoV)
    count = np.broadcast_to(anisotropy.strips(ax, ay), shape)
    narrow = np.broadcast_to(np.minimum(ax, ay), shape)
    radiance = np.zeros(shape + (3,))
    weights = np.zeros(shape)
    for i in range(int(count.max(initial=1))):
        on = i < count
        l, pdf, _, weight = anisotropy.strip_sample(s.n, seen, s.NoV, x, y, ax, ay, np.minimum(i, count - 1),
                                                    count)
        weight = np.where(on, weight, 0.0)
        rough = anisotropy.sample_roughness(pdf, count, narrow)
        if first_clamped < levels:
            rough = np.minimum(rough, r0) + (np.maximum(rough, r1) - np.minimum(rough, r0)) * suns[..., 0]
        radiance += np.where((weight > 0.0)[..., None], read(l, rough) * _rgb_scalar(weight), 0.0)
        weights += weight
    albedo = sum(anisotropy.sample(s.n, s.v, s.NoV, x, y, ax, ay, k, anisotropy.WORLD_ALBEDO)[3]
                 for k in range(anisotropy.WORLD_ALBEDO)) / anisotropy.WORLD_ALBEDO
    # every strip's light under the horizon: none to weigh (as the GPU)
    mean = radiance / _rgb_scalar(np.where(weights > 0.0, weights, 1.0))
    return np.where((weights > 0.0)[..., None], mean * _rgb_scalar(albedo), 0.0)


def anisotropic_prefiltered(s: Surface, read, first_clamped: int, terms: Terms):
    """model_pbr.glsl's radiance for an anisotropic lobe: ``anisotropic_environment`` (its albedo times
    back; where the lobe is round (alpha_x = alpha_y: a coat, a pixel whose Anisotropic is 0), the round
    split sum's own read (``_split_sum_direction``), as model_pbr.glsl branches."""
    round_lobe = np.broadcast_to(s.aniso[2] == s.aniso[3], np.shape(s.NoV))
    d, rough = _split_sum_direction(s)
    if np.all(round_lobe):
        return np.broadcast_to(read(d, rough), np.shape(s.NoV) + (3,))
    E, _ = env_split_sum(s, terms)
    sampled = anisotropic_environment(s, read, first_clamped) / _rgb_scalar(np.maximum(E, 1e-4))
    if not np.any(round_lobe):
        return sampled
    return np.where(round_lobe[..., None], read(d, rough), sampled)


def env_sample_lobe(s: Surface, levels, samples: int, terms: Terms = DEFAULT_TERMS):
    """model_pbr.glsl's env_sample_lobe: the specular lobe's ``samples`` Hammersley half vectors
    about each point's normal (phi = 2 pi (i + 1/2) / N), each sample's light read from the
    chain ``levels`` at its filtered importance sampling level (``environment.chain_lod``, no
    bias), weighted by f cos / pdf = F V 4 (v.h)(n.l) / (n.h); at the roughness floor the mirror
    direction read from the chain's widest level, times F at n.v."""
    if s.aniso is not None:  # the anisotropic lobe by its visible normals: f cos / pdf = F G2 / G1(v)
        total = np.zeros(np.shape(s.NoV) + (3,))
        for i in range(samples):
            l, pdf, VoH, weight = anisotropy.sample(s.n, s.v, s.NoV, *s.aniso, i, samples)
            on = weight > 0.0
            lod = environment.chain_lod(np.where(on, pdf, 1.0), samples, levels[0].shape[1], 0.0)
            L = environment.chain_lookup(levels, l, np.where(on, lod, 0.0))
            F = principled_specular_tint(s, VoH)
            total += np.where(on[..., None], L * F * _rgb_scalar(weight), 0.0)
        return total / samples
    rough = np.broadcast_to(s.roughness, np.shape(s.NoV))
    alpha = np.broadcast_to(s.alpha, np.shape(s.NoV))
    lobe_terms = DEFAULT_TERMS if terms.principled else terms
    r = 2.0 * s.NoV[..., None] * s.n - s.v
    if terms.principled:
        mirror = principled_specular_tint(s, s.NoV)
    else:
        mirror = pbr_fresnel(s, s.NoV, terms)
    mirror = mirror * environment.level_lookup(levels[0], environment.equirect_uv(r))
    tx, ty = environment.tangent_frame(s.n)
    a2 = (alpha * alpha)[..., None]
    total = np.zeros(np.shape(s.NoV) + (3,))
    xi = environment.radical_inverse(np.arange(samples))
    for i in range(samples):
        phi = 2.0 * np.pi * (i + 0.5) / samples
        if lobe_terms.ndf == "BECKMANN":
            cos_t = 1.0 / np.sqrt(1.0 - a2[..., 0] * math.log(max(1.0 - xi[i], 1e-12)))
        else:
            cos_t = np.sqrt((1.0 - xi[i]) / (1.0 + (a2[..., 0] - 1.0) * xi[i]))
        sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
        h = (tx * (sin_t * math.cos(phi))[..., None] + ty * (sin_t * math.sin(phi))[..., None]
             + s.n * cos_t[..., None])
        VoH = _dot(s.v, h)
        l = 2.0 * VoH[..., None] * h - s.v
        NoL = _dot(s.n, l)
        on = (VoH > 0.0) & (NoL > 0.0)
        NoH = np.maximum(cos_t, MIN_COS)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            D = pbr_distribution(NoH, sin_t * sin_t, alpha, lobe_terms)
            pdf = D * NoH / (4.0 * VoH)
            lod = environment.chain_lod(np.where(on, pdf, 1.0), samples, levels[0].shape[1], 0.0)
            L = environment.chain_lookup(levels, l, np.where(on, lod, 0.0))
            if terms.principled:
                F = principled_specular_tint(s, VoH)
                V = V_SmithGGXCorrelated(s.NoV, NoL, alpha)
            else:
                F = pbr_fresnel(s, VoH, terms)
                V = pbr_visibility(s.NoV, NoL, NoH, VoH, alpha, terms)
            weight = V * 4.0 * VoH * NoL / NoH
        total += np.where(on[..., None], L * F * np.where(on, weight, 0.0)[..., None], 0.0)
    total /= samples
    if not terms.principled:
        total = total * specular_energy_compensation(s, terms)
    return np.where((rough <= MIN_PERCEPTUAL_ROUGHNESS)[..., None], mirror, total)


def world_sun_specular(roughness, first_clamped: int):
    """ibl.glsl's world_sun_specular: the suns' specular weight, 0 up to the last level made from
    the whole world, 1 from the first made from the clamped one, linear in roughness between."""
    if first_clamped >= environment.PREFILTER_LEVELS:
        return np.ones(np.shape(roughness))
    r0 = MIN_PERCEPTUAL_ROUGHNESS if first_clamped == 1 else environment.level_roughness(first_clamped - 1)
    r1 = environment.level_roughness(first_clamped)
    return np.clip((np.asarray(roughness, np.float64) - r0) / (r1 - r0), 0.0, 1.0)


def env_sampled_specular(s: Surface, whole, clamped, samples: int, first_clamped: int,
                         terms: Terms = DEFAULT_TERMS):
    """model_pbr.glsl's env_sampled_specular: the lobe sampled against the whole world's chain
    for smooth surfaces, against the clamped one (the suns lit as lights) for rough ones,
    mixed as the split-sum levels are (``world_sun_specular``)."""
    t = np.broadcast_to(world_sun_specular(s.roughness, first_clamped), np.shape(s.NoV))[..., None]
    out = np.zeros(np.shape(s.NoV) + (3,))
    if np.any(t < 1.0):
        out = out + (1.0 - t) * env_sample_lobe(s, whole, samples, terms)
    if np.any(t > 0.0):
        out = out + t * env_sample_lobe(s, clamped, samples, terms)
    return out


MODELS = {
    "BLINN_PHONG": (blinn_phong_direct, True),
    "PHONG": (phong_direct, True),
    "PBR": (pbr_direct, False),
}


def ltc_frame(s: Surface, terms: Terms):
    """(x, y, z, entries): the shading frame (x the tangent towards v, z = n) and the LTC's M^-1
    entries at the view, for the program's distribution (surface.glsl's LtcFrame, ltc_frame_at)."""
    x, y, z, _ = ltc.shading_frame(s.n, s.v)
    entries = ltc.lookup(ltc.ltc_table(terms.lobe[0]), s.NoV, np.broadcast_to(s.roughness, np.shape(s.NoV)))
    return x, y, z, entries


def shade_polygon_light(s: Surface, offsets, to_centre, L, form_factor, l, factors, terms: Terms,
                        ltc_jitter=None, specular_scale=1.0, memo: dict | None = None, memo_key=None,
                        sheen: dict | None = None):
    """light_shading.glsl's shade_polygon_light: a light of radiance ``L`` (rgb, as it arrives)
    over the polygon of corners ``offsets`` about its centre at ``to_centre`` from the points, of
    unclipped form factor ``form_factor``, on the physically based model: the diffuse lobe from
    the horizon-clipped irradiance, the specular from the linearly transformed cosine's integral
    over the polygon (addon/reference/ltc.py). ``ltc_jitter``: ltc.ltc_integral's, for tests. ``memo``
    (with ``memo_key`` naming the polygon): where the same points are shaded with several term
    sets, what depends on the points, the polygon and the distribution alone is computed once.
    ``sheen`` (the Principled set's, ``upper_layers``): its ``"lobe"`` integrated over the polygon into
    ``"value"`` where lit, NaN elsewhere (light_shading.glsl's sheen_polygon_light)."""
    L = np.asarray(L, np.float64)
    lit = (L.max(axis=-1) > 0.0) & (form_factor > 0.0)
    if sheen is not None:
        lobe = sheen["lobe"]
        corners = np.asarray(to_centre)[..., None, :] + offsets
        axes = (lobe.x_axis, lobe.y_axis, lobe.n)
        local = np.stack([np.sum(corners * a[..., None, :], axis=-1) for a in axes], axis=-1)
        integral = ltc.ltc_integral(lobe.m, local, jitter=ltc_jitter)
        sheen["value"] = np.where(lit[..., None], lobe.color * L * (integral * factors[0])[..., None], np.nan)
    key = None if memo is None or memo_key is None or ltc_jitter is not None else (memo_key, terms.lobe[0])
    geometry = memo.get(key) if key is not None else None
    if geometry is None:
        with np.errstate(divide="ignore", invalid="ignore"):
            NoL = _dot(s.n, l)
            clipped = ltc.sphere_lookup(ltc.sphere_table(), np.minimum(form_factor, 1.0), NoL)
            clipped = np.where(NoL > 0.0, np.pi * clipped / np.where(NoL > 0.0, NoL, 1.0), 0.0)
        x, y, z, entries = ltc_frame(s, terms)
        corners = np.asarray(to_centre)[..., None, :] + offsets
        local = np.stack([np.sum(corners * a[..., None, :], axis=-1) for a in (x, y, z)], axis=-1)
        form_factor_lobe, length = ltc.ltc_integral(entries, local, jitter=ltc_jitter, with_length=True)
        LoH = saturate(_dot(l, half_vector(l, s.v, s.n)))
        l_local = np.stack([_dot(l, x), _dot(l, y), _dot(l, z)], axis=-1)
        density = ltc.ltc_density(ltc.minv_from_entries(entries), l_local,
                                  ltc.density_floor(form_factor_lobe, length))
        geometry = (clipped, form_factor_lobe, LoH, density)
        if key is not None:
            memo[key] = geometry
    clipped, form_factor_lobe, LoH, density = geometry
    diffuse = pbr_direct(s, l, L * clipped[..., None], (factors[0], 0.0), terms)
    rough = np.broadcast_to(s.roughness, np.shape(s.NoV))
    albedo = M.interpolate(M.albedo_table(*terms.lobe), s.NoV, rough)
    lobe = ltc.lobe_integral(form_factor_lobe, albedo, pbr_lobe(s, l, terms), density)
    lobe = np.where(form_factor_lobe > 0.0, lobe, 0.0)
    if s.aniso is not None:  # by its visible normals over the polygon (anisotropy.glsl)
        with np.errstate(divide="ignore", invalid="ignore"):
            lobe = anisotropy.polygon_integral(s.n, s.v, s.NoV, *s.aniso, offsets, to_centre, ltc_jitter)
    specular = pbr_specular_tint(s, LoH, terms) * L * (lobe * factors[1] * specular_scale)[..., None]
    return np.where(lit[..., None], diffuse + specular, 0.0)


def shade_area_light(s: Surface, light: Light, E, l, visibility, terms: Terms, ltc_jitter=None,
                     memo: dict | None = None, sheen: dict | None = None):
    """light_shading.glsl's shade_area_light: an area light's polygon of radiance I / A
    (shade_polygon_light); the point emitter in its far field."""
    factors = (light.diffuse_factor, light.specular_factor)
    to_centre = np.asarray(light.position, np.float64) - s.p
    window = light_window(light, s.p)
    spread, offsets, clipped, lobe_spread = 1.0, area_offsets(light), to_centre, 1.0
    if light.spread_terms[1] > 0.0:
        x, y, z, entries = ltc_frame(s, terms)
        spread, offsets, clipped, lobe_spread = area_spread(
            light, to_centre, (ltc.minv_from_entries(entries), x, y, z))
    with np.errstate(divide="ignore", invalid="ignore"):
        specular_scale = np.where(spread > 0.0, lobe_spread / np.where(spread > 0.0, spread, 1.0), 0.0)
    L = np.asarray(light.intensity, np.float64) * (spread * np.asarray(visibility) * window
                                                    / max(area_light_area(light), 1e-12))[..., None]
    L_max, E_max = L.max(axis=-1), np.asarray(E).max(axis=-1)
    lit = (L_max > 0.0) & (E_max > 0.0)
    form_factor = np.where(lit, E_max / (np.pi * np.where(lit, L_max, 1.0)), 0.0)
    polygon = None if light.spread_terms[1] > 0.0 else ("area", id(light))  # spread: its own frame
    out = shade_polygon_light(s, offsets, clipped, L, form_factor, l, factors, terms, ltc_jitter,
                              specular_scale, memo, polygon, sheen)
    far = area_far_field(light, _dot(to_centre, to_centre))
    if sheen is not None:  # the far field: a point emitter, the sheen at its direction
        sheen["value"] = np.where(far[..., None], np.nan, sheen["value"])
    return np.where(far[..., None], pbr_direct(s, l, E, factors, terms), out)


def shade_sphere_light(s: Surface, light: Light, E, l, terms: Terms, ltc_jitter=None, k=None,
                       memo: dict | None = None, sheen: dict | None = None):
    """light_shading.glsl's shade_sphere_light: radiance I / (pi r^2) over the sphere light's disc
    (sphere_offsets), L = E (d^2 [+ r^2]) / (pi r^2), form factor r^2 / (d^2 [+ r^2])."""
    to_centre = np.asarray(light.position, np.float64) - s.p
    r2 = light.sphere_radius ** 2
    falloff = _dot(to_centre, to_centre) + (r2 if light.soft_falloff else 0.0)
    L = np.asarray(E, np.float64) * (np.maximum(falloff, MIN_DIST2) / (np.pi * r2))[..., None]
    factors = (light.diffuse_factor, light.specular_factor)
    fine = np.ones(np.shape(s.NoV), bool) if k is None else np.asarray(k) > SPHERE_FINE_K
    out = 0.0
    polygon_sheen = np.full(np.shape(s.NoV) + (3,), np.nan)
    for sides, use in ((AREA_ELLIPSE_SIDES, fine), (SPHERE_COARSE_SIDES, ~fine)):
        if np.any(use):
            c = shade_polygon_light(s, sphere_offsets(light, s.p, sides), to_centre, L,
                                    r2 / np.maximum(falloff, 1e-30), l, factors, terms, ltc_jitter,
                                    memo=memo, memo_key=("sphere", id(light), sides), sheen=sheen)
            out = out + np.where(use[..., None], c, 0.0)
            if sheen is not None:
                polygon_sheen = np.where(use[..., None], sheen["value"], polygon_sheen)
    # at the centre: no direction to the light (E_Point's l = 0), no light
    centre = (_dot(to_centre, to_centre) > 0.0)[..., None]
    if sheen is not None:
        sheen["value"] = np.where(centre, polygon_sheen, np.nan)
    return np.where(centre, out, 0.0)


def shade_light(model: str, s: Surface, light: Light, E, l, terms: Terms = DEFAULT_TERMS,
                visibility=1.0, ltc_jitter=None, memo: dict | None = None):
    """One light's reflected radiance (rgb, before the model's final clamp) from its irradiance
    ``E`` and direction ``l`` (``light_irradiance``, times ``visibility``, the light's shadow
    factor): the body of mesh.frag.glsl's light loop (light_shading.glsl's shade_light): the
    surface's, and in the Principled set the Principled BSDF's upper layers (``upper_layers``).
    ``ltc_jitter``: for tests (ltc.ltc_integral)."""
    upper = upper_layers(s) if model == "PBR" and terms.principled else None
    sheen = None if upper is None or upper.sheen is None else {"lobe": upper.sheen, "value": None}
    c = shade_light_surface(model, s, light, E, l, terms, visibility, ltc_jitter, memo, sheen)
    if model == "PBR" and terms.principled:
        # the subsurface's share of the base at the light's direction; the translucent lobe beside the
        # layers, lit from behind (light_shading.glsl)
        with np.errstate(invalid="ignore"):
            c = c + subsurface_direct(s, l, *subsurface_light_shape(light, s.p)) * E * light.diffuse_factor
        c = c + transmission_light(s, l, E, (light.diffuse_factor, light.specular_factor), light)
        translucent = subsurface.translucent_direct(s.translucent, s.n, l) * E * light.diffuse_factor
        if upper is None:
            return c + translucent
    if upper is None:
        return c
    c = c * upper.below
    if upper.coat is not None:  # its specular lobe by the light's own path (memo: the base's polygons)
        coat_light = dataclasses.replace(light, diffuse_factor=0.0)
        coat = shade_light_surface(model, upper.coat, coat_light, E, l, terms, visibility, ltc_jitter)
        c = c + _rgb_scalar(upper.coat_weight) * coat
    if upper.sheen is not None:  # over the polygon where one was shaded, else at the light's direction
        at_l = sheen_direct(upper.sheen, l) * E * light.diffuse_factor
        polygon = sheen["value"]
        c = c + (at_l if polygon is None else np.where(np.isnan(polygon), at_l, polygon))
    return c + translucent


def shade_light_surface(model: str, s: Surface, light: Light, E, l, terms: Terms = DEFAULT_TERMS,
                        visibility=1.0, ltc_jitter=None, memo: dict | None = None, sheen: dict | None = None):
    """light_shading.glsl's shade_light_surface: one light's radiance from the surface's own lobes;
    ``sheen``: shade_polygon_light's, where a polygon is shaded."""
    direct, _ = MODELS[model]
    area = light.kind == "AREA" and light.half_size[0] > 0.0
    if model == "PBR" and area:
        return shade_area_light(s, light, E, l, visibility, terms, ltc_jitter, memo, sheen)
    if model == "PBR" and light.sphere_radius > 0.0:
        # by the LTC over its disc where it is large against the lobe, by its nearest point and the
        # lobe widened by it where small, blended between (light_shading.glsl's shade_light)
        to_light = np.asarray(light.position, np.float64) - s.p
        near = ~sphere_far_field(light, _dot(to_light, to_light))
        narrow = s.alpha if s.aniso is None else np.minimum(s.aniso[2], s.aniso[3])  # (light_shading.glsl)
        k = sphere_light_theta(light, s.p) / np.maximum(narrow, 1e-12)
        share = np.where(near, np.clip((k - SPHERE_LTC_FROM) / (SPHERE_LTC_FULL - SPHERE_LTC_FROM), 0.0, 1.0),
                         0.0)
        if np.any(share > 0.0):
            polygon = shade_sphere_light(s, light, E, l, terms, ltc_jitter, k, memo, sheen)
            if sheen is not None:  # only where the polygon is shaded (light_shading.glsl)
                sheen["value"] = np.where((share > 0.0)[..., None], sheen["value"], np.nan)
        n_r = s.n if s.aniso is None else anisotropy.bent_normal(s.n, s.v, *s.aniso, s.roughness)
        r_dir = 2.0 * _dot(n_r, s.v)[..., None] * n_r - s.v
        l_specular, alpha_wide, wide_weight, point_weight = sphere_light_specular(light, s.p, r_dir, s.alpha)
        wide = copy.copy(s)
        wide.alpha = alpha_wide
        if s.aniso is not None:  # each axis widened alike (anisotropy.glsl's anisotropic_widened)
            wide.aniso = (*s.aniso[:2], *anisotropy.widened(s.aniso[2], s.aniso[3], s.alpha, alpha_wide))
        specular = (0.0, light.specular_factor)
        far = (direct(s, l, E, (light.diffuse_factor, 0.0), terms)
               + direct(wide, l, E * np.asarray(wide_weight)[..., None], specular, terms)
               + direct(s, l_specular, E * np.asarray(point_weight)[..., None], specular, terms))
        if not np.any(share > 0.0):
            return far
        share = np.asarray(share)[..., None]
        return np.where(share >= 1.0, polygon, far + (np.where(share > 0.0, polygon, 0.0) - far) * share)
    return direct(s, l, E, (light.diffuse_factor, light.specular_factor), terms)


def shade(model: str, s: Surface, lights: list[Light], ambient: float = 0.0,
          terms: Terms = DEFAULT_TERMS, irradiance: list | None = None, memo: dict | None = None):
    """Outgoing radiance (rgb) at every point of ``s``: the twin of mesh.frag.glsl's main().
    Where the caller shades the same points with several term sets: ``irradiance``, each light's
    ``light_irradiance`` at ``s.p`` (it depends on the light and the points alone), and ``memo``,
    a dict that keeps the area and sphere lights' lobe geometry between the calls."""
    ldr = MODELS[model][1]
    c = np.zeros(np.shape(s.p), np.float64)
    upper = upper_layers(s) if model == "PBR" and terms.principled else None
    c = c + s.emission * (1.0 if upper is None else upper.below)  # under the sheen and the coat
    if ldr:
        c = c + s.ambient_color * ambient  # eq. 1.4
    for k, light in enumerate(lights):
        E, l = light_irradiance(light, s.p) if irradiance is None else irradiance[k]
        c = c + shade_light(model, s, light, E, l, terms, memo=memo)
    return np.clip(c, 0.0, 1.0) if ldr else c
