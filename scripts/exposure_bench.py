"""Automatic exposure on the HDRI presets: what it meters, how it looks, what it costs (a
benchmark, not a test).

    .venv/bin/python scripts/exposure_bench.py [--resolution 1280x720] [--frames 7]
        [--figure docs/images/exposure.png] [--table docs/bench/exposure.md]

For each variant of the *world* preset (Blender's bundled HDRI worlds, physically based model,
Blender's Standard view): a render at manual exposure 0 EV and one with automatic exposure
(histogram and log-average metering), the exposure each chose, and the frame time of each
setting, interleaved round by round after a warm-up, as medians. The difference between manual
and automatic frame times is the cost of the reduction (three full-screen stages and a 64-texel
read-back) plus the one full-screen pass that applies the exposure. Writes a markdown table and a
figure (manual above, automatic below). Frame times are CPU-rasteriser times (Mesa llvmpipe):
compare them as ratios within one run.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

SETTINGS = {"manual": ("MANUAL", "HISTOGRAM"), "auto (histogram)": ("AUTO", "HISTOGRAM"),
            "auto (log-average)": ("AUTO", "LOG_AVERAGE")}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolution", default="1280x720")
    parser.add_argument("--frames", type=int, default=7)
    parser.add_argument("--figure", type=Path, default=ROOT / "docs" / "images" / "exposure.png")
    parser.add_argument("--table", type=Path, default=ROOT / "docs" / "bench" / "exposure.md")
    args = parser.parse_args()
    w, h = (int(x) for x in args.resolution.split("x"))

    import bpy
    import render

    from addon import engine, presets

    render.ensure_addon()
    variants = [v.name for v in presets.load_scene_preset("world").variants]
    rows, pictures = [], {}
    out = Path(tempfile.mkdtemp(prefix="exposure_bench_"))
    for variant in variants:
        scene, _ = render.load_scene("world", variant)
        scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
        scene.render.engine = "SHADING_LAB"
        times = {name: [] for name in SETTINGS}
        chosen = {}
        for round_index in range(args.frames + 1):
            for name, (mode, method) in SETTINGS.items():
                scene.shading_lab.exposure_mode, scene.shading_lab.exposure_method = mode, method
                bpy.ops.render.render()
                if round_index > 0:  # round 0 is the warm-up (programs, the world's tables)
                    times[name].append(engine.last_timings["draw_ms"])
                chosen[name] = engine.last_exposures.get("main", (0.0, 0.0))[0]
                if round_index == args.frames and name != "auto (log-average)":
                    png = out / f"{variant}_{mode}.png"
                    render.save(bpy.data.images["Render Result"], scene, png, "PNG")
                    pictures[variant, mode] = png
            print(f"\r{variant}: round {round_index}/{args.frames}", end="", file=sys.stderr, flush=True)
        print(file=sys.stderr)
        base = statistics.median(times["manual"])
        for name in SETTINGS:
            med = statistics.median(times[name])
            rows.append(f"| {variant} | {name} | {chosen[name]:+.2f} | {med:.1f} | {med - base:+.1f} | "
                        f"{med / base:.3f}x |")
    table = "\n".join([
        f"Automatic exposure on the *world* preset's HDRI variants, {w}x{h}, physically based model, "
        f"{args.frames} frames per setting after a warm-up, interleaved (`scripts/exposure_bench.py`). "
        "Draw + read-back time, medians; the cost of automatic exposure is the difference to manual.",
        "",
        "| world | exposure | EV | draw ms | vs manual ms | ratio |",
        "|---|---|---:|---:|---:|---:|",
        *rows, ""])
    print(table)
    args.table.parent.mkdir(parents=True, exist_ok=True)
    args.table.write_text(table)
    _figure(variants, pictures, args.figure)
    print(f"wrote {args.table} and {args.figure}")
    return 0


def _figure(variants, pictures, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(variants), figsize=(3.2 * len(variants), 4.2), squeeze=False)
    for col, variant in enumerate(variants):
        for row, mode in enumerate(("MANUAL", "AUTO")):
            ax = axes[row][col]
            ax.imshow(plt.imread(str(pictures[variant, mode])))
            ax.set_xticks([])
            ax.set_yticks([])
            if row == 0:
                ax.set_title(variant)
            if col == 0:
                ax.set_ylabel("manual 0 EV" if mode == "MANUAL" else "automatic")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    sys.exit(main())
