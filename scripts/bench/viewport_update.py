"""What a viewport edit costs, and what compiling the scene's programs costs.

On the demo scene plus one subdivided grid (``--grid`` N gives 2 N^2 triangles), measures the
median time of: a full scene read (what the first view_update does), the update after moving one
object (transform only: no geometry is read or uploaded), the update after editing the grid's
vertices (only the grid is read and uploaded), and the GPU upload after each (``--repeats``
times each, in turn). Then compiles every program the demo scene needs, from an empty cache, and
reports their number and compile times.
"""

from __future__ import annotations

import statistics
import time

from .harness import page, scenes

PAGE = "viewport_update.md"
QUICK = dict(repeats=2, grid=50)
SIZE = (320, 180)  # the viewport region drawn
VIEW = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, -8], [0, 0, 0, 1]]
PROJECTION = [[1, 0, 0, 0], [0, 1.78, 0, 0], [0, 0, -1.0, -0.2], [0, 0, -1, 0]]
EVENTS = ("full scene read", "transform-only update", "geometry edit update")


def options(parser) -> None:
    parser.add_argument("--repeats", type=int, default=15, help="times each event is measured (default 15)")
    parser.add_argument("--grid", type=int, default=300,
                        help="the grid's subdivisions per side (default 300)")


def updates(session, depsgraph, sphere, grid, repeats: int, progress):
    """{event: ([update ms], [upload + draw ms], geometries uploaded)}."""
    import bpy
    from gpu_harness import run_on_gpu

    def draw(_):
        start = time.perf_counter()
        session.draw(*SIZE, VIEW, PROJECTION, True)
        return 1e3 * (time.perf_counter() - start), session.renderer.uploaded_geometry

    def full_read():
        session.snapshot = None
        session.renderer.free()
        session.update(depsgraph)

    def move():  # left, then right, and so on
        sphere.location.x += 0.01 if len(found[EVENTS[1]][0]) % 2 else -0.01
        bpy.context.view_layer.update()

    def edit():
        grid.data.vertices[0].co.z += 0.001
        grid.data.update()
        bpy.context.view_layer.update()

    found = {event: ([], [], 0) for event in EVENTS}
    handler = lambda scene, depsgraph: session.update(depsgraph)  # noqa: E731
    progress.expect(repeats * len(EVENTS))
    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        for _ in range(repeats):
            for event, act in zip(EVENTS, (full_read, move, edit)):
                act()
                found[event][0].append(session.last_update_ms)  # before the draw's own updates
                ms, uploaded = run_on_gpu(draw)
                found[event][1].append(ms)
                found[event] = (*found[event][:2], uploaded)
                progress.step(event)
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)
    return found


def compile_all(snap):
    """[(program, defines, compile ms)] of the demo scene's programs from an empty cache, and
    how many the library holds then."""
    from gpu_harness import run_on_gpu

    from addon.frame import gpu_library
    from addon.plan import programs
    from addon.reference.tonemap import TONE_MAPPERS
    from addon.scene.snapshot import MODELS

    def job(_):
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

    return run_on_gpu(job)


def run(ctx) -> None:
    import bpy

    from addon.blender.viewport import ViewportSession

    args = ctx.args
    scene = scenes.demo((1280, 720))
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=args.grid, y_subdivisions=args.grid, size=2.0)
    grid = bpy.context.active_object
    sphere = next(o for o in scene.objects if o.name.startswith("Sphere"))
    bpy.context.view_layer.update()
    session = ViewportSession()
    try:
        depsgraph = bpy.context.evaluated_depsgraph_get()
        found = updates(session, depsgraph, sphere, grid, args.repeats, ctx.progress)
        times, count = compile_all(session.snapshot)
        tris = session.snapshot.triangle_count
    finally:
        session.free()
    ctx.page("Viewport updates and program compiles", [
        f"The demo scene + a {args.grid}x{args.grid} grid: {tris:,} triangles, {args.repeats} repeats, "
        f"drawn at {page.res(SIZE)}.", "",
        *page.table(["viewport event", "scene update ms (median)", "upload + draw ms (median)",
                     "geometries uploaded"],
                    [[event, f"{statistics.median(u):.1f}", f"{statistics.median(d):.1f}", n]
                     for event, (u, d, n) in found.items()]), "",
        f"Programs for the demo scene, compiled from an empty cache: {count}.", "",
        *page.table(["program", "defines", "compile ms"],
                    [[name, " ".join(f"{k}={v}" for k, v in defines), f"{ms:.1f}"]
                     for name, defines, ms in times],
                    "llr")])
