"""Light culling: frame time against the number of lights that each reach a sixteenth of the
screen, with culling on and off (a benchmark, not a test).

    .venv/bin/python scripts/light_culling_bench.py [--resolution 1280x720] [--frames 5]
        [--table docs/bench/light_culling.md]

A plane fills an orthographic view; N point lights (N = 4, 16, 64, on a grid over the view, 0.25 m
above the plane) each reach, by their Custom Distance, a disc of a sixteenth of the view's area.
Every configuration (model x N x culling) is rendered round-robin after a warm-up round, in one
process; the table gives medians of the engine's draw time (GPU work fenced by the read-back) and
the ratio to 4 lights. Times are CPU-rasteriser times (Mesa llvmpipe): compare ratios.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

COUNTS = (4, 16, 64)
HEIGHT = 0.25  # the lights above the plane (m)
VIEW = 8.0  # the view's width (m)


def build(w: int, h: int):
    import bpy
    import round_robin

    scene = round_robin.empty_scene(w, h)
    round_robin.ortho_camera(scene, VIEW)
    bpy.ops.mesh.primitive_plane_add(size=2 * VIEW)
    view_h = VIEW * h / w
    disc = math.sqrt(VIEW * view_h / 16.0 / math.pi)  # a sixteenth of the view's area
    reach = math.hypot(disc, HEIGHT)
    groups = {}
    for n in COUNTS:
        side = int(math.sqrt(n))
        objs = []
        for i in range(n):
            x = ((i % side) + 0.5) / side * VIEW - VIEW / 2
            y = ((i // side) + 0.5) / side * view_h - view_h / 2
            data = bpy.data.lights.new(f"L{n}_{i}", "POINT")
            data.energy, data.shadow_soft_size, data.use_shadow = 20.0, 0.0, False
            data.use_custom_distance, data.cutoff_distance = True, reach
            obj = bpy.data.objects.new(data.name, data)
            obj.location = (x, y, HEIGHT)
            scene.collection.objects.link(obj)
            objs.append(obj)
        groups[n] = objs
    return scene, groups


def main() -> int:
    import round_robin

    args, w, h = round_robin.parse_args(__doc__, "light_culling.md")

    scene, groups = build(w, h)
    configs = [(model, n, culling) for model in ("BLINN_PHONG", "PBR") for n in COUNTS
               for culling in (True, False)]

    def apply(config):
        model, n, culling = config
        round_robin.show_only(groups, n)
        scene.shading_lab.model, scene.shading_lab.light_culling = model, culling

    med = round_robin.median_draw_ms(configs, apply, args.frames)
    rows = []
    for model in ("BLINN_PHONG", "PBR"):
        for n in COUNTS:
            on, off = med[model, n, True], med[model, n, False]
            rows.append(f"| {model} | {n} | {on:.1f} | {on / med[model, COUNTS[0], True]:.2f}x | {off:.1f} | "
                        f"{off / med[model, COUNTS[0], False]:.2f}x | {off / on:.2f}x |")
    table = "\n".join([
        f"Light culling, {w}x{h}: a plane under N point lights that each reach a sixteenth of the view "
        "(points without radius, Cast Shadow off: the plane alone would cast nothing, and 64 lights' "
        "six maps each are not what this measures; tests/test_light_tiles.py renders culling with "
        f"shadows on) (`scripts/light_culling_bench.py`, {args.frames} frames per configuration after a "
        "warm-up, round-robin; draw + read-back ms, medians).",
        "",
        "| model | lights | culled ms | vs 4 lights | every light ms | vs 4 lights | culling speed-up |",
        "|---|---:|---:|---:|---:|---:|---:|",
        *rows, ""])
    round_robin.write_table(args.table, table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
