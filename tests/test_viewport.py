"""The viewport's update logic, headless: depsgraph updates arrive through the update handler
(which fires in background mode), and drawing runs through the shared renderer with the matrices
a viewport region would pass."""

from __future__ import annotations

import bpy
import numpy as np
import pytest
import scenes
from gpu_harness import read_texture, run_on_gpu

from addon import extract, renderer
from addon.viewport import ViewportSession


@pytest.fixture
def session_with_handler():
    scene = scenes.reset(size=16)
    scenes.ortho_camera(scene)
    a = scenes.plane(scene, size=1.0, location=(-0.5, 0.0, 0.0))
    b = scenes.plane(scene, size=1.0, location=(0.5, 0.0, 0.0))
    b.data = bpy.data.meshes.new("Other")
    b.data.from_pydata([(-0.5, -0.5, 0), (0.5, -0.5, 0), (0.0, 0.5, 0)], [], [(0, 1, 2)])
    scenes.light(scene, "SUN", energy=2.0)
    session = ViewportSession()
    session.update(bpy.context.evaluated_depsgraph_get())
    seen = []

    def handler(scene, depsgraph):
        seen.append({u.id.name for u in depsgraph.updates})
        session.update(depsgraph)

    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        yield session, a, b, seen
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)
        session.free()


def _draw(session, size=16):
    cam = bpy.context.scene.camera
    view = np.linalg.inv(np.array(cam.matrix_world))
    proj = np.array(cam.calc_matrix_camera(bpy.context.evaluated_depsgraph_get(), x=size, y=size))

    def job(depsgraph):
        texture = session.draw(size, size, view, proj, False)
        return read_texture(texture, size), session.renderer.uploaded_geometry

    return run_on_gpu(job)


def test_first_update_reads_everything(session_with_handler):
    session, a, b, _ = session_with_handler
    assert len(session.snapshot.geometries) == 2
    assert session.snapshot.fresh == set(session.snapshot.geometries)
    _, uploaded = _draw(session)
    assert uploaded == 2


def test_transform_only_edit_reads_and_uploads_no_geometry(session_with_handler):
    session, a, b, seen = session_with_handler
    _draw(session)
    a.location.x -= 0.25
    bpy.context.view_layer.update()
    assert seen, "the depsgraph update handler must fire"
    assert session.snapshot.fresh == set()
    moved = [i for i in session.snapshot.items if abs(i.matrix[0, 3] - (-0.75)) < 1e-6]
    assert len(moved) == 1, "the moved object's new matrix must be in the snapshot"
    _, uploaded = _draw(session)
    assert uploaded == 0


def test_geometry_edit_reads_and_uploads_only_that_object(session_with_handler):
    session, a, b, _ = session_with_handler
    _draw(session)
    b.data.vertices[2].co.z += 0.2
    b.data.update()
    bpy.context.view_layer.update()
    key_b = next(k for k in session.snapshot.geometries if "Other" in k)
    assert session.snapshot.fresh == {key_b}
    assert np.isclose(session.snapshot.geometries[key_b].positions[:, 2].max(), 0.2)
    _, uploaded = _draw(session)
    assert uploaded == 1


def test_viewport_image_equals_final_render_image(session_with_handler):
    """Same matrices, same snapshot: the viewport texture equals the final renderer's image."""
    session, *_ = session_with_handler
    shown, _ = _draw(session)

    def job(depsgraph):
        snap = extract.snapshot(depsgraph, 16, 16)
        r = renderer.Renderer()
        try:
            return r.render(snap)
        finally:
            r.free()

    reference = run_on_gpu(job)
    assert reference[..., 0].max() > 0.1
    np.testing.assert_allclose(shown[..., :3], reference[..., :3], rtol=2e-3, atol=1e-3)  # RGBA16F target


def test_property_edits_reach_the_viewport(session_with_handler):
    """Editing a Shading Lab property is a depsgraph update naming the edited ID (which makes
    Blender call view_update and redraw), and the session picks up the new value."""
    session, a, _, seen = session_with_handler
    mat = scenes.material("Edited", roughness=0.2)
    a.data.materials.append(mat)
    bpy.context.view_layer.update()
    seen.clear()
    mat.shading_lab.roughness = 0.9
    bpy.context.view_layer.update()  # what Blender's main loop does before the next redraw
    assert any(mat.name in names for names in seen)
    assert session.snapshot.materials[mat.name_full].roughness == pytest.approx(0.9)
    bpy.context.scene.shading_lab.model = "PHONG"
    bpy.context.view_layer.update()
    assert session.snapshot.settings.model == "PHONG"


