"""The same scene rendered by Cycles and by Shading Lab, for point, spot and sun lights.

Cycles is set up to compute what the engine computes: direct light only (max bounces 0), shadows
off (these tests measure the shading; tests/test_shadows.py measures shadows), point and spot
radius 0 (a true point light; tests/test_light_shapes.py has sizes), soft falloff off,
pixel-centre sampling (a Gaussian filter of width 0.01 px; Cycles' Box filter would average the
whole pixel), a black world. One light per render, so Cycles' light selection adds no noise.
(a) a Diffuse BSDF plane: Shading Lab reads it as F0 = 0 (pure Lambert);
(b) a Glossy BSDF plane with GGX: read as a white metal, F0 = 1 so F = 1, alpha = roughness^2.
"""

from __future__ import annotations

import math

import bpy
import numpy as np
import pytest
import scenes

SIZE = 64
LIGHTS = {
    "POINT": dict(energy=200.0, location=(0.25, 0.1, 0.8)),
    "SPOT": dict(energy=400.0, location=(-0.1, 0.2, 1.2), rotation=(math.radians(15.0), 0.0, 0.0),
                 spot_size=math.radians(50.0), spot_blend=0.4),
    "SUN": dict(energy=4.0, rotation=(math.radians(35.0), math.radians(10.0), 0.0)),
}


