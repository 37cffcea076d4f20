"""Benchmark: shadow casters left out of the maps where their shadows fall where no view looks (a
benchmark, not a test).

    .venv/bin/python scripts/shadow_casters_bench.py [--resolution 640x360] [--frames 5]
                                                     [--out docs/bench]

Scene: a town of 225 objects (spheres and boxes, 4 m apart, 1-5 m tall) on an 80 m ground, lit by
a sun (2 degrees) and four point lights (0.2 m), every light casting, as a file would have it.
Three cameras: at eye height down a street (most of the town behind or beside it), close to one
corner, and over the whole town (everything in view: what the test costs where it leaves nothing
out). Each is rendered with ``passes.VIEW_CULLED_CASTERS`` on and off, round-robin after a
warm-up, ``--frames`` rounds; times are the engine's own (``engine.last_timings``: extraction,
drawing, read-back), medians. *pairs*: (layer, caster) pairs the shadow pass drew; *max |d|*: the
largest difference between the two images (0: the same image bit for bit).

Writes ``OUT/shadow_casters.md`` (also printed). Frame times are CPU-rasteriser times (Mesa
llvmpipe): compare ratios within one run.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts"), str(ROOT / "tests")]

import render as cli  # noqa: E402
import round_robin  # noqa: E402

#: camera -> (location, rotation in degrees, lens in mm)
CAMERAS = {
    "street": ((-30.0, -33.0, 1.7), (88.0, 0.0, -45.0), 35.0),
    "corner": ((-33.0, -33.0, 4.0), (70.0, 0.0, -30.0), 50.0),
    "overview": ((0.0, -70.0, 60.0), (48.0, 0.0, 0.0), 28.0),
}


def build_town(width: int, height: int):
    """The town, its lights and a camera (``CAMERAS`` set its placement)."""
    import bpy
    import numpy as np
    import scenes

    scene = scenes.reset(size=width)
    scene.render.resolution_y = height
    scene.shading_lab.model = "PBR"
    mat = bpy.data.materials.new("White")
    bsdf = scenes.node_tree(mat).nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (0.8, 0.8, 0.8, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.6
    scenes.plane(scene, size=80.0, material=mat)
    rng = np.random.default_rng(5)
    for i in range(15):
        for j in range(15):
            x, y, h = -28.0 + 4.0 * i, -28.0 + 4.0 * j, float(rng.uniform(1.0, 5.0))
            if (i + j) % 2:
                bpy.ops.mesh.primitive_uv_sphere_add(radius=0.6, location=(x, y, h), segments=24,
                                                     ring_count=12)
            else:
                bpy.ops.mesh.primitive_cube_add(size=1.0, location=(x, y, 0.5 * h), scale=(1.0, 1.0, h))
            bpy.context.object.data.materials.append(mat)
    sun = scenes.light(scene, "SUN", energy=3.0, rotation=(math.radians(-35.0), math.radians(25.0), 0.0))
    sun.data.angle = math.radians(2.0)
    lights = [sun]
    for x, y in ((-20.0, -20.0), (-6.0, 10.0), (14.0, -8.0), (20.0, 22.0)):
        lights.append(scenes.light(scene, "POINT", energy=2000.0, location=(x, y, 6.0), shadow_soft_size=0.2))
    for light in lights:
        light.data.use_shadow = True
    data = bpy.data.cameras.new("Camera")
    data.clip_start, data.clip_end = 0.1, 500.0
    camera = bpy.data.objects.new("Camera", data)
    scene.collection.objects.link(camera)
    scene.camera = camera
    return scene


def place(scene, name: str) -> None:
    location, rotation, lens = CAMERAS[name]
    scene.camera.location = location
    scene.camera.rotation_euler = tuple(math.radians(a) for a in rotation)
    scene.camera.data.lens = lens


def run(args, tmp: Path, progress) -> list[dict]:
    import numpy as np
    import scenes

    from addon.blender import engine
    from addon.frame import passes

    drawn: list[int] = []
    original = passes.ShadowPass.run

    def counted(self, frame, views=None):
        done = original(self, frame, views)
        drawn.append(self.drawn_casters)
        return done

    passes.ShadowPass.run = counted
    try:
        scene = build_town(args.width, args.height)
        rows = []
        for name in CAMERAS:
            place(scene, name)
            times = {True: [], False: []}
            pairs, images = {}, {}
            for culled in (True, False):  # warm-up: programs, the first maps' texture
                passes.VIEW_CULLED_CASTERS = culled
                drawn.clear()
                images[culled] = scenes.render(scene, tmp / f"{name}_{culled}.exr")
                pairs[culled] = drawn[-1]
            for round_ in range(args.frames):
                for culled in ((True, False) if round_ % 2 == 0 else (False, True)):
                    passes.VIEW_CULLED_CASTERS = culled
                    engine.last_timings.clear()
                    scenes.render(scene, tmp / "timed.exr")
                    times[culled].append(engine.last_timings["total_ms"])
            on, off = statistics.median(times[True]), statistics.median(times[False])
            row = dict(camera=name, on_ms=on, off_ms=off, ratio=on / off, pairs_on=pairs[True],
                       pairs_off=pairs[False], max_diff=float(np.abs(images[True] - images[False]).max()))
            progress(f"{name}: {on:.0f} ms culled, {off:.0f} ms every caster ({on / off:.2f}x); "
                     f"pairs {pairs[True]} / {pairs[False]}; max |d| {row['max_diff']:.3g}")
            rows.append(row)
    finally:
        passes.ShadowPass.run = original
        passes.VIEW_CULLED_CASTERS = True
    return rows


def report(args, rows, stamp: str) -> str:
    lines = [f"Shadow casters left out where their shadows fall where no view looks "
             f"(`scripts/shadow_casters_bench.py`, {stamp}): a town of 225 objects on an 80 m ground, "
             f"a sun (one map, four cascades where the view is deep) and four point lights (six maps each) "
             f"casting, {args.width}x{args.height}, engine ms, "
             f"medians of {args.frames} round-robin rounds after a warm-up.", "",
             "| camera | culled ms | every caster ms | ratio | pairs drawn (culled / every) | max abs diff |",
             "|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['camera']} | {r['on_ms']:.1f} | {r['off_ms']:.1f} | {r['ratio']:.2f}x | "
                     f"{r['pairs_on']} / {r['pairs_off']} | {r['max_diff']:.3g} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", default="640x360", metavar="WxH")
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "bench")
    args = parser.parse_args(argv)
    args.width, args.height = (int(x) for x in args.resolution.split("x"))
    cli.ensure_addon()
    stamp = time.strftime("%Y-%m-%d %H:%M")
    with tempfile.TemporaryDirectory() as tmp:
        rows = run(args, Path(tmp), lambda text: print(text, flush=True))
    round_robin.write_table(args.out / "shadow_casters.md", report(args, rows, stamp))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
