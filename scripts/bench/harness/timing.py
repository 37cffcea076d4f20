"""Round-robin timing for the benchmarks: every configuration rendered in turn, round after
round, so that machine noise hits them alike; round 0 is a warm-up (program compiles)."""

from __future__ import annotations

import argparse
import statistics
import sys
from collections.abc import Callable, Hashable, Sequence
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def parse_args(doc: str, table: str) -> tuple[argparse.Namespace, int, int]:
    """(args, width, height) of a round-robin benchmark: --resolution, --frames and --table
    (default docs/bench/``table``)."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--resolution", default="1280x720")
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--table", type=Path, default=ROOT / "docs" / "bench" / table)
    args = parser.parse_args()
    w, h = (int(x) for x in args.resolution.split("x"))
    return args, w, h


def empty_scene(w: int, h: int):
    """Blender's empty factory scene rendering with Shading Lab at w x h (the add-on registered)."""
    import bpy
    import render

    render.ensure_addon()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "SHADING_LAB"
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
    return scene


def ortho_camera(scene, width: float, location=(0.0, 0.0, 5.0)):
    """An orthographic camera ``width`` metres across, looking down -Z, made the scene's."""
    import bpy

    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.type, cam.data.ortho_scale = "ORTHO", width
    cam.location = location
    scene.collection.objects.link(cam)
    scene.camera = cam
    return cam


def median_draw_ms(configs: Sequence[Hashable], apply: Callable[[Hashable], None], frames: int) -> dict:
    """{config: median of the engine's draw time (ms, GPU work fenced by the read-back)} over
    ``frames`` rounds after the warm-up; ``apply(config)`` sets the scene up for one."""
    import bpy

    from addon.blender import engine

    times = {c: [] for c in configs}
    for round_index in range(frames + 1):
        for config in configs:
            apply(config)
            bpy.ops.render.render()
            if round_index > 0:
                times[config].append(engine.last_timings["draw_ms"])
        print(f"\rround {round_index}/{frames}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    return {c: statistics.median(t) for c, t in times.items()}


def show_only(groups: dict, key) -> None:
    """Render only the objects of ``groups[key]`` among the groups' objects."""
    for name, objs in groups.items():
        for obj in objs:
            obj.hide_render = name != key


def write_table(path: Path, table: str) -> None:
    print(table)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(table)
