"""The viewport's update logic, headless: depsgraph updates arrive through the update handler
(which fires in background mode), and drawing runs through the shared renderer with the matrices
a viewport region would pass."""

from __future__ import annotations

from types import SimpleNamespace

import bpy
import numpy as np
import pytest
import scenes
from gpu_harness import read_texture, run_on_gpu

from addon.blender import engine, extract
from addon.blender.viewport import ViewportSession
from addon.frame import renderer


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
    from addon.plan import programs

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


# --- the engine's own view_update / view_draw ------------------------------------------------------
# Background mode has no window, so Blender itself never calls view_update/view_draw. These tests
# call the engine's methods as Blender would: with a stand-in for the RenderEngine instance (its
# report(); bind_display_space_shader, which needs a real viewport's display settings, is a
# no-op, so the region receives scene-linear values), a stand-in context (region size, the
# region's view and window matrices, the 3D view's render-region settings) and the region's
# pixel-space projection that Blender sets before view_draw. Everything else is the engine's own
# code: the session, the renderer, the render-region clip, the error text and draw_texture_2d.

class _EngineStandIn:
    def __init__(self):
        self._viewport = None
        self.reports: list[tuple[set, str]] = []

    def report(self, kind, message):
        self.reports.append((kind, message))

    def bind_display_space_shader(self, scene):
        pass

    def unbind_display_space_shader(self):
        pass

    def tag_redraw(self):
        self.redraws_asked = getattr(self, "redraws_asked", 0) + 1


def _context(scene, size: int, *, space=None):
    from mathutils import Matrix

    cam = scene.camera
    view = cam.matrix_world.inverted()
    window = Matrix(cam.calc_matrix_camera(bpy.context.evaluated_depsgraph_get(), x=size, y=size))
    rv3d = SimpleNamespace(view_matrix=view, window_matrix=window, perspective_matrix=window @ view,
                           is_perspective=cam.data.type == "PERSP", view_perspective="CAMERA")
    if space is not None:  # a free view with the 3D view's own render region
        rv3d.view_perspective = "PERSP"
    space = space or SimpleNamespace(use_local_camera=False, camera=None, use_render_border=False)
    region = SimpleNamespace(width=size, height=size)
    return SimpleNamespace(region=region, region_data=rv3d, space_data=space)


CLEAR = (0.5, 0.25, 0.125, 1.0)  # the region before the engine draws


def _view_draw(stand_in, context, size: int) -> np.ndarray:
    """What the engine's view_draw leaves in a size x size region cleared to CLEAR."""
    import gpu

    def job(depsgraph):
        offscreen = gpu.types.GPUOffScreen(size, size, format="RGBA32F")
        with offscreen.bind():
            gpu.state.active_framebuffer_get().clear(color=CLEAR)
            with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
                gpu.matrix.load_identity()  # the region's pixel space, as Blender sets it
                gpu.matrix.load_projection_matrix(_pixel_space(size))
                engine.ShadingLabRenderEngine.view_draw(stand_in, context, depsgraph)
        return read_texture(offscreen.texture_color, size)

    return run_on_gpu(job)


def _pixel_space(size: int):
    from mathutils import Matrix

    return Matrix(((2.0 / size, 0, 0, -1.0), (0, 2.0 / size, 0, -1.0), (0, 0, -1.0, 0), (0, 0, 0, 1.0)))


@pytest.fixture
def engine_viewport():
    scene = scenes.lambert_scene(size=32)
    stand_in = _EngineStandIn()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    engine.ShadingLabRenderEngine.view_update(stand_in, _context(scene, 32), depsgraph)
    try:
        yield scene, stand_in
    finally:
        stand_in._viewport.free()


def test_engine_view_draw_shows_the_closed_form(engine_viewport):
    scene, stand_in = engine_viewport
    image = _view_draw(stand_in, _context(scene, 32), 32)
    err = np.abs(image[..., :3] / scenes.LAMBERT - 1.0).max()
    assert err < 1e-3, f"viewport pixels differ from the closed form by {err:.2e} (RGBA16F target)"
    assert not stand_in.reports, stand_in.reports


def _inside(image, box):
    x, y, w, h = box
    mask = np.zeros(image.shape[:2], bool)
    mask[y:y + h, x:x + w] = True
    return mask


