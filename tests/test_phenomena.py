"""Two of the seed's phenomena (section 2.4), measured on renders.

Fresnel: a plane seen at angle theta with a sun in the mirror direction, so h = n and l.h = cos
theta at every pixel. The Fresnel factor is measured as the ratio of a black dielectric (F0 0.04,
specular only) to a white metal (F = 1) in the same geometry: D, G and the light cancel, leaving
F(theta), which must follow Schlick's eq. 1.11. Blinn-Phong's highlight stays the same at every
angle: it has no Fresnel term.

HDR: a 2000 W and a 2 W light over one plane. PBR keeps radiance far above 1 and the weak
light's contribution intact under the strong one; Blinn-Phong clamps to [0, 1] and loses it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scenes

ANGLES = (0.0, 40.0, 60.0, 75.0, 85.0)


def _mirror_scene(theta_deg: float, model: str, **material):
    theta = math.radians(theta_deg)
    scene = scenes.reset(size=16)
    scene.shading_lab.model = model
    scene.shading_lab.ambient = 0.0
    scenes.ortho_camera(scene, location=(0.0, -5.0 * math.sin(theta), 5.0 * math.cos(theta)),
                        rotation=(theta, 0.0, 0.0), scale=0.5)
    scenes.plane(scene, size=200.0, material=scenes.material(**material))
    scenes.light(scene, "SUN", energy=2.0, rotation=(-theta, 0.0, 0.0))
    return scene


def _mean(scene, path) -> float:
    return float(scenes.render(scene, path)[..., :3].mean())


def test_fresnel_follows_schlick_and_blinn_phong_has_none(tmp_path):
    f0 = 0.04
    measured, schlick, blinn = [], [], []
    for theta in ANGLES:
        dielectric = _mean(_mirror_scene(theta, "PBR", base_color=(0, 0, 0), metalness=0.0, f0=f0,
                                         roughness=0.3), tmp_path / f"d{theta}.exr")
        mirror = _mean(_mirror_scene(theta, "PBR", base_color=(1, 1, 1), metalness=1.0, roughness=0.3),
                       tmp_path / f"m{theta}.exr")
        measured.append(dielectric / mirror)
        schlick.append(f0 + (1 - f0) * (1 - math.cos(math.radians(theta))) ** 5)
        blinn.append(_mean(_mirror_scene(theta, "BLINN_PHONG", base_color=(0, 0, 0), shininess=50.0,
                                         specular_color=(0.2, 0.2, 0.2)), tmp_path / f"b{theta}.exr"))
    measured, schlick, blinn = map(np.asarray, (measured, schlick, blinn))
    print("theta", ANGLES, "\nmeasured F", measured.round(4), "\nSchlick F ", schlick.round(4),
          "\nBlinn-Phong", blinn.round(4))
    err = np.abs(measured / schlick - 1.0)
    print("relative error", err, "Blinn-Phong", np.abs(blinn / (0.2 * 2.0 / math.pi) - 1.0))
    assert err.max() < 2e-6, f"F against Schlick: relative error {err.max():.2e} (measured <= 5.7e-7)"
    assert measured[-1] / measured[0] > 10.0  # the Fresnel effect: >10x brighter at 85 degrees
    # Blinn-Phong: the same highlight at every angle (c_spec * E / pi with n.h = 1)
    blinn_err = np.abs(blinn / (0.2 * 2.0 / math.pi) - 1.0).max()
    assert blinn_err < 5e-7, f"Blinn-Phong's highlight: relative error {blinn_err:.2e} (measured 1.2e-7)"


def _hdr_scene(model: str, weak: bool):
    """A 2000 W and a 2 W light over a plane. Light Threshold 0: the test is about the weak light's
    exact contribution next to a strong one, and at the default threshold the 2 W light would reach
    only 4 m, fading from well before (tests/test_light_tiles.py tests that fade)."""
    scene = scenes.reset(size=64)
    scene.shading_lab.model = model
    scene.shading_lab.ambient = 0.0
    scene.shading_lab.light_threshold = 0.0
    scenes.ortho_camera(scene, scale=4.0)
    scenes.plane(scene, size=4.0, material=scenes.material(base_color=(0.8, 0.8, 0.8), f0=0.0))
    scenes.light(scene, "POINT", energy=2000.0, location=(-1.0, 0.0, 1.0))
    if weak:
        scenes.light(scene, "POINT", energy=2.0, location=(1.0, 0.0, 1.0))
    return scene


@pytest.mark.parametrize("model", ["PBR", "BLINN_PHONG"])
def test_hdr_range(model, tmp_path):
    both = scenes.render(_hdr_scene(model, weak=True), tmp_path / "both.exr")[..., 0].astype(np.float64)
    strong = scenes.render(_hdr_scene(model, weak=False), tmp_path / "strong.exr")[..., 0].astype(np.float64)
    weak_part = both - strong
    # pixel under the weak light: x = +1, y = 0 -> column 48, rows 31/32 straddle y = 0
    centres = (np.arange(64) + 0.5) / 64 * 4.0 - 2.0
    x, y = np.meshgrid(centres, -centres)

    def lambert(power, light_x):  # rho / pi * I / d^2 * cos, I = P / 4 pi, the light 1 m up
        d2 = (x - light_x) ** 2 + y ** 2 + 1.0
        return 0.8 / math.pi * (power / (4 * math.pi)) / d2 / np.sqrt(d2)

    if model == "PBR":
        assert both.max() > 30.0, "HDR: the strong light's peak must stay far above 1"
        np.testing.assert_allclose(strong, lambert(2000.0, -1.0), rtol=2e-3)
        np.testing.assert_allclose(weak_part, lambert(2.0, 1.0), rtol=2e-3, atol=2e-4)
    else:
        assert both.max() <= 1.0 and strong.max() <= 1.0
        saturated = strong >= 1.0
        assert saturated.mean() > 0.3, "the strong light must saturate much of the LDR frame"
        assert np.all(weak_part[saturated] == 0.0), "clamped pixels lose the weak light entirely"


def test_f90_and_fresnel_p_shape_the_generalised_schlick(tmp_path):
    """The material's F90 and Fresnel p (Fresnel: generalised Schlick, eq. 1.13): F = F0 +
    (F90 - F0) (1 - cos theta)^(1/p), set away from their defaults (1, 0.2) and measured at 60
    and 80 degrees."""
    for theta in (60.0, 80.0):
        scene_material = dict(base_color=(0, 0, 0), metalness=0.0, f0=0.04, f90=0.6, fresnel_p=0.35,
                              roughness=0.3)
        scene = _mirror_scene(theta, "PBR", **scene_material)
        assert (scene.objects["Plane"].active_material.shading_lab.f90,
                scene.objects["Plane"].active_material.shading_lab.fresnel_p) == pytest.approx((0.6, 0.35))
        import bpy

        bpy.context.scene.shading_lab.fresnel = "SCHLICK_GENERAL"
        got = _fresnel_ratio_scene(scene, theta, tmp_path)
        want = 0.04 + (0.6 - 0.04) * (1.0 - math.cos(math.radians(theta))) ** (1.0 / 0.35)
        default = 0.04 + 0.96 * (1.0 - math.cos(math.radians(theta))) ** 5
        err = float(np.abs(got / want - 1.0).max())
        print(f"{theta} degrees: F {got.round(6)}, eq. 1.13 {want:.6f} (defaults' {default:.6f}), "
              f"relative {err:.1e}")
        assert err < 2e-6, f"{theta}: relative error {err:.1e} against eq. 1.13 (measured <= 3.8e-7)"
        assert abs(want / default - 1.0) > 0.1, "the settings change F here"


def _fresnel_ratio_scene(scene, theta_deg, tmp_path) -> np.ndarray:
    measured = scenes.render(scene, tmp_path / "material.exr")[..., :3].astype(np.float64).mean(axis=(0, 1))
    white_metal = _mirror_scene(theta_deg, "PBR", base_color=(1, 1, 1), metalness=1.0, roughness=0.3)
    mirror = scenes.render(white_metal, tmp_path / "mirror.exr")[..., :3].astype(np.float64).mean(axis=(0, 1))
    return measured / mirror


def _conductor_fresnel(n, k, theta):
    """Unpolarised reflectance of a conductor of complex index n + ik at incidence theta, from the
    Fresnel equations in complex arithmetic (not the engine's real-valued rewriting)."""
    eta = complex(n, k)
    c = math.cos(theta)
    s2 = 1.0 - c * c
    t = np.sqrt(eta * eta - s2 + 0j)  # eta cos theta_t
    rs = (c - t) / (c + t)
    rp = (eta * eta * c - t) / (eta * eta * c + t)
    return 0.5 * (abs(rs) ** 2 + abs(rp) ** 2)


def test_complex_ior_sets_a_metals_exact_fresnel(tmp_path):
    """Fresnel: Exact on a metal reads the material's IOR n and k (complex index per channel): F
    at 0 and 70 degrees equals the Fresnel equations for n + ik, here a copper-like n, k set away
    from the defaults."""
    import bpy

    n, k = (0.27, 0.68, 1.22), (3.61, 2.63, 2.29)
    for theta in (0.0, 70.0):
        scene = _mirror_scene(theta, "PBR", base_color=(1, 1, 1), metalness=1.0, ior_n=n, ior_k=k,
                              roughness=0.3)
        bpy.context.scene.shading_lab.fresnel = "EXACT"
        material = scene.objects["Plane"].active_material.shading_lab
        material.use_complex_ior = True  # the override that turns n and k on
        assert tuple(material.ior_n) == pytest.approx(n) and tuple(material.ior_k) == pytest.approx(k)
        got = _fresnel_ratio_scene(scene, theta, tmp_path)
        want = np.array([_conductor_fresnel(a, b, math.radians(theta)) for a, b in zip(n, k)])
        err = float(np.abs(got / want - 1.0).max())
        print(f"{theta} degrees: F {got.round(6)}, Fresnel's equations {want.round(6)}, relative {err:.1e}")
        assert err < 7e-7, f"{theta}: relative error {err:.1e} (measured <= 1.4e-7)"
