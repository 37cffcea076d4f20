"""Automatic exposure on the HDRI presets: what it meters, how it looks, what it costs (a
benchmark, not a test).

    .venv/bin/python scripts/exposure_bench.py [--resolution 1280x720] [--frames 7]
        [--figure docs/images/exposure.png] [--table docs/bench/exposure.md]

For each variant of the *world* preset (Blender's bundled HDRI worlds, physically based model,
Blender's Standard view): a render at manual exposure 0 EV and one with automatic exposure
(histogram and log-average metering), the exposure each chose, and the frame time of each
setting, interleaved round by round after a warm-up, as medians. The difference between manual
and automatic frame times is the cost of the reduction (three full-screen stages and a 64-texel
read-back) plus the one full-screen pass that applies the exposure - within the noise of
second-long frames on a shared machine, so the reduction is also timed alone: ExposurePass's
histogram of a 1280 x 720 HDR target, after a fence, read-back included, median of 21. Writes a
markdown table and a figure (manual above, automatic below). Times are CPU-rasteriser times
(Mesa llvmpipe): compare them as ratios within one run.
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

    from addon.blender import engine
    from addon.scene import presets

    render.ensure_addon()
    alone = reduction_ms(1280, 720)
    print(f"reduction of a 1280x720 frame alone: {alone:.2f} ms (median of 21)")
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
        *rows, "",
        f"The reduction alone (ExposurePass's histogram of a 1280x720 RGBA32F frame, read-back "
        f"included, median of 21): **{alone:.2f} ms**.", ""])
    print(table)
    args.table.parent.mkdir(parents=True, exist_ok=True)
    args.table.write_text(table)
    _figure(variants, pictures, args.figure)
    print(f"wrote {args.table} and {args.figure}")
    return 0


def reduction_ms(width: int, height: int, repeats: int = 21) -> float:
    """Median time of the automatic-exposure reduction of a width x height frame, alone."""
    import time

    import bpy
    import gpu
    import numpy as np

    from addon.frame.gpu_scene import SceneResources
    from addon.frame.passes import ExposurePass, Frame, Target, full_screen_batch

    times = []

    class _Bench(bpy.types.RenderEngine):
        bl_idname = "SHADING_LAB_EXPOSURE_BENCH"
        bl_label = "exposure bench"
        bl_use_gpu_context = True

        def render(self, depsgraph):
            rng = np.random.default_rng(1)
            pixels = np.concatenate([rng.lognormal(0.0, 3.0, (height, width, 3)),
                                     np.ones((height, width, 1))], axis=-1).astype(np.float32)
            target = Target(width, height, depth=False)
            buffer = gpu.types.Buffer("FLOAT", pixels.size, pixels.ravel())
            target.texture_color = gpu.types.GPUTexture((width, height), format="RGBA32F", data=buffer)
            frame = Frame(None, SceneResources(), full_screen_batch())
            step = ExposurePass()
            step.histogram(frame, target)  # warm-up: programs compiled, targets made
            for _ in range(repeats):
                target.fence()
                start = time.perf_counter()
                step.histogram(frame, target)  # ends with its 64-texel read-back
                times.append(1e3 * (time.perf_counter() - start))
            step.free()

    bpy.utils.register_class(_Bench)
    scene = bpy.context.scene
    previous = scene.render.engine
    try:
        scene.render.engine = _Bench.bl_idname
        scene.render.resolution_x, scene.render.resolution_y = 4, 4
        bpy.ops.render.render()
    finally:
        scene.render.engine = previous
        bpy.utils.unregister_class(_Bench)
    return statistics.median(times)


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
