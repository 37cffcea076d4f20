"""Renders, previews and the viewport share the program library and the image cache, and Blender
runs final renders and previews on threads of their own while the add-on may be disabled on the
main thread. What is tested here is what can run headless: Blender as a module renders on the
calling thread, and Blender's class registration itself is main-thread only (from a second thread,
``bpy.utils.unregister_class`` crashes inside Blender while any operator runs, with or without
this add-on), so the render job on its own thread is played by a thread holding the engine's
activity as Blender's render job does, and the library is cleared from another thread in the
middle of a real frame."""

from __future__ import annotations

import threading
import time

import bpy
import numpy as np
import scenes

import addon
from addon.blender import engine
from addon.frame import gpu_library, passes


def _two_program_scene():
    """Two planes with different shading models: a frame draws with two programs."""
    scene = scenes.reset(size=16)
    scenes.ortho_camera(scene)
    scenes.light(scene, "SUN", energy=2.0, rotation=(0.3, 0.0, 0.0))
    for x, model in ((-0.5, "PBR"), (0.5, "PHONG")):
        mat = scenes.material(f"M{model}", roughness=0.4)
        mat.shading_lab.model = model
        scenes.plane(scene, size=1.0, location=(x, 0.0, 0.0), material=mat)
    return scene


def test_unregister_waits_for_a_render_running_on_another_thread():
    ended = []
    started = threading.Event()

    def render_job():  # what Blender's render thread does between render_init and render_complete
        with engine.ACTIVITY.running():
            started.set()
            time.sleep(0.3)
            ended.append(time.perf_counter())

    worker = threading.Thread(target=render_job)
    worker.start()
    started.wait(5)
    try:
        addon.unregister()
        returned = time.perf_counter()
    finally:
        addon.register()
        worker.join()
    assert ended and returned >= ended[0], "unregister() returned while a render was still running"


def test_render_jobs_count_from_render_init_to_render_complete():
    """The engine's job handlers bracket Blender's whole render job (its own use of the engine
    type included), not only render()."""
    scene = _two_program_scene()
    seen = []

    def probe(*_args):
        seen.append(engine.ACTIVITY.count())

    bpy.app.handlers.render_pre.append(probe)
    bpy.app.handlers.render_post.append(probe)
    try:
        scene.render.engine = "SHADING_LAB"
        bpy.ops.render.render()
    finally:
        bpy.app.handlers.render_pre.remove(probe)
        bpy.app.handlers.render_post.remove(probe)
    assert seen == [1, 1], seen
    assert engine.ACTIVITY.count() == 0


def test_library_cleared_by_another_thread_mid_frame_leaves_the_frame_exact(tmp_path, monkeypatch):
    """unregister() clears the program library; a frame drawing meanwhile keeps the programs it
    holds and compiles anew what it has not fetched yet: the image is the undisturbed one."""
    scene = _two_program_scene()
    reference = scenes.render(scene, tmp_path / "reference.exr")
    real_run = passes.TransparencyPass.run
    cleared = []

    def clear_from_another_thread(self, frame, view):
        worker = threading.Thread(target=gpu_library.LIBRARY.clear)
        worker.start()
        worker.join()
        cleared.append(gpu_library.LIBRARY.program_count())
        return real_run(self, frame, view)

    monkeypatch.setattr(passes.TransparencyPass, "run", clear_from_another_thread)
    disturbed = scenes.render(scene, tmp_path / "disturbed.exr")
    monkeypatch.undo()
    assert cleared == [0], "the library was not cleared mid-frame"
    assert reference[..., 0].max() > 0.1
    np.testing.assert_array_equal(disturbed, reference)
    np.testing.assert_array_equal(scenes.render(scene, tmp_path / "after.exr"), reference)


def test_library_lookups_racing_with_clears_from_8_threads():
    """Lookups racing with clears from 8 threads: every lookup gets a program (never a freed or
    half-made one) and the library ends consistent."""
    from gpu_harness import run_on_gpu

    from addon.plan import programs

    features = programs.Features("PBR", 1, frozenset({"SUN"}))

    def job(_depsgraph):
        errors = []

        def churn():
            try:
                for _ in range(50):
                    gpu_library.LIBRARY.clear()
                    time.sleep(0.0005)
            except Exception as exc:  # pragma: no cover - reported below
                errors.append(exc)

        workers = [threading.Thread(target=churn) for _ in range(8)]
        for w in workers:
            w.start()
        got = [gpu_library.shading_program(features) for _ in range(40)]
        for w in workers:
            w.join()
        return errors, all(g is not None for g in got)

    errors, all_got = run_on_gpu(job)
    assert not errors and all_got
