"""Partly transparent surfaces blend per pixel in depth order (depth peeling), not per object.

Closed forms: surfaces of coverage a and radiance L stack as L = a1 L1 + (1 - a1)(a2 L2 + (1 - a2)
L_behind), nearest first. Two scenes defeat any per-object order: two planes crossing in an X
(each is in front on one side of the crossing), and one mesh whose front face comes first in its
face order (a renderer blending in index order puts the back face over the front one).
"""

from __future__ import annotations

import math

import bpy
import numpy as np
import pytest
import scenes
from gpu_harness import run_on_gpu, viewport_image

from addon.blender import extract
from addon.blender.scene_builder import principled_material
from addon.frame import renderer

SIZE = 32
RED, BLUE = np.array([0.8, 0.0, 0.0]), np.array([0.0, 0.0, 0.6])  # emitted radiance


def emitter(name, emission, alpha) -> bpy.types.Material:
    """No reflection (black base, no specular): the surface's radiance is its emission."""
    material = principled_material(name, (0.0, 0.0, 0.0))
    node = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    node.inputs["Specular IOR Level"].default_value = 0.0
    node.inputs["Emission Color"].default_value = (*emission, 1.0)
    node.inputs["Emission Strength"].default_value = 1.0
    node.inputs["Alpha"].default_value = alpha
    return material


def crossing_planes(layers=4, tilt=30.0):
    """Plane A (red, a 0.5) rises towards +x, plane B (blue, a 0.7) towards -x; the camera looks
    down -z, so A is in front right of the crossing, B left of it. Black world, no light."""
    scene = scenes.reset(size=SIZE)
    scenes.ortho_camera(scene, scale=2.0)
    scene.shading_lab.transparency_layers = layers
    t = math.radians(tilt)
    scenes.plane(scene, size=4.0, rotation=(0.0, -t, 0.0), material=emitter("A", RED, 0.5))
    scenes.plane(scene, size=4.0, rotation=(0.0, t, 0.0), material=emitter("B", BLUE, 0.7))
    return scene


def pixel_x(size=SIZE, scale=2.0):
    return (np.arange(size) + 0.5) / size * scale - scale / 2.0


def expected_crossing(layers=4):
    x = pixel_x()
    a_front = np.broadcast_to((x > 0)[None, :, None], (SIZE, SIZE, 1))
    over = {  # nearest layer first; layers beyond the limit are left out
        True: [(0.5, RED), (0.7, BLUE)],
        False: [(0.7, BLUE), (0.5, RED)],
    }
    out = np.zeros((SIZE, SIZE, 3))
    for front, stack in over.items():
        value, through = np.zeros(3), 1.0
        for a, radiance in stack[:layers]:
            value = value + through * a * radiance
            through *= 1.0 - a
        out = np.where(a_front == front, value, out)
    return out


def away_from_crossing(size=SIZE):
    return np.abs(pixel_x(size)) > 2.0 / size  # the pixels whose centre is not on the crossing line


@pytest.mark.parametrize("layers", [4, 1])
def test_crossing_transparent_planes_blend_in_depth_order_per_pixel(tmp_path, layers):
    got = scenes.render(crossing_planes(layers), tmp_path / "x.exr")[..., :3]
    want = expected_crossing(layers)
    keep = away_from_crossing()
    np.testing.assert_allclose(got[:, keep], want[:, keep], atol=1e-5)
    # both orders occur in one image: no order of whole objects can produce it
    assert got[:, ~keep].size and abs(got[0, -1, 0] - 0.4) < 1e-5 and abs(got[0, 0, 2] - 0.42) < 1e-5


def test_viewport_blends_in_depth_order_too():
    crossing_planes()
    shown = viewport_image(bpy.context.scene, SIZE)
    keep = away_from_crossing()
    np.testing.assert_allclose(shown[:, keep, :3], expected_crossing()[:, keep], atol=2e-3)  # RGBA16F


