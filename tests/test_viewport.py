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