def _material(kind: str) -> bpy.types.Material:
    mat = bpy.data.materials.new(kind)
    tree = mat.node_tree if mat.node_tree is not None else None
    if tree is None:
        mat.use_nodes = True
        tree = mat.node_tree
    tree.nodes.clear()
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    if kind == "diffuse":
        bsdf = tree.nodes.new("ShaderNodeBsdfDiffuse")
        bsdf.inputs["Color"].default_value = (0.8, 0.7, 0.6, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.0
    else:
        bsdf = tree.nodes.new("ShaderNodeBsdfGlossy")
        bsdf.distribution = "GGX"
        bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.45
    tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return mat


def _scene(material_kind: str, light_kind: str):
    scene = scenes.reset(size=SIZE)
    scene.shading_lab.model = "PBR"
    scenes.ortho_camera(scene, location=(0.0, 0.0, 3.0), scale=2.0)
    scenes.plane(scene, size=4.0, rotation=(math.radians(10.0), 0.0, 0.0), material=_material(material_kind))
    scenes.light(scene, light_kind, **LIGHTS[light_kind])
    return scene


def ours_and_cycles(scene, tmp_path):
    """(ours, Cycles, lit mask, relative luminance error on lit pixels) for the same scene."""
    ours = scenes.render(scene, tmp_path / "ours.exr")[..., :3].astype(np.float64)
    ref = _cycles(scene, tmp_path / "cycles.exr")[..., :3].astype(np.float64)
    lum_ref, lum_ours = ref.mean(-1), ours.mean(-1)
    lit = lum_ref > 0.02 * lum_ref.max()
    return ours, ref, lit, np.abs(lum_ours[lit] - lum_ref[lit]) / lum_ref[lit]


def _cycles(scene, path, samples=4):
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = samples  # deterministic direct light needs few; stochastic transparency more
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.max_bounces = 0
    c.pixel_filter_type = "GAUSSIAN"
    c.filter_width = 0.01
    c.use_light_tree = False
    c.seed = 1
    return scenes.render(scene, path)


def _within(value: float, measured: float, what: str, factor: float = 3.0, floor: float = 1e-5) -> None:
    """``value`` at most ``factor`` times what was measured (plus ``floor`` for a measured 0)."""
    assert value <= factor * measured + floor, f"{what}: {value:.4%} (measured {measured:.4%})"


#: Mean and max relative error on lit pixels measured at 64 px with bpy 5.0.1 (bounds: 3x).
MEASURED = {("diffuse", "POINT"): (4.3e-5, 6.75e-3), ("diffuse", "SPOT"): (2.73e-4, 1.342e-2),
            ("diffuse", "SUN"): (0.0, 0.0), ("glossy", "POINT"): (1.15e-4, 1.305e-2),
            ("glossy", "SPOT"): (2.46e-4, 1.52e-2), ("glossy", "SUN"): (6e-6, 6e-6)}


@pytest.mark.parametrize("light_kind", ["POINT", "SPOT", "SUN"])
@pytest.mark.parametrize("material_kind", ["diffuse", "glossy"])
def test_matches_cycles(material_kind, light_kind, tmp_path):
    scene = _scene(material_kind, light_kind)
    ours = scenes.render(scene, tmp_path / "ours.exr")[..., :3].astype(np.float64)
    ref = _cycles(scene, tmp_path / "cycles.exr")[..., :3].astype(np.float64)

    lum_ref, lum_ours = ref.mean(-1), ours.mean(-1)
    lit = lum_ref > 0.02 * lum_ref.max()
    assert lit.mean() > 0.2, "most of the frame must be lit for the comparison to mean anything"
    rel = np.abs(lum_ours[lit] - lum_ref[lit]) / lum_ref[lit]
    print(f"{material_kind}/{light_kind}: mean relative error {rel.mean():.4%}, "
          f"max {rel.max():.4%}, over {lit.sum()} lit pixels")
    mean, largest = MEASURED[material_kind, light_kind]
    # Cycles 4.x's spot cone edge differs from Cycles 5.0's: in this scene the two Cycles disagree
    # by 8.0 % on the outermost lit pixel (mean 0.05 %); ours agrees with 5.0 there to 0.1 %.
    edge_slack = light_kind == "SPOT" and bpy.app.version < (5, 0, 0)
    _within(rel.mean(), 0.0007 if edge_slack else mean, "mean")
    _within(rel.max(), 0.10 if edge_slack else largest, "max", factor=1.0 if edge_slack else 3.0)
    # colour: each channel agrees too, not only the mean
    chan = np.abs(ours[lit] - ref[lit]) / np.maximum(ref[lit], 1e-6)
    assert np.median(chan) <= 0.02
    # unlit pixels stay unlit (the spot's cone, the plane's back side)
    assert np.all(lum_ours[lum_ref == 0.0] < 0.01 * lum_ref.max())


@pytest.mark.parametrize("distribution,terms", [
    ("BECKMANN", dict(ndf="BECKMANN")),
    ("MULTI_GGX", dict(multiscatter=True)),
])
@pytest.mark.parametrize("roughness", [0.3, 0.8])
def test_glossy_distributions_match_cycles(distribution, terms, roughness, tmp_path):
    """Cycles' Glossy BSDF with its other distributions against the matching Shading Lab terms:
    Beckmann with Smith height-correlated masking, and GGX with multiple-scattering compensation
    (Cycles' Multiscatter GGX, white: f_ss / E(mu_o); ours: 1 + F0 (1 / E - 1) with F0 = 1)."""
    scene = _scene("glossy", "POINT")
    for name, value in terms.items():
        setattr(scene.shading_lab, name, value)
    mat = bpy.data.materials["glossy"]
    glossy = next(n for n in mat.node_tree.nodes if n.bl_idname in ("ShaderNodeBsdfGlossy",
                                                                   "ShaderNodeBsdfAnisotropic"))
    glossy.distribution = distribution
    glossy.inputs["Roughness"].default_value = roughness
    ours = scenes.render(scene, tmp_path / "ours.exr")[..., :3].mean(-1).astype(np.float64)
    ref = _cycles(scene, tmp_path / "cycles.exr")[..., :3].mean(-1).astype(np.float64)
    lit = ref > 0.02 * ref.max()
    rel = np.abs(ours[lit] - ref[lit]) / ref[lit]
    print(f"{distribution} r={roughness}: mean relative error {rel.mean():.4%}, max {rel.max():.4%}")
    assert lit.sum() > 200, "the highlight must cover enough pixels to compare"
    # measured (mean, max) with bpy 5.0.1, 2026-12-06; Cycles 4.2 and 4.5 differ on the r = 0.3
    # highlight's outermost lit pixels: max 8.74 % (Beckmann), 4.26 % (multiscatter GGX)
    mean, largest = {("BECKMANN", 0.3): (3.95e-4, 3.23e-3), ("MULTI_GGX", 0.3): (2.71e-4, 7.99e-3),
                     ("BECKMANN", 0.8): (3.5e-5, 5.79e-3), ("MULTI_GGX", 0.8): (4.5e-5, 7.45e-3)}[
        distribution, roughness]
    if bpy.app.version < (5, 0, 0) and roughness == 0.3:
        mean, largest = {"BECKMANN": (6.9e-4, 8.74e-2), "MULTI_GGX": (3.3e-4, 4.26e-2)}[distribution]
    _within(rel.mean(), mean, "mean")
    _within(rel.max(), largest, "max", factor=1.5 if bpy.app.version < (5, 0, 0) else 3.0)


def _principled(base, metallic, roughness, ior=1.5):
    from addon.blender.scene_builder import principled_material

    return principled_material("principled", base, metallic, roughness, ior)


@pytest.mark.parametrize("base,metallic,roughness", [
    ((0.8, 0.1, 0.05), 0.0, 0.5),  # red plastic
    ((0.9, 0.9, 0.9), 0.0, 0.25),  # white dielectric, glossy
    ((1.0, 0.71, 0.29), 1.0, 0.35),  # gold
    ((0.95, 0.64, 0.54), 1.0, 0.8),  # rough copper
    ((0.5, 0.5, 0.5), 0.5, 0.6),  # half metal
])
def test_principled_term_set_matches_cycles(base, metallic, roughness, tmp_path):
    """Principled BSDF scenes (Multiscatter GGX, the node's default) against the Principled term
    set: measured 0.004-0.016 % on lit pixels, bound 3x that."""
    scene = scenes.reset(size=SIZE)
    scene.shading_lab.model = "PBR"
    scene.shading_lab.term_set = "PRINCIPLED"
    scenes.ortho_camera(scene, location=(0.0, 0.0, 3.0), scale=2.0)
    scenes.plane(scene, size=4.0, rotation=(math.radians(10.0), 0.0, 0.0),
                 material=_principled(base, metallic, roughness))
    scenes.light(scene, "POINT", energy=200.0, location=(0.3, 0.2, 0.9))
    ours, ref, lit, rel = ours_and_cycles(scene, tmp_path)
    chan = np.abs(ours[lit] - ref[lit]) / np.maximum(ref[lit], 1e-6)
    print(f"principled {base} m={metallic} r={roughness}: mean relative error {rel.mean():.3%}, "
          f"max {rel.max():.3%}, per channel mean {chan.mean():.3%}")
    assert lit.sum() > 200
    # measured (mean, max) with bpy 5.0.1, 2026-12-06; Cycles 4.2 and 4.5: max 1.53 % (r 0.25),
    # 2.90 % (gold, r 0.35), the rest as 5.0
    mean, largest = {0.5: (5e-5, 6.69e-3), 0.25: (5e-5, 6.44e-3), 0.35: (1.6e-4, 9.38e-3),
                     0.8: (4e-5, 7.05e-3), 0.6: (6e-5, 7.76e-3)}[roughness]
    if bpy.app.version < (5, 0, 0):
        mean, largest = {0.25: (5e-5, 1.53e-2), 0.35: (2e-4, 2.9e-2)}.get(roughness, (mean, largest))
    _within(rel.mean(), mean, "mean")
    _within(rel.max(), largest, "max")


#: The emission scene's largest relative error, measured with bpy 5.0.1 (2026-12-06).
EMISSION_MAX = 9.21e-3


def test_emission_matches_cycles(tmp_path):
    """Principled Emission Color x Strength is emitted radiance, added to the lit surface."""
    scene = scenes.reset(size=SIZE)
    scene.shading_lab.term_set = "PRINCIPLED"
    scenes.ortho_camera(scene, location=(0.0, 0.0, 3.0), scale=2.0)
    mat = _principled((0.5, 0.4, 0.3), 0.0, 0.5)
    node = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    node.inputs["Emission Color"].default_value = (1.0, 0.5, 0.25, 1.0)
    node.inputs["Emission Strength"].default_value = 0.8
    scenes.plane(scene, size=4.0, material=mat)
    scenes.light(scene, "POINT", energy=100.0, location=(0.3, 0.2, 0.9))
    ours = scenes.render(scene, tmp_path / "ours.exr")[..., :3].astype(np.float64)
    ref = _cycles(scene, tmp_path / "cycles.exr")[..., :3].astype(np.float64)
    rel = np.abs(ours - ref) / ref
    print(f"emission: mean relative error {rel.mean():.3%}, max {rel.max():.3%}")
    assert ref[..., 2].min() > 0.8 * 0.25  # every pixel carries the emission
    _within(rel.mean(), 4e-5, "mean")  # measured 0.004 %
    _within(rel.max(), EMISSION_MAX, "max")


def _weak_lights_scene(powers):
    """A grey floor and a red sphere under weak point lights (a few watts, shadows on), seen in
    perspective, materials as Principled BSDFs, every other setting at its default."""
    scene = scenes.reset(size=96)
    scene.shading_lab.term_set = "PRINCIPLED"
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location, cam.rotation_euler = (0.0, -6.0, 4.0), (math.radians(56.0), 0.0, 0.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    scenes.plane(scene, size=12.0, material=_principled((0.6, 0.6, 0.6), 0.0, 0.5))
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.7, location=(0.0, 0.0, 0.7))
    bpy.ops.object.shade_smooth()
    bpy.context.active_object.data.materials.append(_principled((0.8, 0.3, 0.2), 0.0, 0.4))
    places = [(-2.0, -1.0, 1.5), (2.0, 0.5, 2.0), (-1.0, 3.0, 1.0), (3.0, 3.0, 2.5)]
    for power, location in zip(powers, places):
        scenes.light(scene, "POINT", energy=power, location=location, shadow_soft_size=0.1, use_shadow=True)
    return scene


#: (watts of each light) -> mean relative error on lit pixels of the Principled set against Cycles
#: at the default Light Threshold, measured 2026-12-06 (the same as with the threshold at 0; before
#: the threshold was scaled by the scene's brightness: 28.1 % with four lights).
WEAK_LIGHTS = {(2.0, 5.0): 0.00191, (2.0, 5.0, 3.0, 4.0): 0.00332}


@pytest.mark.parametrize("powers", WEAK_LIGHTS, ids=lambda p: f"{len(p)}-lights")
def test_weak_lights_at_the_default_threshold_match_cycles(powers, tmp_path):
    """Two and four weak lights (2-5 W) on a dim scene at the default settings: the default Light
    Threshold drops nothing that shows (each light reaches everywhere where there are two; with four
    the threshold is scaled by the scene's dim light): the Principled set's error against Cycles
    is what it is with the threshold at 0. Cycles' own light threshold is off (it drops these
    lights' samples at random)."""
    scene = _weak_lights_scene(powers)
    scene.cycles.light_sampling_threshold = 0.0
    ref = _cycles(scene, tmp_path / "cycles.exr", samples=16)[..., :3].mean(-1).astype(np.float64)
    scene.render.engine = "SHADING_LAB"
    lit = ref > 0.02 * ref.max()
    errors = {}
    for threshold in (scene.shading_lab.light_threshold, 0.0):
        scene.shading_lab.light_threshold = threshold
        ours = scenes.render(scene, tmp_path / f"ours{threshold}.exr")[..., :3].mean(-1).astype(np.float64)
        errors[threshold] = float((np.abs(ours[lit] - ref[lit]) / ref[lit]).mean())
    default, exact = errors.values()
    print(f"{len(powers)} weak lights: mean relative error {default:.3%} at the default threshold, "
          f"{exact:.3%} at 0")
    assert default <= 1.05 * exact, errors
    _within(default, WEAK_LIGHTS[powers], "mean")
