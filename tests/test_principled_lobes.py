"""The Principled BSDF's lobes beyond its base (glsl/principled.glsl): Specular Tint, Coat and Sheen,
against Cycles and in the numpy twin.

Each lobe is swept over its inputs on a sphere (a node graph drives them from the UV: the compiled
path) and at fixed values (the material's plain values: the constant path), under a sun and a point
light, direct light only (tests/test_material_render.py's scene and comparison: Cycles at pixel
centres, no bounces, the lights casting no shadow). The twin is held to closed forms and to the GPU,
and the lobes at their extremes stay finite and within the white furnace.
"""

from __future__ import annotations

import math

import bpy
import numpy as np
import pytest
import scenes
from test_cycles import _cycles
from test_material_render import _against_cycles, _mix_colors, _scene, _tree, _uv, _within
from test_twin import _compare as _twin_compare

from addon.reference import shading

# --- Specular Tint ------------------------------------------------------------------------------


def _tinted_graph(name="Tinted"):
    """Specular Tint from orange to cyan across u, Roughness = v (from 0.05), Metallic = 1 where
    u > 0.5 (a gold-ish base colour there): the dielectric's F0 tint and the metal's F82 edge tint."""
    mat, tree, out = _tree(name)
    bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
    tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    u, v = _uv(tree)
    tint = _mix_colors(tree, u, (1.0, 0.45, 0.1, 1.0), (0.1, 0.6, 1.0, 1.0))
    tree.links.new(tint, bsdf.inputs["Specular Tint"])
    rough = tree.nodes.new("ShaderNodeMapRange")
    tree.links.new(v, rough.inputs["Value"])
    rough.inputs["To Min"].default_value = 0.05
    tree.links.new(rough.outputs["Result"], bsdf.inputs["Roughness"])
    metal = tree.nodes.new("ShaderNodeMath")
    metal.operation = "GREATER_THAN"
    tree.links.new(u, metal.inputs[0])
    metal.inputs[1].default_value = 0.5
    tree.links.new(metal.outputs[0], bsdf.inputs["Metallic"])
    bsdf.inputs["Base Color"].default_value = (0.9, 0.6, 0.3, 1.0)
    return mat


def _principled(name, **inputs):
    """A material whose surface is one Principled BSDF with these input values (nothing linked:
    the constant path)."""
    mat, tree, out = _tree(name)
    bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
    tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    for socket, value in inputs.items():
        bsdf.inputs[socket.replace("_", " ").title().replace("Ior", "IOR")].default_value = value
    return mat


#: name -> (material, lights)
TINT_CASES = {
    "graph": (_tinted_graph, ("SUN", "POINT")),
    "dielectric": (lambda: _principled("TintedPlastic", base_color=(0.05, 0.05, 0.05, 1.0), roughness=0.3,
                                      specular_tint=(1.0, 0.2, 0.1, 1.0), specular_ior_level=1.0),
                   ("SUN", "POINT")),
    "metal": (lambda: _principled("TintedGold", base_color=(1.0, 0.78, 0.34, 1.0), metallic=1.0,
                                 roughness=0.2, specular_tint=(0.2, 0.3, 1.0, 1.0)),
              ("POINT", "BACK")),
}


#: (mean, 99th percentile) relative error of the lit pixels, measured with bpy 5.0.1
TINT_MEASURED = {"graph": (3.3e-4, 2.12e-3), "dielectric": (5.3e-4, 2.55e-3), "metal": (3.33e-3, 1.24e-2)}


@pytest.mark.parametrize("case", TINT_CASES)
def test_specular_tint_matches_cycles(case, tmp_path):
    make, lights = TINT_CASES[case]
    _lobe_against_cycles(make, {"Specular Tint": (1.0, 1.0, 1.0, 1.0)}, TINT_MEASURED[case],
                         f"specular tint, {case}", tmp_path, lights=lights, eevee=case == "graph")


# --- helpers ------------------------------------------------------------------------------------

def _principled_nodes(scene):
    return [n for m in bpy.data.materials if m.node_tree is not None for n in m.node_tree.nodes
            if n.bl_idname == "ShaderNodeBsdfPrincipled"]


