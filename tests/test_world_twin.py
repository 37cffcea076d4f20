"""The world's light on an image world, the GPU against its numpy twin (environment.world_maps,
shading.shade_image_environment): the split sum and the sampled lobe, each term set, with and
without suns split off. The twin evaluates what the GPU reads between texels at the exact
directions (prefiltered levels, irradiance), from analytic sphere normals where the GPU
interpolates a mesh's; the bounds hold those differences. Shadows and the world's occlusion are
off here: the twin shades the world's light alone (with the suns as lights), and occlusion has
its own tests against Cycles (test_world_light.py). The twin is held to independent references
in test_world_light.py (lobe means by quadrature) and below (Cycles)."""

from __future__ import annotations

import bpy
import numpy as np
import pytest
import scenes
from gpu_harness import run_on_gpu
from test_cycles import _cycles
from test_world_light import _sphere, _world

from addon.blender import extract
from addon.blender.scene_builder import principled_material
from addon.frame import gpu_library
from addon.reference import environment, shading

W, H, SCALE = 96, 48, 4.0  # orthographic, looking down -z; 24 px per metre
CENTRES = (-1.3, 0.0, 1.3)
RADIUS = 0.6
ROUGHNESS = (0.12, 0.35, 0.7)


def _image(folder, sun: float) -> bpy.types.Image:
    """A 128 x 64 world: smooth colour gradients, a few soft blobs, and (``sun`` > 0) one texel
    of that radiance, far above the sun threshold."""
    h, w = 64, 128
    u, v = (np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h
    d = environment.equirect_direction(*np.meshgrid(u, v))
    rgb = 0.4 + 0.3 * d[..., 2:3] * np.array([0.2, 0.5, 1.0]) + 0.2 * d[..., 0:1] * np.array([1.0, 0.6, 0.3])
    for centre, colour in (((0.3, -0.5, 0.8), (3.0, 2.5, 2.0)), ((-0.7, 0.4, 0.6), (0.5, 1.5, 3.0))):
        c = np.asarray(centre) / np.linalg.norm(centre)
        rgb = rgb + np.asarray(colour) * np.exp((d @ c - 1.0) / 0.02)[..., None]
    pixels = np.ones((h, w, 4), np.float32)
    pixels[..., :3] = rgb
    if sun:
        pixels[52, 30, :3] = sun
    return scenes.saved_float_image(f"World {sun}", pixels, folder)


def _scene(folder, kind: str, sun: float, term_set: str = "CUSTOM"):
    scene = scenes.reset(size=W)
    scene.render.resolution_x, scene.render.resolution_y = W, H
    scene.render.film_transparent = True
    props = scene.shading_lab
    props.model = "PBR"
    props.world_occlusion = False
    props.shadows = False
    props.term_set = term_set
    scenes.ortho_camera(scene, location=(0.0, 0.0, 10.0), scale=SCALE)
    for x, r in zip(CENTRES, ROUGHNESS):
        if kind == "metal":
            mat = principled_material(f"metal {r}", (0.95, 0.7, 0.4), 1.0, r)
        else:
            mat = principled_material(f"dielectric {r}", (0.7, 0.25, 0.15), 0.0, r, 1.5)
        _sphere((x, 0.0, 0.0), mat, radius=RADIUS)
    _world(scene, image=_image(folder, sun))
    return scene


def _pixels(every: int = 1):
    """(rows, cols, p, n) of the pixels well inside each sphere (n.z > 0.35), by sphere; ``every``: each
    every-th of them only (a slow twin's)."""
    x = ((np.arange(W) + 0.5) / W - 0.5) * SCALE
    y = (0.5 - (np.arange(H) + 0.5) / H) * SCALE * H / W  # rows top first
    xx, yy = np.meshgrid(x, y)
    out = []
    for cx in CENTRES:
        z2 = RADIUS ** 2 - (xx - cx) ** 2 - yy ** 2
        inside = z2 > (0.35 * RADIUS) ** 2
        rows, cols = np.nonzero(inside)
        rows, cols = rows[::every], cols[::every]
        inside = np.zeros_like(inside)
        inside[rows, cols] = True
        p = np.stack([xx[inside], yy[inside], np.sqrt(z2[inside])], -1) + [0.0, 0.0, 0.0]
        n = (p - [cx, 0.0, 0.0]) / RADIUS
        out.append((rows, cols, p + [0.0, 0.0, 0.0], n))
    return out


def _twin(scene, samples: int, every: int = 1) -> tuple[np.ndarray, list]:
    """The twin's image (the world's light plus the suns as lights) and the pixels compared."""
    snap = run_on_gpu(lambda depsgraph: extract.snapshot(depsgraph, W, H, auto_choice=False))
    maps = environment.world_maps(snap.world)
    image = np.zeros((H, W, 3))
    pixels = _pixels(every)
    materials = sorted(k for k in snap.materials if k)  # "metal 0.12" < "metal 0.35" < "metal 0.7"
    terms = snap.settings.terms
    for (rows, cols, p, n), key in zip(pixels, materials):
        s = shading.Surface(p, n, np.broadcast_to([0.0, 0.0, 1.0], n.shape), snap.materials[key])
        c = shading.shade_image_environment(s, maps, terms, samples, snap.settings.environment_diffuse)
        if snap.world.suns:
            c = c + shading.shade("PBR", s, list(snap.world.suns), terms=terms)
        image[rows, cols] = c
    return image, pixels


def _compare(scene, tmp_path, samples: int, every: int = 1) -> list[tuple[float, float]]:
    """Per sphere, over its inner pixels: (mean |GPU - twin| / mean twin, the 95th percentile of
    |GPU - twin| / twin). A sun's highlight on a smooth metal covers two pixels, which the GPU's
    interpolated mesh normals and the levels' texels place a fraction of a pixel apart from the
    twin's: the mean error is theirs, the percentile the rest's."""
    props = scene.shading_lab
    props.world_specular = "SAMPLED" if samples else "SPLIT_SUM"
    if samples:
        props.world_samples = samples
    gpu = scenes.render(scene, tmp_path / "gpu.exr")[..., :3].astype(np.float64)
    twin, pixels = _twin(scene, samples, every)
    errors = []
    for rows, cols, _, _ in pixels:
        a, b = gpu[rows, cols], twin[rows, cols]
        errors.append((float(np.abs(a - b).mean() / b.mean()),
                       float(np.percentile(np.abs(a - b).mean(-1) / b.mean(-1), 95))))
    return errors


#: (kind, term set, sun, samples): per sphere (roughness 0.12, 0.35, 0.7), the largest mean error
#: and 95th percentile allowed, each about 2.5x what it measures (2026-12-06, printed by the test):
#: no sun, split sum: metal mean 0.39 / 0.63 / 0.15 %, 95th percentile 1.28 / 1.98 / 0.44 % (the
#: prefiltered levels read between texels), dielectric 0.065 / 0.077 / 0.044 %, 0.13 / 0.24 /
#: 0.08 %; sampled (16): metal 0.13 / 0.10 / 0.07 %, 0.34 / 0.22 / 0.18 %, dielectric 0.046 /
#: 0.041 / 0.043 %, 0.081 / 0.070 / 0.074 %. With a sun of 2000 (a texel of a 128-wide world) the
#: roughness-0.12 metal's highlight: mean 25.9 % (split sum) and 11.3 % (sampled), 95th
#: percentile 3.9 % / 3.8 % (its halo); the rougher spheres as without.
CASES = {
    ("metal", "CUSTOM", 0.0, 0): ((0.010, 0.016, 0.004), (0.032, 0.05, 0.011)),
    ("metal", "PRINCIPLED", 0.0, 0): ((0.010, 0.016, 0.004), (0.032, 0.05, 0.011)),
    ("dielectric", "PRINCIPLED", 0.0, 0): ((0.0016, 0.002, 0.0011), (0.0033, 0.006, 0.002)),
    ("metal", "CUSTOM", 0.0, 16): ((0.0034, 0.0025, 0.0017), (0.0085, 0.0055, 0.0046)),
    ("dielectric", "PRINCIPLED", 0.0, 16): ((0.0012, 0.001, 0.0011), (0.002, 0.0018, 0.0019)),
    ("metal", "PRINCIPLED", 2000.0, 0): ((0.5, 0.015, 0.0034), (0.08, 0.041, 0.0085)),
    ("metal", "PRINCIPLED", 2000.0, 16): ((0.25, 0.007, 0.0026), (0.08, 0.011, 0.0057)),
}


@pytest.mark.parametrize("case", CASES, ids=lambda c: "-".join(str(x) for x in c))
def test_gpu_matches_the_twin_under_an_image_world(case, tmp_path):
    kind, term_set, sun, samples = case
    scene = _scene(tmp_path, kind, sun, term_set)
    errors = _compare(scene, tmp_path, samples)
    print(f"{case}: " + ", ".join(f"r {r}: mean {e:.3%}, 95th percentile {q:.3%}"
                                  for r, (e, q) in zip(ROUGHNESS, errors)))
    for roughness, (mean, percentile), mean_bound, percentile_bound in zip(ROUGHNESS, errors, *CASES[case]):
        assert mean < mean_bound, f"r {roughness}: mean {mean:.3%} (bound {mean_bound:.2%})"
        assert percentile < percentile_bound, f"r {roughness}: 95th percentile {percentile:.3%} " \
                                              f"(bound {percentile_bound:.2%})"


#: Per sphere (roughness 0.12, 0.35, 0.7), the largest error of the sampled twin against Cycles
#: (512 samples: its noise is part of what is measured). Measured: metal 0.17 / 1.03 / 1.34 %
#: (2026-12-03), 0.17 / 0.92 / 1.21 % (2026-12-06); the split sum 0.38-0.55 / 1.18-1.21 / 4.16 %;
#: dielectric 0.20 / 0.22 / 0.25 % (split sum 0.23 / 0.45 / 0.55 %).
SAMPLED_VS_CYCLES = {"metal": (0.005, 0.025, 0.032), "dielectric": (0.005, 0.0055, 0.0065)}


@pytest.mark.parametrize("kind", ["metal", "dielectric"])
def test_the_sampled_twin_converges_to_cycles_and_measures_the_split_sums_error(kind, tmp_path):
    """The twin against an independent renderer: its sampled lobe (128 samples) against Cycles
    (direct light, 512 samples) on the world without a sun, and the split sum's own error beside
    it (what World Specular: Sampled buys, the quantity a choice between the two predicts)."""
    scene = _scene(tmp_path, kind, 0.0, "PRINCIPLED")
    sampled, pixels = _twin(scene, 128)
    split, _ = _twin(scene, 0)
    cycles = _cycles(scene, tmp_path / "cycles.exr", samples=512)[..., :3].astype(np.float64)
    rows = []
    for (r_, c_, _, _), roughness in zip(pixels, ROUGHNESS):
        ref = cycles[r_, c_]
        rows.append((roughness, float(np.abs(sampled[r_, c_] - ref).mean() / ref.mean()),
                     float(np.abs(split[r_, c_] - ref).mean() / ref.mean())))
    print(f"{kind}: " + ", ".join(f"r {r}: sampled {a:.2%}, split sum {b:.2%}" for r, a, b in rows))
    for (roughness, error, _), bound in zip(rows, SAMPLED_VS_CYCLES[kind]):
        assert error < bound, f"r {roughness}: sampled twin {error:.2%} from Cycles (bound {bound:.2%})"
    worst_split, worst_sampled = max(b for _, _, b in rows), max(a for _, a, _ in rows)
    assert worst_split > 1.5 * worst_sampled, f"split sum {worst_split:.2%}, sampled {worst_sampled:.2%}"


@pytest.mark.parametrize("scene_samples", [0, 16])
def test_a_material_takes_its_own_world_specular(scene_samples, tmp_path):
    """Material > World Specular overrides the scene's: the middle sphere sampled (16) under a
    split-sum scene, or on the split sum in a sampled scene; every sphere as the twin shades it
    with its own setting, and the program compiled for it says so."""
    scene = _scene(tmp_path, "metal", 0.0, "PRINCIPLED")
    middle = bpy.data.materials[f"metal {ROUGHNESS[1]}"].shading_lab
    middle.world_specular = "SPLIT_SUM" if scene_samples else "SAMPLED"
    middle.world_samples = 16
    props = scene.shading_lab
    props.world_specular = "SAMPLED" if scene_samples else "SPLIT_SUM"
    props.world_samples = max(scene_samples, 1)
    gpu = scenes.render(scene, tmp_path / "gpu.exr")[..., :3].astype(np.float64)
    own = 0 if scene_samples else 16
    errors = []
    for i, samples in enumerate((scene_samples, own, scene_samples)):
        twin, pixels = _twin(scene, samples)
        rows, cols, _, _ = pixels[i]
        a, b = gpu[rows, cols], twin[rows, cols]
        errors.append(float(np.abs(a - b).mean() / b.mean()))
    other, _ = _twin(scene, scene_samples)  # the middle sphere as the scene's setting would shade it
    rows, cols, _, _ = _pixels()[1]
    apart = float(np.abs(other[rows, cols] - gpu[rows, cols]).mean() / gpu[rows, cols].mean())
    print(f"scene {scene_samples} samples, the middle sphere {own}: errors against the twin "
          + ", ".join(f"{e:.3%}" for e in errors) + f"; the middle one as the scene's: {apart:.2%}")
    assert max(errors) < 0.015, errors
    assert apart > 3.0 * errors[1], (apart, errors[1])
    defines = [dict(k) for k in gpu_library.LIBRARY._programs if isinstance(k[0], tuple)]
    assert any(d.get("SL_ENV_SAMPLES") == "16" for d in defines)
    assert any("SL_ENV_MAP" in d and "SL_ENV_SAMPLES" not in d for d in defines)
