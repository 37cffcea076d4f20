"""The GPU against its numpy twin (addon/reference/shading.py) on random scenes: same terms, same lights,
float32 on the GPU vs float64 in numpy. The twin itself is held to closed forms in
test_shading_twin.py and, through the renders, to Cycles."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scenes

from addon.plan import programs
from addon.reference import shading
from addon.scene import snapshot as S

SIZE = 48
SCALE = 2.0
KINDS = ("POINT", "SPOT", "SUN", "AREA")


def _random_case(rng, sizes: bool = False):
    tilt = (rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(0, math.pi))
    mat = dict(
        base_color=tuple(rng.uniform(0.05, 1.0, 3)),
        roughness=float(rng.uniform(0.08, 1.0)),
        metalness=float(rng.choice([0.0, 1.0, rng.uniform()])),
        f0=float(rng.uniform(0.0, 0.08)),
        shininess=float(rng.uniform(1.0, 200.0)),
        specular_color=tuple(rng.uniform(0.0, 1.0, 3)),
        ambient_color=tuple(rng.uniform(0.0, 1.0, 3)),
    )
    lights = []
    for _ in range(rng.integers(1, 5)):
        kind = str(rng.choice(KINDS))
        props = dict(
            kind=kind,
            energy=float(rng.uniform(5.0, 60.0)) if kind != "SUN" else float(rng.uniform(0.2, 2.0)),
            location=(float(rng.uniform(-1, 1)), float(rng.uniform(-1, 1)), float(rng.uniform(0.5, 2.0))),
            rotation=(float(rng.uniform(-0.7, 0.7)), float(rng.uniform(-0.7, 0.7)), 0.0),
            color=tuple(float(c) for c in rng.uniform(0.3, 1.0, 3)),
            diffuse_factor=float(rng.uniform(0.5, 1.0)),
            specular_factor=float(rng.uniform(0.5, 1.5)),
        )
        if kind == "SPOT":
            props.update(spot_size=float(rng.uniform(0.5, 2.5)), spot_blend=float(rng.uniform(0.0, 1.0)))
        if kind == "AREA":
            shape = str(rng.choice(["SQUARE", "RECTANGLE", "DISK", "ELLIPSE"]))
            props.update(shape=shape, size=float(rng.uniform(0.1, 1.0)), size_y=float(rng.uniform(0.1, 1.0)),
                         spread=float(rng.uniform(0.2, 2.5)) if rng.integers(2) else math.pi)
        if sizes and kind in ("POINT", "SPOT"):  # sphere lights
            props.update(shadow_soft_size=float(rng.uniform(0.05, 0.6)),
                         use_soft_falloff=bool(rng.integers(2)))
        lights.append(props)
    return tilt, mat, lights


def _twin_light(props) -> S.Light:
    m = scenes.euler_matrix(props["rotation"])
    direction = tuple(-m[:, 2])
    kind = props["kind"]
    strength = np.asarray(props["color"]) * props["energy"]
    intensity = {"POINT": strength / (4 * math.pi), "SPOT": strength / (4 * math.pi),
                 "SUN": strength, "AREA": strength / math.pi}[kind]
    extra = {}
    if kind == "SPOT":
        extra = dict(spot_cos_half=math.cos(props["spot_size"] / 2),
                     spot_smooth=S.spot_smooth(props["spot_size"], props["spot_blend"]))
    if kind == "AREA":
        sy = props["size_y"] if props["shape"] in ("RECTANGLE", "ELLIPSE") else props["size"]
        extra = dict(axis_x=tuple(m[:, 0]), half_size=(props["size"] / 2, sy / 2),
                     ellipse=props["shape"] in ("DISK", "ELLIPSE"), spread=props["spread"])
    return S.Light(kind, tuple(props["location"]), direction, tuple(intensity),
                   diffuse_factor=props["diffuse_factor"], specular_factor=props["specular_factor"],
                   radius=props.get("shadow_soft_size", 0.0),
                   soft_falloff=props.get("use_soft_falloff", False), **extra)


def _reaches(lights, tilt, size=10.0):
    """The lights with the reach the scene's default Light Threshold gives them (faded to nothing
    there), as extraction gives it: from the box of the tilted plane of ``size``."""
    half = size / 2.0
    corners = np.array([[x, y, 0.0] for x in (-half, half) for y in (-half, half)])
    corners = corners @ scenes.euler_matrix(tilt).T
    return programs.light_reaches(lights, S.Settings().light_threshold, (corners.min(0), corners.max(0)))


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("model", ["BLINN_PHONG", "PHONG", "PBR"])
def test_gpu_matches_numpy_twin(model, seed, tmp_path):
    _compare(model, seed, tmp_path)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("model", ["BLINN_PHONG", "PBR"])
def test_gpu_matches_numpy_twin_with_sphere_lights(model, seed, tmp_path):
    """Point and spot lights with a radius, with and without soft falloff."""
    _compare(model, seed + 100, tmp_path, sizes=True)


#: The Principled BSDF's socket of each of MaterialParams' lobe fields (``_compare``'s ``lobes``).
LOBE_SOCKETS = {"specular_tint": "Specular Tint", "coat_weight": "Coat Weight",
                "coat_roughness": "Coat Roughness", "coat_ior": "Coat IOR", "coat_tint": "Coat Tint",
                "sheen_weight": "Sheen Weight",
                "sheen_roughness": "Sheen Roughness", "sheen_tint": "Sheen Tint",
                "thin_film_thickness": "Thin Film Thickness", "thin_film_ior": "Thin Film IOR"}


def _compare(model, seed, tmp_path, sizes=False, lobes=None):
    """``lobes``: the Principled BSDF's lobe inputs (MaterialParams' fields -> values) of the
    material's surface, drawn by the Principled term set (else the scene's default terms); fields
    without a socket (LOBE_SOCKETS) are the twin's alone (what the reader sets itself)."""
    rng = np.random.default_rng(1000 * seed + len(model))
    tilt, mat, lights = _random_case(rng, sizes)
    scene = scenes.reset(size=SIZE)
    scene.shading_lab.model = model
    scene.shading_lab.ambient = 0.05
    scenes.ortho_camera(scene, scale=SCALE)
    material = scenes.material(**mat)
    terms = S.Terms()
    if lobes:
        terms = S.Terms(principled=True)
        scene.shading_lab.term_set = "PRINCIPLED"
        bsdf = next(n for n in scenes.node_tree(material).nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        for field, value in lobes.items():
            if field not in LOBE_SOCKETS:
                continue
            rgba = (*value, 1.0) if isinstance(value, tuple) else value
            bsdf.inputs[LOBE_SOCKETS[field]].default_value = rgba
    scenes.plane(scene, size=10.0, rotation=tilt, material=material)
    for props in lights:
        props = dict(props)
        kind = props.pop("kind")
        scenes.light(scene, kind, **props)
    got = scenes.render(scene, tmp_path / "gpu.exr")[..., :3].astype(np.float64)

    cam = np.eye(4)
    cam[:3, 3] = (0.0, 0.0, 5.0)
    origins, direction = scenes.ortho_pixel_rays(SIZE, SCALE, cam)
    normal = scenes.euler_matrix(tilt) @ np.array([0.0, 0.0, 1.0])
    p = scenes.intersect_plane(origins, direction, np.zeros(3), normal)
    v = np.broadcast_to(-direction, p.shape)
    n = np.broadcast_to(normal if normal @ -direction > 0 else -normal, p.shape)  # back face flip
    # Blinn-Phong's diffuse colour falls back to base x (1 - metalness) (addon/blender/extract.py)
    diffuse = tuple(c * (1.0 - mat["metalness"]) for c in mat["base_color"])
    surface = shading.Surface(p, n, v, S.MaterialParams(**mat, diffuse_color=diffuse, **(lobes or {})))
    twin_lights = _reaches([_twin_light(dict(props)) for props in lights], tilt)
    want = shading.shade(model, surface, twin_lights, ambient=0.05, terms=terms)

    assert np.all(np.isfinite(got))
    scale = max(float(want.max()), 1e-3)
    err = np.abs(got - want)
    print(f"{model} seed {seed}: max abs error {err.max():.3g} (scale {scale:.3g}), "
          f"max relative {np.max(err / np.maximum(want, 1e-3 * scale)):.3g}")
    # float32 agreement: 1e-4 of the image's range everywhere, 1e-3 relative per pixel
    assert err.max() <= 1e-4 * scale
    assert np.all(err <= 1e-3 * want + 1e-5 * scale)