def _lobe_against_cycles(make_material, off: dict, measured, what, tmp_path, eevee=False,
                         lights=("SUN", "POINT")):
    """Ours against Cycles (``_against_cycles``: relative error of the lit pixels) within 3x
    ``measured`` (mean, 99th percentile); the lobe must matter: Cycles with the lobe turned off
    (``off``: the Principled BSDF's inputs that do so, links to them removed) differs from Cycles
    with it by at least 5x our mean error. ``eevee``: EEVEE's error in the same measure, printed
    beside ours. ``lights``: _scene's, "BACK" a sun from behind, "AREA" a square area light."""
    scene, _ = _scene(make_material, lights=tuple(k for k in lights if k in ("SUN", "POINT")))
    if "BACK" in lights:  # a sun from behind the sphere, 20 degrees off the view's axis: its rim
        # seen at l.h ~ 0.17, where F82's edge term and the sheen peak
        scenes.light(scene, "SUN", energy=3.0, rotation=(math.radians(160.0), 0.0, 0.0))
    if "AREA" in lights:  # a 0.6 m square light 1.5 m away, up and to the right
        scenes.light(scene, "AREA", energy=150.0, location=(0.9, 0.7, 1.2),
                     rotation=(math.radians(-30.0), math.radians(35.0), 0.0), size=0.6)
    ours, ref, rel = _against_cycles(scene, tmp_path)
    lit = ref.max(-1) > 0.02 * ref.max()
    for node in _principled_nodes(scene):
        for socket, value in off.items():
            for link in list(node.inputs[socket].links):
                node.id_data.links.remove(link)
            node.inputs[socket].default_value = value
    without = _cycles(scene, tmp_path / "without.exr")[..., :3].astype(np.float64)
    effect = np.abs(without - ref).max(-1)[lit] / ref.max(-1)[lit]
    mean, q = float(effect.mean()), float(np.quantile(effect, 0.99))
    note = f"; the lobe changes Cycles' image by {mean:.2%} mean, {q:.2%} at the 99th percentile"
    if eevee:
        note += f"; EEVEE: mean {_eevee_error(scene, ref, tmp_path):.3%}"
    print(f"{what}{note}")
    ours_q = float(np.quantile(rel, 0.99))
    assert q >= 5.0 * ours_q, f"{what}: the lobe's effect {q:.3%} against our error {ours_q:.3%} (99th pct)"
    _within(rel, *measured, what)


EEVEE = "BLENDER_EEVEE" if bpy.app.version >= (5, 0, 0) else "BLENDER_EEVEE_NEXT"


def _eevee_error(scene, ref, tmp_path, samples=16) -> float:
    """EEVEE's mean relative error on the lit pixels of ``ref`` (Cycles'), in _against_cycles'
    measure, the scene as it is (its Shading Lab engine restored after)."""
    previous = scene.render.engine
    scene.render.engine = EEVEE
    scene.eevee.taa_render_samples = samples
    scene.eevee.light_threshold = 1e-6
    try:
        image = scenes.render(scene, tmp_path / "eevee.exr")[..., :3].astype(np.float64)
    finally:
        scene.render.engine = previous
    lit = ref.max(-1) > 0.02 * ref.max()
    return float((np.abs(image - ref).max(-1)[lit] / ref.max(-1)[lit]).mean())


def test_specular_tint_twin_closed_forms():
    """F82-tint is Schlick times the tint at cos = 1/7 and Schlick for a white tint; the tinted
    dielectric Fresnel is F0 x tint at normal incidence, 1 at grazing, the exact Fresnel when white."""
    f0 = np.array([[0.95, 0.64, 0.54], [0.04, 0.04, 0.04]])
    tint = np.array([[0.3, 0.8, 1.0], [1.0, 1.0, 1.0]])
    b = shading.F82_tint_b(f0, tint)
    c = np.array([1.0 / 7.0, 1.0 / 7.0])
    schlick = f0 + (1.0 - f0) * ((1.0 - c) ** 5)[:, None]
    np.testing.assert_allclose(shading.F_F82Tint(f0, b, c), schlick * tint, rtol=1e-12)
    cosines = np.linspace(0.0, 1.0, 11)
    white = shading.F82_tint_b(f0[:1], np.ones(3))
    np.testing.assert_allclose(shading.F_F82Tint(np.broadcast_to(f0[:1], (11, 3)), white, cosines),
                               f0[:1] + (1.0 - f0[:1]) * ((1.0 - cosines) ** 5)[:, None], rtol=1e-12)
    eta = np.full(11, 1.5)
    exact = shading.F_Dielectric(eta, cosines)
    np.testing.assert_allclose(shading.F_DielectricTinted(eta, np.full((11, 3), 0.04), cosines)[:, 0], exact,
                               rtol=1e-12, atol=1e-15)
    tinted = shading.F_DielectricTinted(eta, np.broadcast_to([0.04, 0.02, 0.0], (11, 3)), cosines)
    np.testing.assert_allclose(tinted[-1], [0.04, 0.02, 0.0], atol=1e-12)
    np.testing.assert_allclose(tinted[0], 1.0, atol=1e-12)


#: Lobe inputs for the GPU-vs-twin comparisons, by name
TWIN_LOBES = {"specular tint": dict(specular_tint=(0.9, 0.3, 0.05))}


@pytest.mark.parametrize("sizes", [False, True], ids=["points", "sphere-lights"])
@pytest.mark.parametrize("lobe", TWIN_LOBES)
def test_gpu_matches_twin(lobe, sizes, tmp_path):
    """The GPU against the numpy twin on test_twin's random planes and lights (every kind, area
    lights of every shape and spread; point and spot lights with a radius), the Principled set
    with the lobe on: float32 agreement, 1e-4 of the image's range, 1e-3 relative per pixel."""
    for seed in range(3):
        _twin_compare("PBR", 500 + seed + (100 if sizes else 0), tmp_path / str(seed), sizes=sizes,
                      lobes=TWIN_LOBES[lobe])
