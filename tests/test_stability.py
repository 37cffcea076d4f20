"""Numerical stability at the extremes (SPEC 9): a sweep of 11,520 combinations of roughness
exactly 0 and 1, shininess 0 to 1e6, n.v and n.l at 1, tiny, 0 and negative, F0 0 and 1, light
distance 0 to 1e6, intensity up to 1e8 and back-facing normals, through every model and term
variant, on the GPU (the shaders' own make_surface/light_irradiance/shade_direct) and in the
numpy twin: no NaN, no Inf, no negative radiance; half-float targets stay below 65504. Then
whole scenes built from the same extremes render finite."""

from __future__ import annotations

import itertools
import math

import bpy
import numpy as np
import pytest
import scenes
from glsl_harness import evaluate

from addon import programs, shading
from addon import snapshot as S

MATERIALS = list(itertools.product(
    (0.0, 1e-4, 0.045, 0.3, 1.0),  # roughness
    (0.0, 1.0),  # metalness
    (0.0, 0.04, 1.0),  # dielectric F0
    (0.0, 1.0, 1e4, 1e6),  # shininess
    (0.0, 1.0),  # base colour (grey level)
))
ROWS_PER_MATERIAL = 48


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _sweep():
    rng = np.random.default_rng(11)
    n_rows = len(MATERIALS) * ROWS_PER_MATERIAL
    mats = np.repeat(np.array(MATERIALS), ROWS_PER_MATERIAL, axis=0)
    n = np.tile([0.0, 0.0, 1.0], (n_rows, 1))
    # view: normal, oblique, grazing (n.v = 1e-4, 0) and below the horizon (a smooth normal
    # facing away, as at silhouettes)
    nov = rng.choice([1.0, 0.5, 1e-4, 1e-7, 0.0, -0.2], n_rows)
    phi = rng.uniform(0, 2 * np.pi, n_rows)
    sin_v = np.sqrt(1 - nov ** 2)
    v = np.column_stack([sin_v * np.cos(phi), sin_v * np.sin(phi), nov])
    # light: direction with n.l at 1, oblique, tiny, 0 and below; distance 0 .. 1e6; up to 1e8 W/sr
    nol = rng.choice([1.0, 0.7, 1e-7, 0.0, -0.3], n_rows)
    phl = rng.uniform(0, 2 * np.pi, n_rows)
    sin_l = np.sqrt(1 - nol ** 2)
    l_dir = np.column_stack([sin_l * np.cos(phl), sin_l * np.sin(phl), nol])
    dist = rng.choice([0.0, 1e-6, 1e-2, 1.0, 1e3, 1e6], n_rows)
    intensity = rng.choice([0.0, 1.0, 1e4, 1e8], n_rows)
    light_pos = l_dir * dist[:, None]
    return mats, n, v, light_pos, intensity


MATS, NORMALS, VIEWS, LIGHT_POS, INTENSITY = _sweep()


def _twin(model, terms):
    mat = S.MaterialParams(
        base_color=np.repeat(MATS[:, 4:5], 3, axis=1), diffuse_color=np.repeat(MATS[:, 4:5], 3, axis=1),
        specular_color=(1.0, 1.0, 1.0), ambient_color=(0.0, 0.0, 0.0), roughness=MATS[:, 0],
        metalness=MATS[:, 1], f0=MATS[:, 2], shininess=MATS[:, 3],
        ior_n=(0.18, 0.42, 1.37), ior_k=(3.42, 2.35, 1.77))
    surface = shading.Surface(np.zeros_like(NORMALS), NORMALS, VIEWS, mat)
    light = S.Light("POINT", LIGHT_POS, (0.0, 0.0, -1.0), np.repeat(INTENSITY[:, None], 3, axis=1))
    with np.errstate(all="ignore"):
        E, l = shading.light_irradiance(light, surface.p)
        direct, ldr = shading.MODELS[model]
        c = direct(surface, l, E, (1.0, 1.0), terms)
    return np.clip(c, 0.0, 1.0) if ldr else c


BODY = """
MaterialData m;
m.base_color = vec4(vec3(mat.w), 1.0);
m.diffuse_color = m.base_color;
m.specular_color = vec4(1.0);
m.ambient_color = vec4(0.0);
m.params = vec4(mat.x, mat.y, max(mat.z, 1e-4), geo.w);
m.fresnel = vec4(-1.0, 0.2, 1.0, 0.0);
m.ior_n = vec4(0.18, 0.42, 1.37, 0.0);
m.ior_k = vec4(3.42, 2.35, 1.77, 0.0);
m.emission = vec4(0.0);
Surface s = make_surface(vec3(0.0), nrm.xyz, view.xyz, m);
LightData L;
L.position_kind = vec4(lpos.xyz, 0.0);
L.direction_cone = vec4(0.0, 0.0, -1.0, -1.0);
L.intensity_blend = vec4(vec3(lpos.w), 1e20);
L.factors = vec4(1.0, 1.0, 0.0, 0.0);
L.shape = vec4(0.0);
L.area = vec4(1.0, 0.0, 0.0, 0.0);
L.influence = vec4(0.0);
vec3 l;
vec3 E = light_irradiance(L, s.p, l);
result = vec4(write_target(shade_finish(shade_direct(s, l, E, L.factors))), 0.0);
"""

VARIANTS = [("BLINN_PHONG", S.Terms()), ("BLINN_PHONG", S.Terms(normalized_blinn_phong=True)),
            ("PHONG", S.Terms()), ("PBR", S.Terms())]
