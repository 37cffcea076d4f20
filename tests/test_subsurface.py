"""The Translucent BSDF and the Principled BSDF's subsurface (glsl/subsurface.glsl, twin
addon/reference/subsurface.py): against closed forms, against Cycles (direct light; the subsurface
by Cycles' own random walk, which needs no bounce beyond the camera's: max_bounces 0), and at their
extremes.

Cycles' settings: tests/test_cycles.py's _cycles (CPU, no bounces, a 0.01 px Gaussian filter: pixel
centres, no light tree), light_sampling_threshold 0; the random walk's noise needs samples (below).
"""

from __future__ import annotations

import math

import bpy
import numpy as np
import scenes
from test_cycles import _cycles
from test_material_render import _scene, _tree

from addon.plan import programs
from addon.scene import snapshot as S

SIZE = 48

# --- the Translucent BSDF ---------------------------------------------------------------------------


def _translucent_plane(color=(0.6, 0.4, 0.2, 1.0), mix_diffuse=0.0):
    """A 2 m open plane facing the camera (+z), its surface a Translucent BSDF of ``color`` (mixed
    with a white Diffuse BSDF by ``mix_diffuse``)."""
    scene = scenes.reset(size=SIZE)
    scene.shading_lab.model = "PBR"
    scene.shading_lab.term_set = "PRINCIPLED"
    scenes.ortho_camera(scene, location=(0.0, 0.0, 3.0), scale=1.6)
    mat, tree, out = _tree("Translucent")
    node = tree.nodes.new("ShaderNodeBsdfTranslucent")
    node.inputs["Color"].default_value = color
    shader = node.outputs["BSDF"]
    if mix_diffuse:
        diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = mix_diffuse
        tree.links.new(shader, mix.inputs[1])
        tree.links.new(diffuse.outputs["BSDF"], mix.inputs[2])
        shader = mix.outputs["Shader"]
    tree.links.new(shader, out.inputs["Surface"])
    scenes.plane(scene, size=2.0, material=mat)
    return scene


#: A sun from behind the plane, 30 degrees off its normal: Blender's sun shines along its -z, turned
#: by 150 degrees about x it shines up through the plane's back
BEHIND = math.radians(150.0)


def test_translucent_plane_lit_from_behind_is_its_closed_form(tmp_path):
    """A Translucent plane under a sun of 3 W/m^2 from behind at 30 degrees: colour x 3 cos 30 / pi
    at every pixel (Cycles' bsdf_translucent_eval), exactly up to float32, and nothing from the front;
    a point light behind it whose shadow map sees the plane itself: a thin open plane is lit (its
    own depth in the map is the receiver's: no self-shadow)."""
    color = np.array([0.6, 0.4, 0.2])
    scene = _translucent_plane(tuple(color) + (1.0,))
    scenes.light(scene, "SUN", energy=3.0, rotation=(BEHIND, 0.0, 0.0))
    image = scenes.render(scene, tmp_path / "sun.exr")[..., :3].astype(np.float64)
    expected = color * 3.0 * math.cos(math.radians(30.0)) / math.pi
    error = float(np.abs(image - expected).max() / expected.max())
    print(f"translucent plane, sun from behind: {error:.2e} of the closed form")
    assert error < 1e-5, error
    front = _translucent_plane(tuple(color) + (1.0,))
    scenes.light(front, "SUN", energy=3.0, rotation=(math.radians(30.0), 0.0, 0.0))
    assert float(np.abs(scenes.render(front, tmp_path / "front.exr")[..., :3]).max()) == 0.0
    # a point light 1 m behind the plane's centre, casting shadows (its cube map holds the plane)
    point = _translucent_plane(tuple(color) + (1.0,))
    scenes.light(point, "POINT", energy=100.0, location=(0.0, 0.0, -1.0), use_shadow=True)
    image = scenes.render(point, tmp_path / "point.exr")[..., :3].astype(np.float64)
    x = (np.arange(SIZE) + 0.5) / SIZE * 1.6 - 0.8  # the ortho camera's pixel centres (m)
    xx, yy = np.meshgrid(x, -x)
    d2 = xx * xx + yy * yy + 1.0
    expected = color * (100.0 / (4.0 * math.pi * math.pi) / d2 * (1.0 / np.sqrt(d2)))[..., None]
    error = float(np.abs(image - expected).max() / expected.max())
    print(f"translucent plane, shadowed point light behind: {error:.2e} of the closed form")
    assert error < 1e-4, error


#: (mean, 99th percentile) relative error of the lit pixels against Cycles, measured with bpy 5.0.1
TRANSLUCENT_MEASURED = (4.66e-4, 8.77e-3)


def test_translucent_mixed_with_diffuse_matches_cycles(tmp_path):
    """A sphere whose surface mixes a Translucent BSDF with a Diffuse BSDF (Fac 0.4), under a point
    light in front and a sun from behind: the translucent lobe lights the far side (against Cycles,
    the lobe's effect at least 5x our error)."""
    def make():
        mat, tree, out = _tree("HalfTranslucent")
        node = tree.nodes.new("ShaderNodeBsdfTranslucent")
        node.inputs["Color"].default_value = (0.3, 0.8, 0.4, 1.0)
        diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (0.8, 0.3, 0.2, 1.0)
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = 0.4
        tree.links.new(node.outputs["BSDF"], mix.inputs[1])
        tree.links.new(diffuse.outputs["BSDF"], mix.inputs[2])
        tree.links.new(mix.outputs["Shader"], out.inputs["Surface"])
        return mat

    scene, _ = _scene(make, lights=("POINT",))
    scenes.light(scene, "SUN", energy=3.0, rotation=(math.radians(160.0), 0.0, 0.0))
    ours = scenes.render(scene, tmp_path / "ours.exr")[..., :3].astype(np.float64)
    ref = _cycles(scene, tmp_path / "cycles.exr", samples=4)[..., :3].astype(np.float64)
    lit = ref.max(-1) > 0.02 * ref.max()
    rel = np.abs(ours - ref).max(-1)[lit] / ref.max(-1)[lit]
    for node in bpy.data.materials["HalfTranslucent"].node_tree.nodes:
        if node.bl_idname == "ShaderNodeBsdfTranslucent":
            node.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    without = _cycles(scene, tmp_path / "without.exr", samples=4)[..., :3].astype(np.float64)
    effect = np.abs(without - ref).max(-1)[lit] / ref.max(-1)[lit]
    mean, p99 = float(rel.mean()), float(np.quantile(rel, 0.99))
    print(f"translucent + diffuse sphere: mean {mean:.3e}, p99 {p99:.3e}; the lobe changes Cycles' image "
          f"by {effect.mean():.2%} mean")
    assert float(np.quantile(effect, 0.99)) >= 5.0 * p99
    assert mean <= 3.0 * TRANSLUCENT_MEASURED[0] and p99 <= 3.0 * TRANSLUCENT_MEASURED[1], (mean, p99)


def test_translucent_lobe_compiles_only_where_used():
    """SL_TRANSLUCENT only in programs of a graph with a Translucent BSDF; elsewhere (another model)
    the node is drawn as a diffuse of its colour."""
    assert "TRANSLUCENT" in S.LOBES
    plain = programs.Features("PBR", 1, frozenset({"SUN"}), S.Terms(principled=True))
    assert not any(name == "SL_TRANSLUCENT" for name, _ in plain.defines())
    lobed = programs.Features("PBR", 1, frozenset({"SUN"}), S.Terms(principled=True),
                              lobes=frozenset({"TRANSLUCENT"}))
    assert ("SL_TRANSLUCENT", "1") in lobed.defines() and not lobed.deferred
