"""A|B compare: split view and difference heat map, in final renders and through the viewport
session, checked against separate renders of each model."""

from __future__ import annotations

import math

import bpy
import numpy as np
import pytest
import scenes
from gpu_harness import viewport_image

SIZE = 32


def _scene():
    scene = scenes.reset(size=SIZE)
    scene.shading_lab.ambient = 0.0
    scenes.ortho_camera(scene, scale=4.0)
    scenes.plane(scene, size=8.0, material=scenes.material(base_color=(0.7, 0.5, 0.3), roughness=0.3))
    scenes.light(scene, "POINT", energy=300.0, location=(0.3, -0.2, 1.0))
    return scene


def _render(scene, tmp_path, name):
    return scenes.render(scene, tmp_path / f"{name}.exr")


def _model_renders(scene, tmp_path):
    out = {}
    for model in ("BLINN_PHONG", "PBR"):
        scene.shading_lab.model = model
        out[model] = _render(scene, tmp_path, model)
    return out


def turbo(t):
    """Mikhailov 2019's polynomial approximation of Turbo (from his published shader code)."""
    t = np.clip(t, 0.0, 1.0)
    def poly(c):
        return sum(k * t ** i for i, k in enumerate(c))

    r = poly((0.13572138, 4.61539260, -42.66032258, 132.13108234, -152.94239396, 59.28637943))
    g = poly((0.09140261, 2.19418839, 4.84296658, -14.18503333, 4.27729857, 2.82956604))
    b = poly((0.10667330, 12.64194608, -60.58204836, 110.36276771, -89.90310912, 27.34824973))
    return np.clip(np.stack([r, g, b], axis=-1), 0.0, 1.0)


def srgb_decode(c):
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def test_split_view_is_each_model_on_its_side(tmp_path):
    scene = _scene()
    separate = _model_renders(scene, tmp_path)
    props = scene.shading_lab
    props.compare_mode, props.compare_split = "SPLIT", 0.25
    props.compare_a, props.compare_b = "BLINN_PHONG", "PBR"
    split = _render(scene, tmp_path, "split")
    edge = math.floor(0.25 * SIZE)
    np.testing.assert_array_equal(split[:, :edge], separate["BLINN_PHONG"][:, :edge])
    np.testing.assert_array_equal(split[:, edge + 1:], separate["PBR"][:, edge + 1:])
    np.testing.assert_array_equal(split[:, edge, :3], 1.0)  # the divider
    assert np.abs(separate["PBR"] - separate["BLINN_PHONG"]).max() > 0.1  # the two sides differ


def test_difference_is_a_heat_map_with_its_scale(tmp_path):
    scene = _scene()
    separate = _model_renders(scene, tmp_path)
    props = scene.shading_lab
    props.compare_mode, props.compare_range = "DIFFERENCE", 2.0
    props.compare_a, props.compare_b = "BLINN_PHONG", "PBR"
    heat = _render(scene, tmp_path, "diff")
    weights = np.array([0.2126, 0.7152, 0.0722])
    d = np.abs(separate["BLINN_PHONG"][..., :3] @ weights - separate["PBR"][..., :3] @ weights)
    want = srgb_decode(turbo(d / 2.0))
    rows = SIZE - 8  # the bottom 8 rows (top-first array: the last 8) are the legend
    np.testing.assert_allclose(heat[:rows, :, :3], want[:rows], atol=2e-4)
    legend = heat[rows:, :, :3]
    ramp = srgb_decode(turbo((np.arange(SIZE) + 0.5) / SIZE))
    np.testing.assert_allclose(legend, np.broadcast_to(ramp, legend.shape), atol=2e-4)


def test_viewport_compare_matches_final_render(tmp_path):
    scene = _scene()
    props = scene.shading_lab
    props.compare_mode, props.compare_split = "SPLIT", 0.5
    final = _render(scene, tmp_path, "final")[::-1]  # bottom row first, like textures
    shown = viewport_image(scene, SIZE)
    np.testing.assert_allclose(shown[..., :3], final[..., :3], rtol=2e-3, atol=1e-3)  # half-float targets


@pytest.mark.parametrize("mode", ["SPLIT", "DIFFERENCE"])
def test_compare_with_engine_tone_mapper(mode, tmp_path):
    """Under an engine tone mapper a split shows each model's display values (each side equal to
    that model's own render through the tone mapper); a difference map is the heat map of the two
    models' radiance difference (the Range property's unit), not tone mapped itself: its colours
    are the heat map's, exactly; neither writes a Radiance pass."""
    scene = _scene()
    props = scene.shading_lab
    radiance = _model_renders(scene, tmp_path)  # tone mapper "Blender": Combined is the radiance
    props.tone_mapper = "REINHARD"
    separate = _model_renders(scene, tmp_path)  # Combined: each model's display values
    hdr = max(float(separate[m][..., :3].max()) for m in separate)
    props.compare_mode, props.compare_a, props.compare_b = mode, "BLINN_PHONG", "PBR"
    props.compare_split, props.compare_range = 0.5, 0.5
    bpy.ops.render.render()
    layers = scenes.read_exr_layers(scenes.save_result(scene, tmp_path / "all.exr", "MULTILAYER"))
    assert "Radiance" not in layers
    combined = layers["Combined"][..., :3]
    assert np.isfinite(combined).all() and 0.0 <= combined.min() and combined.max() <= 1.0 + 1e-6
    a, b = separate["BLINN_PHONG"][..., :3], separate["PBR"][..., :3]
    if mode == "SPLIT":
        edge = SIZE // 2
        np.testing.assert_array_equal(combined[:, :edge], a[:, :edge])
        np.testing.assert_array_equal(combined[:, edge + 1:], b[:, edge + 1:])
        assert hdr < 1.0 and np.abs(a - b).max() > 0.05, "display values on both sides, and they differ"
    else:
        weights = np.array([0.2126, 0.7152, 0.0722])
        ra, rb = radiance["BLINN_PHONG"][..., :3], radiance["PBR"][..., :3]
        want = srgb_decode(turbo(np.abs(ra @ weights - rb @ weights) / 0.5))
        rows = SIZE - 8  # the legend's rows at the bottom
        err = np.abs(combined[:rows] - want[:rows]).max()
        reinhard = want / (1.0 + want)  # the map tone mapped again: what it must not be
        apart = np.abs(reinhard - want)[:rows].max()
        print(f"difference map: {err:.1e} off the radiance's heat map, {apart:.3f} from it tone mapped")
        assert err < 5e-5, f"difference map off the heat map of the radiance by {err:.1e} (measured 1.4e-5)"
        assert apart > 100 * err, f"the test tells a tone-mapped map apart ({apart:.3f})"
