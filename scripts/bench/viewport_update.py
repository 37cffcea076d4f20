"""What a viewport edit costs, and what compiling the scene's programs costs (a benchmark).

    .venv/bin/python scripts/viewport_update.py [--repeats 15] [--grid 300]

On the demo scene plus one subdivided grid (``--grid`` N gives 2 N^2 triangles), measures the
median time of: a full scene read (what the first view_update does), the update after moving one
object (transform only: no geometry is read or uploaded), the update after editing the grid's
vertices (only the grid is read and uploaded), and the GPU upload after each. Then compiles every
program the demo scene needs, from an empty cache, and reports their number and compile times.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts"), str(ROOT / "tests")]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--grid", type=int, default=300)
    args = parser.parse_args()

    import bpy
    import demo_scene
    from gpu_harness import run_on_gpu

    import addon
    from addon.blender.viewport import ViewportSession
    from addon.frame import gpu_library
    from addon.plan import programs
    from addon.reference.tonemap import TONE_MAPPERS
    from addon.scene.snapshot import MODELS

    addon.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    demo_scene.build(scene)
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=args.grid, y_subdivisions=args.grid, size=2.0)
    grid = bpy.context.active_object
    sphere = next(o for o in scene.objects if o.name.startswith("Sphere"))
    bpy.context.view_layer.update()
    depsgraph = bpy.context.evaluated_depsgraph_get()

    session = ViewportSession()
    calls = []
    handler = lambda scene, depsgraph: calls.append(session.update(depsgraph))  # noqa: E731
    size = (320, 180)
    view = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, -8], [0, 0, 0, 1]]
    proj = [[1, 0, 0, 0], [0, 1.78, 0, 0], [0, 0, -1.0, -0.2], [0, 0, -1, 0]]

    def upload_ms():
        def job(_):
            start = time.perf_counter()
            session.draw(*size, view, proj, True)
            return 1e3 * (time.perf_counter() - start), session.renderer.uploaded_geometry
        return run_on_gpu(job)

    rows = {"full scene read": [], "transform-only update": [], "geometry edit update": []}
    draws = {key: [] for key in rows}
    uploads = {}
    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        for i in range(args.repeats):
            session.snapshot = None
            session.renderer.free()
            session.update(depsgraph)
            rows["full scene read"].append(session.last_update_ms)
            ms, uploads["full scene read"] = upload_ms()
            draws["full scene read"].append(ms)

            sphere.location.x += 0.01 if i % 2 else -0.01
            bpy.context.view_layer.update()
            rows["transform-only update"].append(session.last_update_ms)
            ms, uploads["transform-only update"] = upload_ms()
            draws["transform-only update"].append(ms)

            grid.data.vertices[0].co.z += 0.001
            grid.data.update()
            bpy.context.view_layer.update()
            rows["geometry edit update"].append(session.last_update_ms)
            ms, uploads["geometry edit update"] = upload_ms()
            draws["geometry edit update"].append(ms)
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)

    tris = session.snapshot.triangle_count
    print(f"demo scene + {args.grid}x{args.grid} grid: {tris:,} triangles, {args.repeats} repeats, "
          f"draw at {size[0]}x{size[1]}")
    print("| viewport event | scene update ms (median) | upload + draw ms (median) | geometries uploaded |")
    print("|---|---:|---:|---:|")
    for key in rows:
        print(f"| {key} | {statistics.median(rows[key]):.1f} | {statistics.median(draws[key]):.1f} | "
              f"{uploads[key]} |")

    # --- program compilation ---------------------------------------------------------------
    snap = session.snapshot

    def compile_all(_):
        gpu_library.LIBRARY.clear()
        times = []
        for model in MODELS:
            features = programs.Features.from_snapshot(snap, model)
            start = time.perf_counter()
            gpu_library.shading_program(features)
            times.append((model, features.defines(), 1e3 * (time.perf_counter() - start)))
        for tone_mapper in TONE_MAPPERS[1:]:  # the engine's own curves
            post = programs.PostFeatures(1, tone_mapper, "SRGB")
            start = time.perf_counter()
            gpu_library.post_program(post)
            times.append(("display " + tone_mapper, post.defines(), 1e3 * (time.perf_counter() - start)))
        return times, gpu_library.LIBRARY.program_count()

    times, count = run_on_gpu(compile_all)
    print(f"\nprograms for the demo scene, compiled from an empty cache: {count}")
    print("| program | defines | compile ms |")
    print("|---|---|---:|")
    for name, defines, ms in times:
        print(f"| {name} | {' '.join(f'{k}={v}' for k, v in defines)} | {ms:.1f} |")
    session.free()
    return 0


if __name__ == "__main__":
    sys.exit(main())
