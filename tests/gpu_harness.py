"""Run a function inside a render engine's GPU context.

In background mode Blender's ``gpu`` module draws only inside ``RenderEngine.render()`` of an
engine with ``bl_use_gpu_context``; this test-only engine runs a given job there and hands its
return value (or exception) back, so the renderer can be tested without the product's engine.
"""

from __future__ import annotations

import atexit

import bpy


class _HarnessEngine(bpy.types.RenderEngine):
    bl_idname = "SHADING_LAB_TEST_HARNESS"
    bl_label = "Shading Lab test harness"
    bl_use_gpu_context = True

    job = None
    outcome = None

    def render(self, depsgraph):
        cls = type(self)
        try:
            cls.outcome = ("ok", cls.job(depsgraph))
        except BaseException as exc:  # handed back to the test
            cls.outcome = ("error", exc)


def _unregister() -> None:
    if _HarnessEngine.is_registered:
        bpy.utils.unregister_class(_HarnessEngine)


def run_on_gpu(job):
    """``job(depsgraph)`` runs inside a GPU context; returns its result or re-raises its error."""
    if not _HarnessEngine.is_registered:
        bpy.utils.register_class(_HarnessEngine)
        # Blender as a module never unregisters classes at exit; 4.x then leaks them and can
        # hang or crash in its exit destructors (the add-on does the same for its own classes)
        atexit.register(_unregister)
    scene = bpy.context.scene
    previous = scene.render.engine
    scene.render.engine = _HarnessEngine.bl_idname
    _HarnessEngine.job, _HarnessEngine.outcome = job, None
    # Blender renders nothing without a camera; a job that draws on its own needs none of the
    # scene, so whatever scene an earlier test left gets a stand-in for the call
    stand_in = None
    if scene.camera is None:
        stand_in = bpy.data.objects.new("Harness camera", bpy.data.cameras.new("Harness camera"))
        scene.collection.objects.link(stand_in)
        scene.camera = stand_in
    try:
        bpy.ops.render.render()
    finally:
        scene.render.engine = previous
        _HarnessEngine.job = None
        if stand_in is not None:
            camera = stand_in.data
            bpy.data.objects.remove(stand_in)
            bpy.data.cameras.remove(camera)
    status, value = _HarnessEngine.outcome or ("error", RuntimeError("the harness engine did not run"))
    _HarnessEngine.outcome = None
    if status == "error":
        raise value
    return value


def read_texture(texture, size: int):
    """A square GPU texture as (size, size, 4) float32, bottom row first (call on the GPU)."""
    import numpy as np

    buffer = texture.read()
    buffer.dimensions = size * size * 4
    return np.array(buffer, np.float32).reshape(size, size, 4)


def viewport_image(scene, size: int):
    """What a size x size viewport region looking through ``scene``'s camera shows, drawn by a
    fresh viewport session: (size, size, 4) float32, bottom row first."""
    import numpy as np

    from addon.blender.viewport import ViewportSession

    session = ViewportSession()
    try:
        depsgraph = bpy.context.evaluated_depsgraph_get()
        session.update(depsgraph)
        cam = scene.camera
        view = np.linalg.inv(np.array(cam.matrix_world))
        proj = np.array(cam.calc_matrix_camera(depsgraph, x=size, y=size))
        perspective = cam.data.type != "ORTHO"
        return run_on_gpu(lambda _d: read_texture(session.draw(size, size, view, proj, perspective), size))
    finally:
        session.free()