def test_engine_view_draw_honours_the_scene_render_region_in_camera_view(engine_viewport):
    scene, stand_in = engine_viewport
    r = scene.render
    r.use_border = True
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.25, 0.75, 0.5, 1.0
    image = _view_draw(stand_in, _context(scene, 32), 32)
    inside = _inside(image, (8, 16, 16, 16))
    assert np.allclose(image[inside][:, :3], scenes.LAMBERT, rtol=1e-3), image[inside][:, 0].min()
    assert np.array_equal(image[~inside], np.tile(CLEAR, ((~inside).sum(), 1))), "drawn outside the region"


def test_engine_view_draw_honours_the_viewport_render_region(engine_viewport):
    scene, stand_in = engine_viewport
    scene.render.use_border = True  # the scene's region applies in camera view only
    space = SimpleNamespace(use_local_camera=False, camera=None, use_render_border=True,
                            render_border_min_x=0.0, render_border_max_x=0.5,
                            render_border_min_y=0.25, render_border_max_y=0.5)
    image = _view_draw(stand_in, _context(scene, 32, space=space), 32)
    inside = _inside(image, (0, 8, 16, 8))
    assert np.allclose(image[inside][:, :3], scenes.LAMBERT, rtol=1e-3)
    assert np.array_equal(image[~inside], np.tile(CLEAR, ((~inside).sum(), 1))), "drawn outside the region"


def test_engine_view_draw_keeps_the_last_good_image_and_draws_the_error(engine_viewport, monkeypatch):
    """A program that fails to compile after an edit: the region keeps the last good image, the
    error is written over it and reported once, and redraws do not try the same program again."""
    import gpu

    scene, stand_in = engine_viewport
    size = 256
    context = _context(scene, size)
    engine.ShadingLabRenderEngine.view_update(stand_in, context, bpy.context.evaluated_depsgraph_get())
    good = _view_draw(stand_in, context, size)
    assert np.allclose(good[..., :3], scenes.LAMBERT, rtol=1e-3)
    tries = []

    def broken(info):
        tries.append(info)
        raise Exception("compile failed: test")

    monkeypatch.setattr(gpu.shader, "create_from_info", broken)
    scene.shading_lab.model = "PHONG"  # a program not compiled yet
    engine.ShadingLabRenderEngine.view_update(stand_in, context, bpy.context.evaluated_depsgraph_get())
    first = _view_draw(stand_in, context, size)
    second = _view_draw(stand_in, context, size)
    assert len(tries) == 1, f"the failed program was compiled {len(tries)} times"
    errors = [m for kind, m in stand_in.reports if "ERROR" in kind]
    assert len(errors) == 1 and "could not compile" in errors[0], stand_in.reports
    assert "compile failed: test" in stand_in._viewport.error
    changed = np.any(first != good, axis=-1)
    text_rows = np.nonzero(changed.any(axis=1))[0]
    rows = f"{text_rows.min()}..{text_rows.max()}" if len(text_rows) else "none"
    assert changed.sum() > 50 and text_rows.max() < size - 24 and not changed[:size // 4].any(), (
        f"the error text must be drawn from the top left down, over the image: {changed.sum()} pixels "
        f"changed, in rows {rows}")
    assert np.array_equal(first[~changed], good[~changed]), "the last good image must stay under the text"
    assert np.array_equal(first, second)
    monkeypatch.undo()
    scene.shading_lab.model = "BLINN_PHONG"
    engine.ShadingLabRenderEngine.view_update(stand_in, context, bpy.context.evaluated_depsgraph_get())
    recovered = _view_draw(stand_in, context, size)
    assert stand_in._viewport.error == ""
    assert np.allclose(recovered[..., :3], scenes.LAMBERT, rtol=1e-3)


