"""The GPU renderer and program cache, driven directly inside a GPU context."""

from __future__ import annotations

import bpy
import numpy as np
import pytest
import scenes
from gpu_harness import run_on_gpu

from addon.blender import extract
from addon.frame import gpu_library, renderer
from addon.plan import programs


def _lit_scene(kinds=("POINT",)):
    scene = scenes.reset(size=16)
    scenes.ortho_camera(scene)
    scenes.plane(scene, size=4.0)
    for kind in kinds:
        scenes.light(scene, kind, energy=50.0 if kind != "SUN" else 2.0)
    return scene


def test_cancel_draws_nothing():
    _lit_scene()

    def job(depsgraph):
        snap = extract.snapshot(depsgraph, 16, 16)
        r = renderer.Renderer()
        try:
            drawn = r.render(snap, background=(0.25, 0.5, 0.75, 1.0))
            cancelled = r.render(snap, background=(0.25, 0.5, 0.75, 1.0), should_stop=lambda: True)
        finally:
            r.free()
        return drawn, cancelled

    drawn, cancelled = run_on_gpu(job)
    assert drawn[..., 0].max() > 0.25 + 1e-3  # the lit plane was drawn over the background
    np.testing.assert_array_equal(cancelled[..., :3], np.broadcast_to([0.25, 0.5, 0.75], (16, 16, 3)))


def test_same_scene_compiles_once_and_uploads_once():
    _lit_scene()

    def job(depsgraph):
        snap = extract.snapshot(depsgraph, 16, 16)
        r = renderer.Renderer()
        try:
            r.render(snap)
            before = gpu_library.LIBRARY.program_count()
            first_upload = r.uploaded_geometry
            r.render(snap)
            return before, gpu_library.LIBRARY.program_count(), first_upload, r.uploaded_geometry
        finally:
            r.free()

    before, after, first_upload, second_upload = run_on_gpu(job)
    assert after == before, "rendering the same scene again must not compile a new program"
    assert (first_upload, second_upload) == (1, 0), "unchanged geometry must not be uploaded again"


def test_light_kinds_specialise_the_program():
    point = programs.Features(model="PBR", max_lights=1, light_kinds=frozenset({"POINT"}))
    spot = programs.Features(model="PBR", max_lights=1, light_kinds=frozenset({"SPOT"}))
    assert ("SL_HAS_POINT", "1") in point.defines() and ("SL_HAS_SPOT", "1") not in point.defines()
    assert point.defines() != spot.defines()
    run_on_gpu(lambda _d: gpu_library.LIBRARY.clear())  # whatever programs earlier tests left
    _lit_scene(("POINT",))
    run_on_gpu(lambda d: renderer.Renderer().render(extract.snapshot(d, 16, 16)))
    count = gpu_library.LIBRARY.program_count()
    _lit_scene(("SPOT",))
    run_on_gpu(lambda d: renderer.Renderer().render(extract.snapshot(d, 16, 16)))
    assert gpu_library.LIBRARY.program_count() == count + 1


def test_viewport_matrices_give_the_camera_image():
    """The viewport passes its own view-projection: the camera's one must reproduce render()."""
    _lit_scene(("SUN", "POINT"))

    def job(depsgraph):
        snap = extract.snapshot(depsgraph, 16, 16)
        r = renderer.Renderer()
        try:
            reference = r.render(snap)
            return reference, r.render(snap, view_projection=snap.camera.view_projection)
        finally:
            r.free()

    reference, viewport = run_on_gpu(job)
    assert reference[..., 0].max() > 0.0
    np.testing.assert_array_equal(viewport, reference)


@pytest.mark.parametrize("count", [512, 700, 4096])
def test_thousands_of_coincident_lights_equal_that_many_times_one(count, tmp_path):
    """Up to 512 lights are read from a uniform block (512 fill it), more from the rows of a
    texture: ``count`` coincident point lights render as one of ``count`` times the power,
    within float32 summation (measured 7.9e-6 for 700, 4.8e-5 for 4,096). Light Threshold 0: a weak
    light reaches less far than a strong one (each fades out where its irradiance falls to the
    threshold), which is not what this test is about (tests/test_light_tiles.py is)."""
    scene = _lit_scene(())
    scene.shading_lab.light_threshold = 0.0
    scene.render.resolution_x = scene.render.resolution_y = 24
    mesh = bpy.data.lights.new("Many", "POINT")
    mesh.energy = 0.5
    mesh.use_shadow = False
    mesh.shadow_soft_size = 0.0
    for i in range(count):
        obj = bpy.data.objects.new(f"L{i}", mesh)
        obj.location = (0.3, -0.2, 1.0)
        scene.collection.objects.link(obj)
    many = scenes.render(scene, tmp_path / "many.exr")
    for obj in [o for o in scene.objects if o.type == "LIGHT"]:
        bpy.data.objects.remove(obj)
    one = scenes.light(scene, "POINT", energy=0.5 * count, location=(0.3, -0.2, 1.0))
    assert one is not None
    single = scenes.render(scene, tmp_path / "one.exr")
    assert single[..., :3].min() > 0.0
    error = float(np.abs(many - single)[..., :3].max() / single[..., :3].max())
    print(f"{count} coincident lights vs one: {error:.2e}")
    assert error < 4e-8 * count, f"{count} lights vs one: max relative difference {error:.2e}"


