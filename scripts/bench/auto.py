"""The Auto term set against the Principled set on every preset: frame time (a benchmark, not a
test).

    .venv/bin/python scripts/auto_bench.py [--resolution 1280x720] [--frames 7] [--bound 0.5]
        [--table docs/bench/auto.md] [--presets world] [--world-samples 64]

Per preset, Auto (at ``--bound``) and the Principled set are rendered alternately, one warm-up
round (program compiles, Auto's first prediction) then ``--frames`` rounds, in one process; each
timed render follows an untimed one of the same set (a switch of sets re-uploads what changed);
the table gives the medians of the engine's total time (extraction, including Auto's cached
prediction, + draw + read-back + result) and their ratio, with the sets Auto chose. Where Auto
draws the very same programs as the Principled set, the ratio shows this machine's noise
(+-5 % between runs of 9 rounds; 0.997 and 0.995 over 40 renders each on fresnel and
material_grid). Times are
CPU-rasteriser times (Mesa llvmpipe): compare the ratios. ``bench.py`` times Auto among every
configuration; this isolates the one comparison, with fewer configurations sharing the noise.
``--world-samples N`` renders every preset with World Specular: Sampled at N samples a pixel
(where the world has images, Auto may then take the split sum: its largest saving).
"""

from __future__ import annotations

import math
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

PRESETS = ("fresnel", "furnace", "hdr", "long_tail", "material_grid", "portability", "roughness_sweep",
           "softbox", "world")


def main() -> int:
    import round_robin

    parser = round_robin.argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolution", default="1280x720")
    parser.add_argument("--frames", type=int, default=7)
    parser.add_argument("--bound", default="0.5", help="error bound(s), comma-separated")
    parser.add_argument("--table", type=Path, default=ROOT / "docs" / "bench" / "auto.md")
    parser.add_argument("--presets", default=",".join(PRESETS), help="comma-separated preset names")
    parser.add_argument("--world-samples", type=int, default=0,
                        help="World Specular: Sampled at this many samples a pixel (0: the presets' own)")
    args = parser.parse_args()
    w, h = (int(x) for x in args.resolution.split("x"))

    import bpy
    import render as cli

    cli.ensure_addon()
    from addon.blender import engine
    from addon.plan import auto_terms

    bounds = [float(b) for b in args.bound.split(",")]
    rows, ratios = [], []
    for name, bound in ((n, b) for n in args.presets.split(",") for b in bounds):
        scene, _ = cli.load_scene(name, None)
        scene.render.engine = "SHADING_LAB"
        scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
        props = scene.shading_lab
        if args.world_samples:
            props.world_specular, props.world_samples = "SAMPLED", args.world_samples
        times = {"PRINCIPLED": [], "AUTO": []}
        chosen = ""
        for r in range(args.frames + 1):
            for term_set in (("PRINCIPLED", "AUTO") if r % 2 else ("AUTO", "PRINCIPLED")):
                props.term_set, props.auto_error_bound = term_set, bound
                bpy.ops.render.render()  # the switch: what changed is uploaded, not timed
                bpy.ops.render.render()
                if term_set == "AUTO":
                    chosen = auto_terms.summary(engine.last_term_choices).removeprefix("Auto: ")
                if r:
                    times[term_set].append(engine.last_timings["total_ms"])
            print(f"\r{name} round {r}/{args.frames}", end="", file=sys.stderr, flush=True)
        print(file=sys.stderr)
        auto, principled = statistics.median(times["AUTO"]), statistics.median(times["PRINCIPLED"])
        ratios.append(auto / principled)
        rows.append(f"| {name} | {bound:g} | {auto:.1f} | {principled:.1f} | {auto / principled:.3f}× | "
                    f"{chosen} |")
    mean = math.exp(statistics.mean(math.log(r) for r in ratios))
    n = args.world_samples
    sampled = f" --world-samples {n}`: World Specular: Sampled, {n} samples a pixel" if n else "`"
    text = "\n".join([
        f"The Auto term set against the Principled set, {w}x{h}, medians of {args.frames} alternating "
        f"rounds after a warm-up (`scripts/auto_bench.py{sampled}).", "",
        "| preset | bound | Auto ms | Principled ms | Auto / Principled | Auto chose |",
        "|---|---:|---:|---:|---:|---|",
        *rows, "", f"Geometric mean {mean:.3f}× ({min(ratios):.3f}–{max(ratios):.3f}×).", ""])
    round_robin.write_table(args.table, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
