"""The Principled BSDF's Diffuse Roughness (Blender 4.3 and later): its diffuse base drawn as Cycles 5.0
draws it, the Diffuse BSDF's Oren-Nayar (Fujii's improved model with OpenPBR's multiple scattering:
glsl/closures.glsl, twin addon/reference/closures.py), through the constant path (a Principled BSDF
with nothing linked: MaterialParams -> the material block) and a node graph (closure_principled).

Against Cycles (tests/test_principled_lobes.py's _lobe_against_cycles: direct light, pixel centres, no
bounces; each comparison also checks that the roughness changes Cycles' image by at least 5x our
error) under a sun, a point light, an area light and a uniform world; at its ends; in the white
furnace; only in the programs of materials that use it; named by Auto.
"""

from __future__ import annotations

import math

import bpy
import numpy as np
import pytest
import scenes
import test_world_light as TW
from test_cycles import _cycles
from test_material_render import _mix_colors, _scene, _within
from test_principled_lobes import FURNACE_ALL, _furnace_material, _graph, _lobe_against_cycles, _principled

from addon.blender import materials
from addon.plan import programs
from addon.scene import snapshot as S

#: Blender 4.2's Principled BSDF has no Diffuse Roughness (4.3 added it)
pytestmark = pytest.mark.skipif(bpy.app.version < (4, 3, 0),
                                reason="Blender 4.2's Principled BSDF has no Diffuse Roughness input")


def _swept(name="RoughSwept"):
    """A Principled BSDF (roughness 0.5) whose Base Color runs from orange to blue across u and whose
    Diffuse Roughness is v (0 .. 1): the node graph's path."""
    mat, tree, bsdf, u, v = _graph(name)
    tree.links.new(v, bsdf.inputs["Diffuse Roughness"])
    color = _mix_colors(tree, u, (0.9, 0.25, 0.1, 1.0), (0.2, 0.5, 0.9, 1.0))
    tree.links.new(color, bsdf.inputs["Base Color"])
    return mat


def _constant(roughness, name="RoughClay", **inputs):
    """A Principled BSDF of this Diffuse Roughness, nothing linked: the constant path."""
    return _principled(name, base_color=(0.8, 0.4, 0.2, 1.0), roughness=0.5, diffuse_roughness=roughness,
                       **inputs)


#: name -> (material, lights)
CASES = {
    "graph-0-to-1": (_swept, ("SUN", "POINT")),
    "constant-0.5": (lambda: _constant(0.5), ("SUN", "POINT")),
    "constant-1-back": (lambda: _constant(1.0), ("POINT", "BACK")),
    "constant-1-area": (lambda: _constant(1.0), ("AREA",)),
    "coated": (lambda: _constant(1.0, "CoatedRough", coat_weight=1.0, coat_roughness=0.2), ("SUN", "POINT")),
}
#: (mean, 99th percentile) relative error of the lit pixels (under the area light: over the lit pixels'
#: mean), measured with bpy 5.0.1. The area light: Oren-Nayar's t and n.l averaged over 16 points of
#: the light (closures.glsl's oren_nayar_polygon); at the light's representative direction alone
#: 1.18 % / 12.5 % (test_area_light_at_the_silhouette)
MEASURED = {"graph-0-to-1": (2.08e-4, 2.48e-3), "constant-0.5": (1.89e-4, 1.75e-3),
            "constant-1-back": (4.05e-4, 4.62e-3), "constant-1-area": (4.04e-3, 2.06e-2),
            "coated": (3.37e-4, 1.48e-3)}


@pytest.mark.parametrize("case", CASES)
def test_diffuse_roughness_matches_cycles(case, tmp_path):
    """Ours against Cycles within 3x what was measured; Cycles' image of Diffuse Roughness 0 (Lambert)
    differs from it by at least 5x our error (the 99th percentiles); EEVEE beside (the graph)."""
    make, lights = CASES[case]
    _lobe_against_cycles(make, {"Diffuse Roughness": 0.0}, MEASURED[case], f"diffuse roughness, {case}",
                         tmp_path, eevee=case == "graph-0-to-1", lights=lights)