VARIANTS += [("PBR", S.Terms(fresnel=f)) for f in S.TERM_CHOICES["fresnel"][1:]]
VARIANTS += [("PBR", S.Terms(ndf=d, visibility=v)) for d in S.TERM_CHOICES["ndf"]
             for v in S.TERM_CHOICES["visibility"] if (d, v) != ("GGX", "SMITH_CORRELATED")]
VARIANTS += [("PBR", S.Terms(diffuse=d)) for d in S.TERM_CHOICES["diffuse"][1:]]
VARIANTS += [("PBR", S.Terms(multiscatter=True)), ("PBR", S.Terms(ndf="BECKMANN", multiscatter=True)),
             ("PBR", S.Terms(principled=True))]


def _label(variant):
    model, terms = variant
    changed = {k: v for k, v in vars(terms).items() if v != getattr(S.Terms(), k)}
    return model + "".join(f"-{v if isinstance(v, str) else k}" for k, v in changed.items())


@pytest.mark.parametrize("variant", VARIANTS, ids=_label)
def test_sweep_stays_finite_and_non_negative(variant):
    model, terms = variant
    assert len(MATS) >= 10_000
    features = programs.Features(model, 1, frozenset({"POINT"}), terms)
    extra = ("model_pbr.glsl",) if model == "PBR" else (programs.MODEL_FILES[model],)
    inputs = {"mat": np.column_stack([MATS[:, 0], MATS[:, 1], MATS[:, 3], MATS[:, 4]]),
              "geo": np.column_stack([np.zeros((len(MATS), 3)), MATS[:, 2]]),
              "nrm": np.column_stack([NORMALS, np.zeros(len(MATS))]),
              "view": np.column_stack([VIEWS, np.zeros(len(MATS))]),
              "lpos": np.column_stack([LIGHT_POS, INTENSITY])}
    gpu = evaluate(BODY, inputs, dict(features.defines()), extra=extra, terms=terms)[:, :3]
    twin = _twin(model, terms)
    for name, values in (("GPU", gpu), ("numpy twin", twin)):
        bad = ~np.isfinite(values)
        rows = bad.any(axis=1)
        assert not rows.any(), f"{name}: {rows.sum()} rows NaN/Inf, e.g. materials {MATS[rows][:3]}"
        assert values.min() >= 0.0, f"{name}: negative radiance {values.min()}"
    # the two compute the same function: where the twin is well inside float32's range
    moderate = (twin > 1e-4) & (twin < 1e30)
    rel = np.abs(gpu[moderate] - twin[moderate]) / twin[moderate]
    assert np.median(rel) < 1e-5 and np.mean(rel < 1e-3) > 0.99, (np.median(rel), np.mean(rel < 1e-3))


def test_half_float_target_caps_radiance():
    features = programs.Features("PBR", 1, frozenset({"POINT"}), S.Terms(), half_target=True)
    inputs = {"mat": np.column_stack([MATS[:, 0], MATS[:, 1], MATS[:, 3], MATS[:, 4]]),
              "geo": np.column_stack([np.zeros((len(MATS), 3)), MATS[:, 2]]),
              "nrm": np.column_stack([NORMALS, np.zeros(len(MATS))]),
              "view": np.column_stack([VIEWS, np.zeros(len(MATS))]),
              "lpos": np.column_stack([LIGHT_POS, INTENSITY])}
    gpu = evaluate(BODY, inputs, dict(features.defines()), extra=("model_pbr.glsl",))[:, :3]
    assert gpu.max() == 65504.0, "the sweep reaches beyond half-float range, and is capped there"
    assert np.all(np.isfinite(gpu))


@pytest.mark.parametrize("model", ["BLINN_PHONG", "PHONG", "PBR"])
def test_extreme_scene_renders_finite(model, tmp_path):
    """A mirror (roughness 0, shininess 1e6), a 1e8 W light touching the surface, a light 1e6 m
    away, a triangle whose corner normals cancel (a zero-length interpolated normal), a back face."""
    scene = scenes.reset(size=32)
    scene.shading_lab.model = model
    scene.shading_lab.multiscatter = True
    scenes.ortho_camera(scene, scale=4.0)
    mirror = scenes.material("Mirror", roughness=0.0, metalness=1.0, base_color=(1, 1, 1), shininess=1e6)
    scenes.plane(scene, size=2.0, location=(-1.0, 0.0, 0.0), material=mirror)
    back = scenes.plane(scene, size=2.0, location=(1.0, 1.0, 0.0), rotation=(math.pi, 0.0, 0.0),
                        material=scenes.material("Black", base_color=(0, 0, 0), f0=1.0, roughness=1.0))
    bpy.context.view_layer.update()
    assert back.matrix_world[2][2] < 0  # its front faces away from the camera
    mesh = bpy.data.meshes.new("Cancel")
    mesh.from_pydata([(0.2, -1.8, 0.0), (1.8, -1.8, 0.0), (1.0, -0.2, 0.0)], [], [(0, 1, 2)])
    mesh.normals_split_custom_set([(0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (1.0, 0.0, 0.0)])
    scene.collection.objects.link(bpy.data.objects.new("Cancel", mesh))
    scenes.light(scene, "POINT", energy=1e8, location=(-1.0, 0.0, 0.0))  # on the mirror's surface
    scenes.light(scene, "POINT", energy=1e8, location=(1e6, 0.0, 1e6))
    scenes.light(scene, "SPOT", energy=1e8, location=(1.0, -1.0, 1e-6), spot_size=1e-3, spot_blend=0.0)
    image = scenes.render(scene, tmp_path / "extreme.exr")
    assert np.all(np.isfinite(image)) and image.min() >= 0.0
    assert image[..., :3].max() > 0.0
