"""Frame time of each shading model on the demo scene (a benchmark, not a test).

    .venv/bin/python scripts/frame_time.py [--resolution 1280x720] [--frames 7]

Renders the demo scene with every model in the same process, interleaving the models round by
round so that machine noise hits them alike, after one warm-up render each (program compile).
Reports medians of the engine's phases: scene extraction, GPU draw + read-back (fenced by the
read-back), and handing the pixels to Blender. Frame times here are CPU-rasteriser times (Mesa
llvmpipe on a machine without a GPU): compare them as ratios within one run.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolution", default="1280x720")
    parser.add_argument("--frames", type=int, default=7)
    args = parser.parse_args()
    w, h = (int(x) for x in args.resolution.split("x"))

    import bpy
    import demo_scene

    from addon.blender import engine

    scene = demo_scene.empty_scene(w, h)
    demo_scene.build(scene)
    from addon.scene.snapshot import MODELS as models
    samples = {m: [] for m in models}
    for round_index in range(args.frames + 1):
        for model in models:
            scene.shading_lab.model = model
            bpy.ops.render.render()
            if round_index > 0:  # round 0 is the warm-up
                samples[model].append(dict(engine.last_timings))
        print(f"\rround {round_index}/{args.frames}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    tris = sum(len(o.data.polygons) for o in scene.objects if o.type == "MESH")
    print(f"demo scene, {w}x{h}, {args.frames} frames per model after a warm-up, ~{tris:,} faces")
    print("| model | total ms (median) | extract ms | draw + read-back ms | result ms | vs Blinn-Phong |")
    print("|---|---:|---:|---:|---:|---:|")
    base = statistics.median(t["total_ms"] for t in samples["BLINN_PHONG"])
    for model in models:
        med = {k: statistics.median(t[k] for t in samples[model]) for k in samples[model][0]}
        print(f"| {model} | {med['total_ms']:.1f} | {med['extract_ms']:.1f} | {med['draw_ms']:.1f} | "
              f"{med['result_ms']:.1f} | {med['total_ms'] / base:.2f}x |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