def test_a_kept_renderer_moves_between_the_light_block_and_the_light_texture():
    """A scene's lights grow past what the uniform block holds (600: the light texture) and shrink
    back (3: the block): a kept renderer (the viewport's) draws each as a fresh one does, to the
    bit, holding the lights in the one or the other (the other dropped)."""
    scene = _lit_scene(())
    rng = np.random.default_rng(3)
    lights = [scenes.light(scene, "POINT", energy=float(rng.uniform(0.2, 2.0)),
                           location=(*rng.uniform(-1.5, 1.5, 2), float(rng.uniform(0.3, 1.5))))
              for _ in range(600)]
    many = run_on_gpu(lambda d: extract.snapshot(d, 16, 16))
    for obj in lights[3:]:
        bpy.data.objects.remove(obj)
    few = run_on_gpu(lambda d: extract.snapshot(d, 16, 16))

    def job(_depsgraph):
        kept = renderer.Renderer()
        out = []
        try:
            for snap in (few, many, few):
                image = kept.render(snap).copy()
                where = (kept.scene._light_block.ubo is not None, kept.scene._lights.texture is not None)
                fresh = renderer.Renderer()
                try:
                    out.append((image, fresh.render(snap).copy(), where))
                finally:
                    fresh.free()
        finally:
            kept.free()
        return out

    out = run_on_gpu(job)
    assert [where for _, _, where in out] == [(True, False), (False, True), (True, False)]
    for i, (image, reference, _) in enumerate(out):
        assert np.array_equal(image, reference), f"render {i}: max {np.abs(image - reference).max():.3g}"
    assert not np.array_equal(out[0][0], out[1][0]), "600 lights drawn as 3"
    assert np.array_equal(out[0][0], out[2][0]), "back to 3 lights: the first image again"


@pytest.mark.parametrize("model", ["BLINN_PHONG", "PBR"])
def test_lights_from_the_uniform_block_equal_the_texture_bit_for_bit(model, tmp_path, monkeypatch):
    """Every kind of light, with a size, a spot's blend, an area light's shape and spread, shadow
    maps and a Custom Distance (light culling): read from the lights' uniform block, the image is
    the one read from the light texture, to the bit."""
    scene = scenes.reset(size=48)
    scene.shading_lab.model = model
    scenes.ortho_camera(scene, scale=3.0)
    scenes.plane(scene, size=4.0)
    scenes.plane(scene, size=0.6, location=(0.1, 0.0, 0.4), rotation=(0.3, 0.2, 0.0))  # a caster
    scenes.light(scene, "POINT", energy=60.0, location=(0.5, 0.3, 1.2), shadow_soft_size=0.1,
                 use_shadow=True)
    scenes.light(scene, "SPOT", energy=80.0, location=(-0.6, 0.2, 1.5), rotation=(0.2, -0.3, 0.0),
                 spot_size=1.0, spot_blend=0.3, use_shadow=True)
    scenes.light(scene, "SUN", energy=1.5, rotation=(0.3, 0.2, 0.0), angle=0.05, use_shadow=True)
    scenes.light(scene, "AREA", energy=40.0, location=(0.2, -0.6, 1.0), size=0.4, use_shadow=True)
    scenes.light(scene, "AREA", energy=30.0, location=(-0.4, -0.5, 0.8), shape="DISK", size=0.3,
                 spread=1.0)
    scenes.light(scene, "POINT", energy=20.0, location=(0.8, -0.8, 0.3), use_custom_distance=True,
                 cutoff_distance=1.0)
    read = []
    compile_program = gpu_library.shading_program

    def spy(features):
        read.append(features.light_block)
        return compile_program(features)

    monkeypatch.setattr(gpu_library, "shading_program", spy)
    block = scenes.render(scene, tmp_path / "block.exr")
    assert read and all(read), "the lights fit the uniform block"
    read.clear()
    monkeypatch.setattr(programs, "LIGHT_BLOCK", False)
    texture = scenes.render(scene, tmp_path / "texture.exr")
    assert read and not any(read)
    assert block[..., :3].max() > 0.1, "lit"
    assert np.array_equal(block, texture), f"max difference {np.abs(block - texture).max():.3g}"
