"""Every pixel of a GPU render against a closed form written here, for all three models.

An orthographic camera looks straight down at a tilted plane lit by one point light. For each
pixel centre the test intersects the camera ray with the plane and evaluates the seed's
equations directly (eq. 1.7 for Blinn-Phong, 1.2-1.3 for Phong, 1.10 + 1.11 + 1.15-1.18 for PBR,
lights as SPEC section 4 states), in float64, in the textbook form of each equation: not the
rearranged forms the shaders use, and without calling the package.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scenes

SIZE = 64
SCALE = 2.0
TILT = (math.radians(25.0), math.radians(-10.0), 0.0)
LIGHT_POS = np.array([0.3, -0.2, 1.1])
LIGHT_POWER = {"BLINN_PHONG": 30.0, "PHONG": 30.0, "PBR": 300.0}  # W; PBR reaches HDR
LIGHT_COLOR = np.array([1.0, 0.9, 0.8])
BASE = np.array([0.6, 0.3, 0.2])
SPEC = np.array([0.5, 0.45, 0.4])
AMBIENT_COLOR = np.array([0.1, 0.2, 0.3])
ROUGHNESS = 0.4
SHININESS = 20.0
AMBIENT_X = 0.1
F0 = 0.04


def _geometry(power: float):
    cam = np.eye(4)
    cam[:3, 3] = (0.0, 0.0, 5.0)
    origins, direction = scenes.ortho_pixel_rays(SIZE, SCALE, cam)
    normal = scenes.euler_matrix(TILT) @ np.array([0.0, 0.0, 1.0])
    p = scenes.intersect_plane(origins, direction, np.zeros(3), normal)
    v = -direction
    d = LIGHT_POS - p
    dist2 = np.sum(d * d, axis=-1)
    l = d / np.sqrt(dist2)[..., None]
    intensity = power / (4.0 * math.pi) * LIGHT_COLOR  # W/sr
    E = intensity / dist2[..., None]  # W/m^2 on a surface facing the light
    n = np.broadcast_to(normal, p.shape)
    return n, v, l, E


def _dot(a, b):
    return np.sum(a * b, axis=-1)


def expected(model: str) -> np.ndarray:
    n, v, l, E = _geometry(LIGHT_POWER[model])
    NoL = _dot(n, l)
    lit = (NoL > 0)[..., None]
    NoL = np.maximum(NoL, 0.0)
    if model in ("BLINN_PHONG", "PHONG"):
        c_light = E / math.pi  # the seed's c_PL: radiance of a white Lambertian facing the light
        if model == "BLINN_PHONG":
            h = (l + v) / np.linalg.norm(l + v, axis=-1, keepdims=True)  # eq. 1.6
            spec = np.maximum(_dot(h, n), 0.0) ** SHININESS  # eq. 1.7
        else:
            r = 2.0 * _dot(n, l)[..., None] * n - l  # eq. 1.3
            spec = np.maximum(_dot(r, v), 0.0) ** SHININESS  # eq. 1.2
        c = AMBIENT_COLOR * AMBIENT_X + np.where(
            lit, BASE * c_light * NoL[..., None] + SPEC * c_light * spec[..., None], 0.0)
        return np.clip(c, 0.0, 1.0)
    # PBR
    alpha = ROUGHNESS ** 2
    h = (l + v) / np.linalg.norm(l + v, axis=-1, keepdims=True)
    NoH, NoV = _dot(n, h), _dot(n, v)
    F = F0 + (1.0 - F0) * (1.0 - _dot(h, l)) ** 5  # eq. 1.11 on h.l
    D = alpha ** 2 / (math.pi * (1.0 + NoH ** 2 * (alpha ** 2 - 1.0)) ** 2)  # eq. 1.15

    def Lambda(cos):  # eq. 1.17 with a = cos / (alpha sin)
        a = cos / (alpha * np.sqrt(1.0 - cos ** 2))
        return (-1.0 + np.sqrt(1.0 + 1.0 / a ** 2)) / 2.0

    G = 1.0 / (1.0 + Lambda(NoV) + Lambda(NoL))  # eq. 1.16
    f_spec = F * G * D / (4.0 * NoV * NoL)  # eq. 1.10
    f_diff = (1.0 - F)[..., None] * BASE / math.pi  # eq. 1.18
    f = f_diff + f_spec[..., None]
    return np.where(lit, f * E * NoL[..., None], 0.0)


@pytest.mark.parametrize("model", ["BLINN_PHONG", "PHONG", "PBR"])
def test_every_pixel_matches_closed_form(model, tmp_path):
    scene = scenes.reset(size=SIZE)
    scene.shading_lab.model = model
    scene.shading_lab.ambient = AMBIENT_X
    scenes.ortho_camera(scene, scale=SCALE)
    mat = scenes.material(base_color=BASE, roughness=ROUGHNESS, metalness=0.0, f0=F0,
                          shininess=SHININESS, specular_color=SPEC, ambient_color=AMBIENT_COLOR)
    scenes.plane(scene, size=8.0, rotation=TILT, material=mat)
    scenes.light(scene, "POINT", energy=LIGHT_POWER[model], location=LIGHT_POS, color=LIGHT_COLOR)

    got = scenes.render(scene, tmp_path / f"{model}.exr")[..., :3].astype(np.float64)
    want = expected(model)

    assert want.max() > 0.05, "the closed-form scene must be lit"
    if model != "PBR":
        assert (want < 1.0).mean() > 0.5, "most pixels must be unclamped for the test to mean anything"
    else:
        assert want.max() > 1.0, "PBR must reach HDR values in this scene"
    np.testing.assert_allclose(got, want, rtol=1e-3, atol=1e-5)
