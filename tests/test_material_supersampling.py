"""Screen-space sizes under Anti-Aliasing: a Wireframe's Pixel Size and a Bump's step are a pixel
of the image, as Cycles' ray differentials span a whole pixel however many samples it takes in it,
not a sub-pixel of the engine's supersampled target.

One perspective render of two tilted planes, each emitting what its graph computes (no lights: the
Combined pass is the emission): the left one a Wireframe of 1 pixel over a grid of quads, the right
one the normal a Bump bends along a sine of 7.5 pixels' wavelength (Filter Width 1: a whole pixel's
step, where the sine's curvature shows a step's size). The engine at Anti-Aliasing 1 and 3, against
Cycles at one sample on pixel centres and at 256 samples under a pixel-wide box filter (the
engine's resolve)."""

from __future__ import annotations

import math

import bpy
import numpy as np
import pytest
import scenes
from test_cycles import _cycles

from addon.blender import engine

WIDTH, HEIGHT = 96, 48
#: The supersampling grid compared with Cycles' box filter
SAMPLES = 3


def _emitting(name: str):
    """A material emitting (strength 1) the colour its caller links into the returned socket."""
    mat = bpy.data.materials.new(name)
    tree = scenes.node_tree(mat)
    tree.nodes.clear()
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(emission.outputs["Emission"], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    return mat, tree, emission.inputs["Color"]


def _grid(scene, x: float, material):
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=9, y_subdivisions=9, size=2.0, location=(x, 0.0, 0.0))
    obj = bpy.context.active_object
    obj.data.materials.append(material)
    return obj


def _scene():
    scene = scenes.reset(size=HEIGHT)
    scene.render.resolution_x = WIDTH
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location, cam.rotation_euler = (0.0, -3.6, 2.6), (math.radians(54.0), 0.0, 0.0)
    cam.data.lens = 38.0
    scene.collection.objects.link(cam)
    scene.camera = cam
    wire_mat, tree, color = _emitting("Wires")
    wire = tree.nodes.new("ShaderNodeWireframe")
    wire.use_pixel_size = True
    wire.inputs["Size"].default_value = 1.0
    tree.links.new(wire.outputs["Fac"], color)
    _grid(scene, -1.1, wire_mat)
    bump_mat, tree, color = _emitting("Bumps")
    coords = tree.nodes.new("ShaderNodeTexCoord")
    split = tree.nodes.new("ShaderNodeSeparateXYZ")
    tree.links.new(coords.outputs["Object"], split.inputs["Vector"])
    scale = tree.nodes.new("ShaderNodeMath")
    scale.operation = "MULTIPLY"
    scale.inputs[1].default_value = 20.0  # a wavelength of 0.31 m: 7.5 pixels here
    tree.links.new(split.outputs["X"], scale.inputs[0])
    sine = tree.nodes.new("ShaderNodeMath")
    sine.operation = "SINE"
    tree.links.new(scale.outputs[0], sine.inputs[0])
    bump = tree.nodes.new("ShaderNodeBump")
    bump.inputs["Distance"].default_value = 0.05  # slopes up to 1
    if "Filter Width" in bump.inputs:  # Blender 4.3 and later (before: always a whole step)
        bump.inputs["Filter Width"].default_value = 1.0
    tree.links.new(sine.outputs[0], bump.inputs["Height"])
    shown = tree.nodes.new("ShaderNodeVectorMath")  # the unit normal as a colour, 0..1
    shown.operation = "MULTIPLY_ADD"
    shown.inputs[1].default_value = (0.5, 0.5, 0.5)
    shown.inputs[2].default_value = (0.5, 0.5, 0.5)
    tree.links.new(bump.outputs["Normal"], shown.inputs[0])
    tree.links.new(shown.outputs["Vector"], color)
    _grid(scene, 1.1, bump_mat)
    return scene


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("supersampling")
    scene = _scene()
    out = {}
    for n in (1, SAMPLES):
        scene.render.engine = engine.ENGINE_ID
        scene.shading_lab.samples = n
        out[("ours", n)] = scenes.render(scene, tmp / f"ours_{n}.exr")[..., :3].astype(np.float64)
    out[("cycles", 1)] = _cycles(scene, tmp / "cycles_1.exr", samples=1)[..., :3].astype(np.float64)
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 1.0
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 256
    out[("cycles", SAMPLES)] = scenes.render(scene, tmp / "cycles_box.exr")[..., :3].astype(np.float64)
    scene.render.engine = engine.ENGINE_ID
    return out


def _halves(image):
    """The wire plane's and the bump plane's halves of the image."""
    return image[:, : WIDTH // 2], image[:, WIDTH // 2:]


#: Measured with bpy 5.0.1 (bounds 3x): the wires' coverage (the mean of their Fac over the left
#: half) against Cycles' as |ours / Cycles' - 1|, and the bent normal's mean difference inside the
#: right plane (at Anti-Aliasing 1 the wires cover the same pixels as Cycles': a pixel of a thousand
#: more or less would be 1e-3). With the target's sub-pixel as the pixel, Anti-Aliasing 3 drew the
#: wires at 0.366 of Cycles' coverage (a third as wide) and the bump's normal 1.9e-2 off.
MEASURED = {("wire", 1): 0.0, ("wire", SAMPLES): 1.6e-2, ("bump", 1): 2.1e-4, ("bump", SAMPLES): 5.6e-4}


@pytest.mark.parametrize("n", [1, SAMPLES])
def test_wire_pixel_size_is_an_image_pixel(rendered, n):
    ours, theirs = (_halves(rendered[(who, n)])[0][..., 0] for who in ("ours", "cycles"))
    off = abs(float(ours.mean() / theirs.mean()) - 1.0)
    measured = MEASURED[("wire", n)]
    print(f"Anti-Aliasing {n}: wire coverage off Cycles' by {off:.2%}")
    assert off <= 3.0 * measured + 1e-3, \
        f"Anti-Aliasing {n}: wire coverage off by {off:.2%} (measured {measured:.2%})"


@pytest.mark.parametrize("n", [1, SAMPLES])
def test_bump_step_is_an_image_pixel(rendered, n):
    ours, theirs = (_halves(rendered[(who, n)])[1] for who in ("ours", "cycles"))
    inside = theirs.sum(-1) > 0
    for axis in (0, 1):  # the plane's outline pixels are partly covered: left out
        for shift in (-1, 1):
            inside &= np.roll(inside, shift, axis)
    assert inside.sum() > 300
    error = float(np.abs(ours - theirs)[inside].mean())
    measured = MEASURED[("bump", n)]
    print(f"Anti-Aliasing {n}: bump normal mean difference {error:.2e}")
    assert error <= 3.0 * measured, f"Anti-Aliasing {n}: {error:.2e} (measured {measured:.1e})"