def test_viewport_chooses_auto_terms_for_the_view_it_draws(session_with_handler):
    """With the Auto term set, the viewport's first update knows no view yet and predicts nothing;
    its first draw chooses for the view it draws, the image equals the final render's (the same choice), and a
    later edit chooses again from that view, keeping the sets (hysteresis)."""
    session, a, _b, _seen = session_with_handler
    a.data.materials.append(scenes.material("Rough metal", roughness=0.7, metalness=1.0))
    scene = bpy.context.scene
    scene.shading_lab.term_set = "AUTO"
    bpy.context.view_layer.update()  # what Blender's main loop does before the next redraw
    assert session._unchosen and not session.snapshot.term_choices  # no view yet: nothing predicted
    shown, _ = _draw(session)
    choices = session.snapshot.term_choices
    assert not session._unchosen and choices, choices
    assert all(c.samples > 0 for c in choices.values()), choices
    assert session.snapshot.materials["Rough metal"].terms == choices["Rough metal"].terms

    def job(depsgraph):
        snap = extract.snapshot(depsgraph, 16, 16)
        r = renderer.Renderer()
        try:
            return snap.term_choices, r.render(snap)
        finally:
            r.free()

    final_choices, reference = run_on_gpu(job)
    assert {k: c.name for k, c in final_choices.items()} == {k: c.name for k, c in choices.items()}
    np.testing.assert_allclose(shown[..., :3], reference[..., :3], rtol=2e-3, atol=1e-3)  # RGBA16F target
    a.data.materials[0].shading_lab.roughness = 0.69  # a small edit: the set stays
    bpy.context.view_layer.update()
    assert session.snapshot.materials["Rough metal"].roughness == pytest.approx(0.69)
    assert session.snapshot.term_choices["Rough metal"].name == choices["Rough metal"].name


# --- a node graph: what an edit costs -----------------------------------------------------------

def test_value_edit_compiles_nothing_and_one_structure_shares_a_program(session_with_handler):
    """A graph's constants live in a uniform block: editing a node's value in the viewport uploads
    that material's block and compiles nothing; a second material of the same structure (other
    values) draws with the same program."""
    from test_material_render import _socket, _swept_principled
    from test_viewport import _draw, _uploads

    from addon.frame import gpu_library

    session, a, b, _ = session_with_handler
    first = _swept_principled("First")
    a.data.materials.append(first)
    bpy.context.view_layer.update()
    _uploads(session)
    compiles = gpu_library.LIBRARY.compiles
    mix = next(n for n in first.node_tree.nodes if n.bl_idname == "ShaderNodeMix")
    before = _draw(session)[0]
    _socket(mix.inputs, "A_Color").default_value = (0.1, 0.9, 0.1, 1.0)
    bpy.context.view_layer.update()
    assert _uploads(session) == {"graph constants": 1}
    after = _draw(session)[0]
    assert np.abs(after - before).max() > 0.05, "the edit did not reach the image"
    second = first.copy()
    _socket(next(n for n in second.node_tree.nodes if n.bl_idname == "ShaderNodeMix").inputs,
            "B_Color").default_value = (0.9, 0.9, 0.1, 1.0)
    b.data.materials.append(second)
    bpy.context.view_layer.update()
    uploads = _uploads(session)
    assert uploads.get("graph constants") == 1 and uploads.get("materials") == 1, uploads
    assert gpu_library.LIBRARY.compiles == compiles, "an edit or a second material of one structure compiled"


def test_only_edited_materials_are_read_again(session_with_handler, monkeypatch):
    """A viewport update reads (and compiles) again only the materials it names: a transform edit
    none, a node value edit that material's graph, a node group edit every one."""
    from test_material_render import _socket, _swept_principled

    from addon.materials import surface

    session, a, b, _ = session_with_handler
    first, second = _swept_principled("First"), _swept_principled("Second")
    group = bpy.data.node_groups.new("Shared", "ShaderNodeTree")
    math_node = group.nodes.new("ShaderNodeMath")
    second.node_tree.nodes.new("ShaderNodeGroup").node_tree = group
    a.data.materials.append(first)
    b.data.materials.append(second)
    bpy.context.view_layer.update()
    read = []
    original = surface.compile_material
    monkeypatch.setattr(surface, "compile_material", lambda *args: read.append(1) or original(*args))
    a.location.x += 0.1
    bpy.context.view_layer.update()
    assert read == [], "a transform edit read a material again"
    mix = next(n for n in first.node_tree.nodes if n.bl_idname == "ShaderNodeMix")
    _socket(mix.inputs, "A_Color").default_value = (0.2, 0.9, 0.1, 1.0)
    bpy.context.view_layer.update()
    assert len(read) == 1, f"{len(read)} materials read again for one material's edit"
    assert session.snapshot.materials["First"].graph is not session.snapshot.materials["Second"].graph
    read.clear()
    math_node.inputs[1].default_value = 0.25
    bpy.context.view_layer.update()
    assert len(read) == 2, f"{len(read)} of 2 materials read again after a node group's edit"