# --- what each edit uploads (counted by the renderer: zero for an unchanged scene) ---------------

def _uploads(session):
    cam = bpy.context.scene.camera
    view = np.linalg.inv(np.array(cam.matrix_world))
    proj = np.array(cam.calc_matrix_camera(bpy.context.evaluated_depsgraph_get(), x=16, y=16))

    def job(depsgraph):
        session.draw(16, 16, view, proj, False)
        return session.renderer.uploads

    return run_on_gpu(job)


def test_first_draw_uploads_everything_once(session_with_handler):
    session, *_ = session_with_handler
    first = _uploads(session)
    assert first == {"geometry": 2, "materials": 1, "lights": 1, "objects": 1, "frame": 1}, first


def test_redrawing_an_unchanged_scene_uploads_nothing(session_with_handler):
    session, *_ = session_with_handler
    _uploads(session)
    assert _uploads(session) == {}


def test_transform_only_edit_uploads_only_the_object_block(session_with_handler):
    session, a, _, _ = session_with_handler
    _uploads(session)
    a.location.x -= 0.25
    bpy.context.view_layer.update()
    assert _uploads(session) == {"objects": 1}


def test_light_edit_uploads_only_the_light_block(session_with_handler):
    session, *_ = session_with_handler
    _uploads(session)
    bpy.data.lights[0].energy *= 2.0
    bpy.context.view_layer.update()
    assert _uploads(session) == {"lights": 1}


def test_material_edit_uploads_only_that_material(session_with_handler):
    session, a, _, _ = session_with_handler
    a.data.materials.append(scenes.material("Edited", roughness=0.2))
    bpy.context.view_layer.update()
    _uploads(session)
    a.data.materials[0].shading_lab.roughness = 0.7
    bpy.context.view_layer.update()
    assert _uploads(session) == {"materials": 1}


def test_camera_orbit_uploads_only_the_frame_block(session_with_handler):
    session, *_ = session_with_handler
    _uploads(session)
    bpy.context.scene.camera.location.x += 0.1  # the region's view moves; the scene does not
    bpy.context.view_layer.update()
    assert _uploads(session) == {"frame": 1}


def _render_with_uploads(size):
    def job(depsgraph):
        r = renderer.Renderer()
        try:
            image = r.render(extract.snapshot(depsgraph, size, size))
            first = r.uploads
            r.render(extract.snapshot(depsgraph, size, size))
            return image, first, r.uploads
        finally:
            r.free()

    return run_on_gpu(job)


def test_many_objects_upload_blocks_not_items_and_each_finds_its_matrix():
    """1,024 instances of one small plane tiling the view (4 object blocks): one geometry and
    4 blocks uploaded, and the image equals that of one plane covering the same square (an item
    reading another's matrix would leave a hole or an overlap)."""
    from addon import programs

    size, tiles = 32, 32
    scene = scenes.reset(size=size)
    scenes.ortho_camera(scene, scale=2.0)
    scenes.light(scene, "SUN", energy=2.0, rotation=(0.3, 0.2, 0.0))
    source = scenes.plane(scene, size=2.0 / tiles)
    for k in range(tiles * tiles):
        row, col = divmod(k, tiles)
        obj = source if k == 0 else bpy.data.objects.new(f"P{k}", source.data)
        obj.location = (-1.0 + (col + 0.5) * 2.0 / tiles, -1.0 + (row + 0.5) * 2.0 / tiles, 0.0)
        if k:
            scene.collection.objects.link(obj)
    tiled, first, second = _render_with_uploads(size)
    for obj in [o for o in scene.objects if o.type == "MESH"]:
        bpy.data.objects.remove(obj)
    scenes.plane(scene, size=2.0)
    whole, *_ = _render_with_uploads(size)
    blocks = -(-tiles * tiles // programs.OBJECT_BLOCK)
    assert blocks == 4
    assert first == {"geometry": 1, "materials": 1, "lights": 1, "objects": blocks, "frame": 1}, first
    assert second == {}, second
    assert whole[..., 0].min() > 0.1
    np.testing.assert_allclose(tiled, whole, rtol=1e-5)
