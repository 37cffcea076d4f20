"""Colour management (SPEC section 5): with the engine's own tone mappers, Combined holds the
display-linear tone-curve output, a Radiance pass keeps the HDR data, and Blender's Standard view
transform encodes it; the saved PNG equals the formula applied to the raw radiance within 1/255.
The formulas here are written from the papers, independently of addon/reference/tonemap.py."""

from __future__ import annotations

import math

import bpy
import numpy as np
import pytest
import scenes

from addon.reference import tonemap


def srgb_encode(x):  # IEC 61966-2-1
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def srgb_decode(c):
    return np.where(c <= 0.04045, c / 12.92, np.power((c + 0.055) / 1.055, 2.4))


def reinhard(x):  # Reinhard et al. 2002, eq. 3, per channel
    return x / (1 + x)


def hable(x):  # Hable 2010: Uncharted 2 curve, W = 11.2, exposure bias 2
    def f(v):
        return ((v * (0.15 * v + 0.05) + 0.004) / (v * (0.15 * v + 0.5) + 0.06)) - 0.02 / 0.3

    return np.clip(f(2 * x) / f(11.2), 0, 1)


def aces(x):  # Hill's ACES fitted (BakingLab): input matrix, RRT+ODT fit, output matrix
    m_in = np.array([[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566], [0.02840, 0.13383, 0.83777]])
    m_out = np.array([[1.60475, -0.53108, -0.07367],
                      [-0.10208, 1.10813, -0.00605],
                      [-0.00327, -0.07276, 1.07602]])
    v = np.einsum("ij,...j->...i", m_in, x)
    v = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081)
    return np.clip(np.einsum("ij,...j->...i", m_out, v), 0, 1)


CURVES = {"CLAMP": lambda x: np.clip(x, 0, 1), "REINHARD": reinhard, "HABLE": hable, "ACES": aces}


def _hdr_scene(tone_mapper, exposure=0.0, transfer="SRGB"):
    """A coloured plane under a close point light: radiance from ~0.01 to ~20 across the frame."""
    scene = scenes.reset(size=32)
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.shading_lab.tone_mapper = tone_mapper
    scene.shading_lab.exposure = exposure
    scene.shading_lab.transfer = transfer
    scenes.ortho_camera(scene, scale=6.0)
    scenes.plane(scene, size=8.0, material=scenes.material(base_color=(0.9, 0.5, 0.2), roughness=0.4))
    scenes.light(scene, "POINT", energy=300.0, location=(-1.5, 1.0, 0.6))
    return scene


@pytest.mark.parametrize("tone_mapper,exposure,transfer", [
    ("CLAMP", 0.0, "SRGB"), ("REINHARD", 0.0, "SRGB"), ("HABLE", 1.0, "SRGB"), ("ACES", -1.0, "SRGB"),
    ("REINHARD", 0.5, "GAMMA22"),
])
def test_png_is_the_tone_curve_of_the_radiance(tone_mapper, exposure, transfer, tmp_path):
    scene = _hdr_scene(tone_mapper, exposure, transfer)
    bpy.ops.render.render()
    layers = scenes.read_exr_layers(scenes.save_result(scene, tmp_path / "all.exr", "MULTILAYER"))
    png = scenes.read_png(scenes.save_result(scene, tmp_path / "shown.png", "PNG"))
    radiance = layers["Radiance"][..., :3].astype(np.float64)
    assert radiance.max() > 5.0 and radiance.min() < 0.1, "the scene must span a high dynamic range"

    y = CURVES[tone_mapper](radiance * 2.0 ** exposure)
    if transfer == "GAMMA22":
        code = np.power(y, 1 / 2.2)  # what the display receives
        combined = srgb_decode(code)  # what Combined must hold so that Standard's encoding yields it
    else:
        code, combined = srgb_encode(y), y
    np.testing.assert_allclose(layers["Combined"][..., :3], combined, atol=2e-5, rtol=1e-4)
    assert np.abs(png[..., :3] - np.rint(code * 255)).max() <= 1


def test_blender_tone_mapper_keeps_combined_scene_linear(tmp_path):
    scene = _hdr_scene("BLENDER")
    bpy.ops.render.render()
    layers = scenes.read_exr_layers(scenes.save_result(scene, tmp_path / "all.exr", "MULTILAYER"))
    assert "Radiance" not in layers
    assert layers["Combined"][..., :3].max() > 5.0  # HDR kept for Blender's view transform


def test_tonemap_twin_matches_the_papers():
    x = np.concatenate([np.linspace(0, 2, 50), np.geomspace(2, 1e4, 50)])
    rgb = np.stack([x, x * 0.5, x * 0.1], axis=-1)
    for name, curve in CURVES.items():
        np.testing.assert_allclose(tonemap.CURVES[name](rgb), curve(rgb), atol=1e-12)
    np.testing.assert_allclose(tonemap.display(rgb, "REINHARD", 1.0, "GAMMA22"),
                               srgb_decode(np.power(reinhard(rgb * 2.0), 1 / 2.2)), atol=1e-12)
    ramp = np.linspace(0, 1, 11)
    np.testing.assert_allclose(tonemap.linear_to_srgb(ramp), srgb_encode(ramp), atol=1e-12)
    assert math.isclose(float(tonemap.tonemap_hable(np.array(1e9))), 1.0, rel_tol=0.02)