def test_one_mesh_folded_over_itself_blends_front_over_back(tmp_path):
    """One object, one material: a front quad (z 0.5, faces 0) and a back quad (z 0, face 1),
    textured red and blue (base colour image, Lambert, a sun straight down with E = pi: radiance
    = albedo), coverage 0.5. Expected 0.5 red + 0.25 blue; index order would give the reverse."""
    scene = scenes.reset(size=SIZE)
    scenes.ortho_camera(scene, scale=2.0)
    verts = [(-2, -2, 0.5), (2, -2, 0.5), (2, 2, 0.5), (-2, 2, 0.5),
             (-2, -2, 0.0), (2, -2, 0.0), (2, 2, 0.0), (-2, 2, 0.0)]
    mesh = bpy.data.meshes.new("Folded")
    mesh.from_pydata(verts, [], [(0, 1, 2, 3), (4, 5, 6, 7)])
    uv = mesh.uv_layers.new(name="UVMap")
    # front quad samples the left (red) texel, back quad the right (blue) one
    uv.data.foreach_set("uv", np.array([(0.25, 0.5)] * 4 + [(0.75, 0.5)] * 4, np.float32).ravel())
    image = bpy.data.images.new("two", 2, 1, alpha=True, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    image.pixels.foreach_set(np.array([0.8, 0.1, 0.1, 1.0, 0.1, 0.2, 0.9, 1.0], np.float32))
    material = principled_material("Folded", (1.0, 1.0, 1.0))
    node = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    node.inputs["Specular IOR Level"].default_value = 0.0
    node.inputs["Alpha"].default_value = 0.5
    tex = material.node_tree.nodes.new("ShaderNodeTexImage")
    tex.image, tex.interpolation = image, "Closest"
    material.node_tree.links.new(tex.outputs["Color"], node.inputs["Base Color"])
    obj = bpy.data.objects.new("Folded", mesh)
    obj.data.materials.append(material)
    scene.collection.objects.link(obj)
    scenes.light(scene, "SUN", energy=math.pi)
    got = scenes.render(scene, tmp_path / "folded.exr")[..., :3]
    red, blue = (np.array(c, np.float16).astype(np.float64)  # Blender keeps float images as half
                 for c in ([0.8, 0.1, 0.1], [0.1, 0.2, 0.9]))
    want = 0.5 * red + 0.25 * blue
    np.testing.assert_allclose(got, np.broadcast_to(want, got.shape), atol=1e-5)


@pytest.mark.parametrize("layers,peeled", [(16, 2), (2, 2), (1, 1)])
def test_peeling_stops_when_no_surface_is_left(layers, peeled):
    """Two surfaces per pixel: however many layers are allowed, two are blended (a third pass
    finds nothing and ends the peeling), and the image is still the closed form."""
    crossing_planes(layers)
    image, count = render_counted()
    assert count == peeled
    keep = away_from_crossing()
    np.testing.assert_allclose(image[::-1, keep, :3], expected_crossing(layers)[:, keep], atol=1e-5)

GREEN = np.array([0.0, 0.5, 0.0])
STACK = [(0.5, RED, 0.6), (0.25, GREEN, 0.5), (0.0, BLUE, 0.4)]  # (height, emission, coverage), nearest first


def stacked_planes(layers, cover=False):
    """Three parallel transparent emitters seen from above, and optionally a fully transparent
    plane in front of them all (a cut-out: it must take no layer)."""
    scene = scenes.reset(size=SIZE)
    scenes.ortho_camera(scene, scale=2.0)
    scene.shading_lab.transparency_layers = layers
    for i, (z, emission, a) in enumerate(STACK):
        scenes.plane(scene, size=4.0, location=(0.0, 0.0, z), material=emitter(f"S{i}", emission, a))
    if cover:
        scenes.plane(scene, size=4.0, location=(0.0, 0.0, 1.0), material=emitter("Cut", RED, 0.0))
    return scene


def render_counted(size=SIZE):
    def job(depsgraph):
        r = renderer.Renderer()
        try:
            return r.render(extract.snapshot(depsgraph, size, size)), r.peeled_layers
        finally:
            r.free()

    return run_on_gpu(job)


@pytest.mark.parametrize("layers,cover", [(2, False), (3, False), (16, False), (3, True)])
def test_stacked_layers_nearest_first_and_cut_outs_take_none(layers, cover):
    stacked_planes(layers, cover)
    image, count = render_counted()
    value, through = np.zeros(3), 1.0
    for _, emission, a in STACK[:layers]:
        value, through = value + through * a * emission, through * (1.0 - a)
    assert count == min(layers, 3)
    np.testing.assert_allclose(image[..., :3], np.broadcast_to(value, (SIZE, SIZE, 3)), atol=1e-5)


def test_opaque_surfaces_hide_transparent_ones_behind_them():
    scene = scenes.reset(size=SIZE)
    scenes.ortho_camera(scene, scale=2.0)
    scenes.plane(scene, size=4.0, location=(0.0, 0.0, 0.5), material=emitter("Opaque", GREEN, 1.0))
    scenes.plane(scene, size=4.0, location=(0.0, 0.0, 0.0), material=emitter("Behind", RED, 0.5))
    image, count = render_counted()
    assert count == 0  # the transparent plane is entirely behind the opaque one
    np.testing.assert_allclose(image[..., :3], np.broadcast_to(GREEN, (SIZE, SIZE, 3)), atol=1e-6)