#: The area light's (test_area_light_at_the_silhouette) silhouette facing it: (mean, largest) of the
#: pixels' own relative error, measured with bpy 5.0.1 (at the light's direction alone: 1.8 %, 9.5 %)
SILHOUETTE_MEASURED = (5.2e-3, 8.5e-3)


def test_area_light_at_the_silhouette(tmp_path):
    """Diffuse Roughness 1 under the 0.6 m square light (_lobe_against_cycles' "AREA") where the view
    grazes and the light is near: the sphere's pixels of n.v < 0.3 and n.l > 0.3 towards the light's
    centre (inside 97 % of its radius), each pixel's own relative error against Cycles (256 samples),
    within 3x what was measured; Diffuse Roughness 0 (Lambert) changes Cycles' image there by at least 5x
    our largest error."""
    scene, _ = _scene(lambda: _constant(1.0), lights=())
    centre = np.array([0.9, 0.7, 1.2])
    scenes.light(scene, "AREA", energy=150.0, location=tuple(centre),
                 rotation=(math.radians(-30.0), math.radians(35.0), 0.0), size=0.6)
    scene.cycles.light_sampling_threshold = 0.0
    ours = scenes.render(scene, tmp_path / "ours.exr")[..., :3].astype(np.float64)
    ref = _cycles(scene, tmp_path / "cycles.exr", samples=256)[..., :3].astype(np.float64)
    n = ref.shape[0]
    y, x = np.mgrid[0:n, 0:n]
    # the sphere (radius 0.9) in the orthographic view 2 m wide, rows top first
    px, py = (x + 0.5) / n * 2.0 - 1.0, 1.0 - (y + 0.5) / n * 2.0
    r2 = (px ** 2 + py ** 2) / 0.81
    normal = np.stack([px / 0.9, py / 0.9, np.sqrt(np.clip(1.0 - r2, 0.0, 1.0))], -1)
    to_light = centre - 0.9 * normal
    cos_l = np.sum(normal * to_light, -1) / np.linalg.norm(to_light, axis=-1)
    rim = (r2 < 0.97 ** 2) & (normal[..., 2] < 0.3) & (cos_l > 0.3) & (ref.max(-1) > 0.02 * ref.max())
    rel = np.abs(ours - ref).max(-1)[rim] / ref.max(-1)[rim]
    bsdf = next(n for n in scene.objects["Sphere"].data.materials[0].node_tree.nodes
                if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Diffuse Roughness"].default_value = 0.0
    lambert = _cycles(scene, tmp_path / "lambert.exr", samples=256)[..., :3].astype(np.float64)
    effect = np.abs(lambert - ref).max(-1)[rim] / ref.max(-1)[rim]
    print(f"area light, silhouette facing it ({rim.sum()} px): mean {rel.mean():.3%}, "
          f"largest {rel.max():.3%}; "
          f"Lambert differs there by {effect.mean():.2%} mean, {effect.min():.2%} least")
    assert rim.sum() >= 10, rim.sum()
    assert effect.mean() >= 5.0 * rel.max(), (effect.mean(), rel.max())
    assert rel.mean() <= 3.0 * SILHOUETTE_MEASURED[0] and rel.max() <= 3.0 * SILHOUETTE_MEASURED[1], \
        (rel.mean(), rel.max())


def world_lit(make, tmp_path, samples):
    """The sphere of ``make()``'s material in a uniform world (0.5), no lights, no occlusion, a
    transparent film: (scene, sphere, ours, Cycles' at ``samples``), RGBA."""
    scene, sphere = _scene(make, lights=())
    TW._world(scene, color=(0.5, 0.5, 0.5))
    scene.shading_lab.world_occlusion = False
    scene.render.film_transparent = True
    ours = scenes.render(scene, tmp_path / "ours.exr").astype(np.float64)
    ref = _cycles(scene, tmp_path / "cycles.exr", samples=samples).astype(np.float64)
    return scene, sphere, ours, ref


#: The world's light on it: (mean, 99th percentile) relative error against Cycles at WORLD_SAMPLES (its
#: noise included: at 512 samples 0.35 % / 2.1 %, as Lambert's 0.34 % / 1.9 %), measured with bpy 5.0.1
WORLD_MEASURED = (5.19e-3, 2.45e-2)
WORLD_SAMPLES = 256


def test_world_light_on_the_diffuse_roughness(tmp_path):
    """A uniform world (0.5) on the swept sphere (Diffuse Roughness 0 .. 1), no lights: the base's
    Oren-Nayar directional albedo at the view times the irradiance (exact for a uniform world), against
    Cycles; Diffuse Roughness 0 differs from it by at least 5x our error (the means: the p99 is Cycles'
    noise)."""
    scene, _, ours, ref = world_lit(_swept, tmp_path, WORLD_SAMPLES)
    inside = (ours[..., 3] > 0.999) & (ref[..., 3] > 0.999)
    lit = inside & (ref[..., :3].max(-1) > 0.02 * ref[..., :3].max())
    rel = np.abs(ours[..., :3] - ref[..., :3]).max(-1)[lit] / ref[..., :3].max(-1)[lit]
    bsdf = next(n for n in bpy.data.materials["RoughSwept"].node_tree.nodes
                if n.bl_idname == "ShaderNodeBsdfPrincipled")
    for link in list(bsdf.inputs["Diffuse Roughness"].links):
        bsdf.id_data.links.remove(link)
    bsdf.inputs["Diffuse Roughness"].default_value = 0.0
    lambert = _cycles(scene, tmp_path / "lambert.exr", samples=WORLD_SAMPLES).astype(np.float64)
    effect = np.abs(lambert[..., :3] - ref[..., :3]).max(-1)[lit] / ref[..., :3].max(-1)[lit]
    print(f"world light: the roughness changes Cycles' image by {effect.mean():.2%} mean, "
          f"{np.quantile(effect, 0.99):.2%} p99")
    assert effect.mean() >= 5.0 * rel.mean(), (effect.mean(), rel.mean())
    _within(rel, *WORLD_MEASURED, "world light on the Principled BSDF's Diffuse Roughness")


def test_roughness_0_is_lambert_and_the_lobe_only_where_used(tmp_path):
    """Diffuse Roughness 0 (a plain Principled BSDF) draws no Oren-Nayar lobe: no SL_DIFFUSE_ROUGHNESS
    program, Lambert; one linked to 0 (a node graph's lobe, Lambert per fragment) renders the same image
    to float rounding; a value above 0 or a link turns the lobe on (SL_CLOSURE_BSDFS with it), in the
    Principled set alone; the constant path's material rows hold what the graph's closure gives."""

    def linked_zero():
        mat, tree, bsdf, u, v = _graph("LinkedZero")
        zero = tree.nodes.new("ShaderNodeMath")
        zero.operation = "MULTIPLY"
        zero.inputs[1].default_value = 0.0
        tree.links.new(u, zero.inputs[0])
        tree.links.new(zero.outputs[0], bsdf.inputs["Diffuse Roughness"])
        bsdf.inputs["Base Color"].default_value = (0.8, 0.4, 0.2, 1.0)
        return mat

    images = {}
    for name, make, lobed in (("plain", lambda: _constant(0.0, "Plain"), False),
                              ("linked-zero", linked_zero, True),
                              ("constant", lambda: _constant(0.7, "Constant"), True)):
        scene, sphere = _scene(make)
        params = materials.material_params(sphere.data.materials[0])
        assert ("DIFFUSE_ROUGHNESS" in params.lobes) == lobed, (name, params.lobes)
        images[name] = scenes.render(scene, tmp_path / f"{name}.exr")[..., :3]
        principled = programs.Features("PBR", 1, frozenset({"SUN"}), S.Terms(principled=True),
                                       lobes=params.lobes)
        defines = dict(principled.defines())
        assert ("SL_DIFFUSE_ROUGHNESS" in defines) == lobed and ("SL_CLOSURE_BSDFS" in defines) == lobed, name
        other = programs.Features("PBR", 1, frozenset({"SUN"}), S.Terms(), lobes=params.lobes)
        assert "SL_DIFFUSE_ROUGHNESS" not in dict(other.defines()), name
    diff = float(np.abs(images["plain"] - images["linked-zero"]).max())
    print(f"Lambert against Diffuse Roughness linked to 0: largest difference {diff:.3g}")
    assert diff <= 1e-6 * float(images["plain"].max()), diff


def test_constant_path_equals_the_graph(tmp_path):
    """The constant path (MaterialParams' diffuse_roughness and pack_material's multiple scattering,
    addon/reference/closures.py's oren_nayar_ms) and a node graph giving the same values (a Value node
    linked to Diffuse Roughness: glsl/node_closure.glsl's closure_oren_nayar) render the same image."""
    def graph():
        mat, tree, bsdf, u, v = _graph("Linked")
        value = tree.nodes.new("ShaderNodeValue")
        value.outputs[0].default_value = 0.6
        tree.links.new(value.outputs[0], bsdf.inputs["Diffuse Roughness"])
        bsdf.inputs["Base Color"].default_value = (0.8, 0.4, 0.2, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.5
        return mat

    images = []
    for make in (lambda: _constant(0.6, "Constant"), graph):
        scene, _ = _scene(make)
        TW._world(scene, color=(0.2, 0.3, 0.4))
        images.append(scenes.render(scene, tmp_path / f"{len(images)}.exr")[..., :3].astype(np.float64))
    diff = float(np.abs(images[0] - images[1]).max() / images[0].max())
    print(f"constant path against the graph: {diff:.3g} of the image's largest value")
    assert diff <= 1e-5, diff


def test_extremes_stay_finite_and_the_white_furnace_holds(tmp_path):
    """Diffuse Roughness 0 .. 1 across the sphere (a node graph; also beyond: -1 and 2, clamped as Cycles
    clamps it) under a sun, a point light touching the sphere and a world: finite, not negative. A white
    Principled BSDF of Diffuse Roughness 1 with every other lobe on (test_principled_lobes' FURNACE_ALL)
    in a white world reflects at most the world's radiance."""
    def beyond():
        mat, tree, bsdf, u, v = _graph("Beyond")
        stretch = tree.nodes.new("ShaderNodeMapRange")
        stretch.clamp = False
        tree.links.new(v, stretch.inputs["Value"])
        stretch.inputs["To Min"].default_value = -1.0
        stretch.inputs["To Max"].default_value = 2.0
        tree.links.new(stretch.outputs["Result"], bsdf.inputs["Diffuse Roughness"])
        return mat

    for name, make in (("swept", _swept), ("beyond", beyond)):
        scene, _ = _scene(make)
        scenes.light(scene, "POINT", energy=1e6, location=(0.0, 0.0, 0.9))  # on the sphere's top
        TW._world(scene, color=(0.3, 0.3, 0.3))
        image = scenes.render(scene, tmp_path / f"{name}.exr")[..., :3]
        print(f"{name}: range {image.min():.3g} .. {image.max():.3g}")
        assert np.isfinite(image).all() and image.min() >= 0.0, name
    scene = scenes.reset(size=32)
    scene.render.film_transparent = True
    scene.shading_lab.model = "PBR"
    scene.shading_lab.term_set = "PRINCIPLED"
    scene.shading_lab.world_occlusion = False
    TW._world(scene, color=(1.0, 1.0, 1.0))
    scenes.ortho_camera(scene, location=(0.0, 0.0, 10.0), scale=2.0)
    mat = _furnace_material("RoughFurnace", FURNACE_ALL, base_color=(1.0, 1.0, 1.0), roughness=1.0,
                            diffuse_roughness=1.0)
    TW._sphere((0.0, 0.0, 0.0), mat, radius=0.95)
    image = scenes.render(scene, tmp_path / "furnace.exr")
    top = float(image[..., :3][image[..., 3] > 0.999].max())
    print(f"the white furnace with Diffuse Roughness 1 and every lobe: at most {top:.4f}")
    assert 0.9 <= top <= 1.0 + 1e-3, top


def test_auto_names_the_oren_nayar_diffuse():
    """Auto gives a Principled BSDF of Diffuse Roughness above 0 the Principled set (the only one drawing
    its Oren-Nayar), naming it."""
    from addon.blender import extract

    scene, _ = _scene(lambda: _constant(0.8, "AutoRough"))
    scene.shading_lab.term_set = "AUTO"
    snap = extract.snapshot(bpy.context.evaluated_depsgraph_get(), 256, 256)
    choice = next(c for key, c in snap.term_choices.items() if key.startswith("AutoRough"))
    print(choice)
    assert choice.name == "PRINCIPLED" and choice.limiting == "Oren-Nayar diffuse", choice
