"""Material, world and light previews drawn by the engine (``bl_use_preview``).

In background mode ``ID.asset_generate_preview()`` renders the preview synchronously through the
scene's engine, in the preview scene Blender builds (its own camera, area lights, floor and world),
so the previews are checked here where a closed form exists: an emitter's pixels are its emitted
colour through the sRGB transfer function, a world preview is the world's colour. Previews read
back as 8-bit display values, hence the 1/255 tolerances.
"""

from __future__ import annotations

import bpy
import numpy as np
import pytest
import scenes

from addon.blender import engine

QUANTUM = 1.0 / 255.0


def srgb(linear) -> np.ndarray:
    """IEC 61966-2-1 encoding, written here independently of the add-on's tone mapper."""
    c = np.asarray(linear, np.float64)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(np.maximum(c, 0.0), 1 / 2.4) - 0.055)


def preview(idb) -> np.ndarray:
    """Render ``idb``'s preview now; its pixels as rows (bottom first) x columns x RGBA."""
    engine.last_timings.clear()
    idb.asset_generate_preview()
    assert engine.last_timings, "the preview was not rendered by Shading Lab"
    p = idb.preview
    width, height = p.image_size
    assert (width, height) == (128, 128)
    return np.array(p.image_pixels_float[:], np.float32).reshape(height, width, 4)


def surface(material, shader: str):
    tree = scenes.node_tree(material)
    node = tree.nodes.new(shader)
    output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    tree.links.new(node.outputs[0], output.inputs["Surface"])
    return node


def emitter(color) -> bpy.types.Material:
    material = bpy.data.materials.new("Emitter")
    node = surface(material, "ShaderNodeEmission")
    node.inputs["Color"].default_value = (*color, 1.0)
    node.inputs["Strength"].default_value = 1.0
    return material


def principled(name, base, metallic=0.0, roughness=0.3) -> bpy.types.Material:
    material = bpy.data.materials.new(name)
    node = next(n for n in scenes.node_tree(material).nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    node.inputs["Base Color"].default_value = (*base, 1.0)
    node.inputs["Metallic"].default_value = metallic
    node.inputs["Roughness"].default_value = roughness
    return material


EMISSION = (0.2, 0.5, 0.8)


@pytest.mark.parametrize("model", ["PBR", "BLINN_PHONG", "PHONG"])
def test_emitter_preview_is_its_emission_in_every_model(model):
    scene = scenes.reset()
    scene.shading_lab.model = model
    pixels = preview(emitter(EMISSION))
    centre = pixels[56:72, 56:72]  # the preview sphere covers the middle of the frame
    assert np.abs(centre[..., :3] - srgb(EMISSION)).max() <= QUANTUM
    assert (centre[..., 3] == 1.0).all()
    # the preview's floor hides from camera rays (its material mixes in a Transparent BSDF by
    # Light Path > Is Camera Ray, compiled): the corners show the preview's transparent film
    assert (pixels[:8, :8, 3] == 0.0).all() and (pixels[-8:, -8:, 3] == 0.0).all()


@pytest.mark.parametrize("shape", ["FLAT", "SPHERE", "CUBE", "CLOTH", "FLUID"])
def test_every_preview_shape_shows_the_material(shape):
    scenes.reset()
    material = emitter(EMISSION)
    material.preview_render_type = shape
    pixels = preview(material)
    assert np.abs(pixels[64, 64, :3] - srgb(EMISSION)).max() <= QUANTUM


@pytest.mark.parametrize("shape", ["SHADERBALL", "HAIR"])
def test_remaining_preview_shapes_render(shape):
    """The shader ball mixes in Blender's own materials and hair is curves, not drawn: both render
    finite images without error, of coverage 0 to 1."""
    scenes.reset()
    material = emitter(EMISSION)
    material.preview_render_type = shape
    pixels = preview(material)
    assert np.isfinite(pixels).all() and (pixels[..., 3] >= 0.0).all() and (pixels[..., 3] <= 1.0).all()


def test_world_preview_is_the_world_colour():
    scenes.reset()
    world = bpy.data.worlds.new("Sky")
    background = next(n for n in scenes.node_tree(world).nodes if n.bl_idname == "ShaderNodeBackground")
    background.inputs["Color"].default_value = (0.1, 0.3, 0.05, 1.0)
    background.inputs["Strength"].default_value = 2.0
    pixels = preview(world)
    assert np.abs(pixels[..., :3] - srgb((0.2, 0.6, 0.1))).max() <= QUANTUM


def test_light_preview_renders():
    scenes.reset()
    pixels = preview(bpy.data.lights.new("Bulb", "POINT"))
    assert np.isfinite(pixels).all() and pixels[..., :3].max() > 0.0


def test_preview_follows_the_scene_model_and_the_material_override():
    scene = scenes.reset()
    material = principled("Red", (0.8, 0.1, 0.1))
    scene.shading_lab.model = "PBR"
    pbr = preview(material)
    scene.shading_lab.model = "BLINN_PHONG"
    blinn_phong = preview(material)
    # the two models shade the lit sphere differently: the preview is not the preview scene's
    # default model whatever the artist chose
    sphere = (slice(40, 88), slice(40, 88))
    assert np.abs(pbr[sphere] - blinn_phong[sphere])[..., :3].max() > 0.1
    # the override shades the sphere as the scene setting did (the floor keeps the scene's model)
    scene.shading_lab.model = "PBR"
    material.shading_lab.model = "BLINN_PHONG"
    np.testing.assert_array_equal(preview(material)[sphere], blinn_phong[sphere])


def test_previews_ignore_supersampling_and_compare():
    """Previews are small and frequent: one sample per pixel, the scene's model alone."""
    scene = scenes.reset()
    material = principled("Metal", (0.9, 0.6, 0.3), metallic=1.0, roughness=0.2)
    plain = preview(material)
    scene.shading_lab.samples = 4
    scene.shading_lab.compare_mode = "SPLIT"
    np.testing.assert_array_equal(preview(material), plain)
    scene.shading_lab.compare_mode = "OFF"
    scene.shading_lab.samples = 1
    scene.shading_lab.model = "BLINN_PHONG"
    assert np.abs(preview(material) - plain)[..., :3].max() > 0.1  # the comparison can fail
