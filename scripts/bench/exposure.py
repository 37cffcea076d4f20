"""Automatic exposure on the HDRI presets: what it meters, how it looks, what it costs.

For each variant of the *world* preset (Blender's bundled HDRI worlds, physically based model,
Blender's Standard view): a render at manual exposure 0 EV and one with automatic exposure
(histogram and log-average metering), the exposure each chose, and the frame time of each
setting, round-robin after a warm-up, as medians. The difference between manual and automatic
frame times is the cost of the reduction (three full-screen stages and a 64-texel read-back) plus
the one full-screen pass that applies the exposure - within the noise of second-long frames on a
shared machine, so the reduction is also timed alone: ExposurePass's histogram of a 1280 x 720
HDR target, after a fence, read-back included, median of ``--repeats``. Writes a Markdown table
and a figure (manual above, automatic below; ``docs/images/exposure.png``, beside the page when
``--out`` is another folder).
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

from .harness import ROOT, page, plots, scenes, standard, timing

PAGE = "exposure.md"
FIGURE = ROOT / "docs" / "images" / "exposure.png"
QUICK = dict(resolution="160x90", frames=1, variants="forest", repeats=3)
SETTINGS = {"manual": ("MANUAL", "HISTOGRAM"), "auto (histogram)": ("AUTO", "HISTOGRAM"),
            "auto (log-average)": ("AUTO", "LOG_AVERAGE")}
PICTURED = ("manual", "auto (histogram)")


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=7)
    parser.add_argument("--variants", default=None, help="comma-separated world variants (default: all)")
    parser.add_argument("--repeats", type=int, default=21, help="timings of the reduction alone (default 21)")


def reduction_ms(width: int, height: int, repeats: int) -> float:
    """Median time of the automatic-exposure reduction of a width x height frame, alone."""
    import gpu
    import gpu_harness
    import numpy as np

    from addon.frame.gpu_scene import SceneResources
    from addon.frame.passes import ExposurePass, Frame, Target, full_screen_batch

    def job(_depsgraph):
        rng = np.random.default_rng(1)
        pixels = np.concatenate([rng.lognormal(0.0, 3.0, (height, width, 3)),
                                 np.ones((height, width, 1))], axis=-1).astype(np.float32)
        target = Target(width, height, depth=False)
        buffer = gpu.types.Buffer("FLOAT", pixels.size, pixels.ravel())
        target.texture_color = gpu.types.GPUTexture((width, height), format="RGBA32F", data=buffer)
        frame = Frame(None, SceneResources(), full_screen_batch())
        step = ExposurePass()
        times = []
        try:
            step.histogram(frame, target)  # warm-up: programs compiled, targets made
            for _ in range(repeats):
                target.fence()
                start = time.perf_counter()
                step.histogram(frame, target)  # ends with its 64-texel read-back
                times.append(1e3 * (time.perf_counter() - start))
        finally:
            step.free()
        return statistics.median(times)

    return gpu_harness.run_on_gpu(job)


def figure(variants, pictures, path: Path) -> None:
    plt = plots.pyplot()
    fig, axes = plt.subplots(2, len(variants), figsize=(3.2 * len(variants), 4.2), squeeze=False)
    for col, variant in enumerate(variants):
        for row, name in enumerate(PICTURED):
            plots.image_panel(axes[row][col], plt.imread(str(pictures[variant, name])),
                              variant if row == 0 else "", fontsize=None,
                              ylabel=("manual 0 EV", "automatic")[row] if col == 0 else "")
    fig.tight_layout()
    plots.save(fig, path, dpi=110)


def measure(variant: str, args, progress, tmp: Path, pictures: dict) -> list[list[str]]:
    """The table's rows of one world variant; its pictures into ``pictures``."""
    import bpy
    import render

    from addon.blender import engine

    scene = scenes.preset("world", args.resolution, variant)

    def apply(name):
        scene.shading_lab.exposure_mode, scene.shading_lab.exposure_method = SETTINGS[name]

    med = timing.median_ms(list(SETTINGS), apply, args.frames, progress, variant)
    chosen = {}
    for name in SETTINGS:  # the exposure each chose, and the pictures, from one more render each
        apply(name)
        bpy.ops.render.render()
        chosen[name] = engine.last_exposures.get("main", (0.0, 0.0))[0]
        if name in PICTURED:
            pictures[variant, name] = tmp / f"{variant}_{SETTINGS[name][0]}.png"
            render.save(bpy.data.images["Render Result"], scene, pictures[variant, name], "PNG")
    base = med["manual"]
    return [[variant, name, f"{chosen[name]:+.2f}", f"{med[name]:.1f}", f"{med[name] - base:+.1f}",
             f"{med[name] / base:.3f}x"] for name in SETTINGS]


def run(ctx) -> None:
    from addon.scene import presets

    args = ctx.args
    alone = reduction_ms(1280, 720, args.repeats)
    variants = args.variants.split(",") if args.variants else [v.name for v in
                                                                presets.load_scene_preset("world").variants]
    rows = []
    with tempfile.TemporaryDirectory(prefix="exposure_bench_") as tmp:
        pictures = {}
        for variant in variants:
            rows += measure(variant, args, ctx.progress, Path(tmp), pictures)
        figure(variants, pictures, ctx.path(FIGURE))
    ctx.page("Automatic exposure", [
        f"The *world* preset's HDRI variants, {page.res(args.resolution)}, physically based model, "
        f"{args.frames} frames per setting after a warm-up, round-robin. Draw + read-back time, medians; "
        "the cost of automatic exposure is the difference to manual.", "",
        *page.table(["world", "exposure", "EV", "draw ms", "vs manual ms", "ratio"], rows, "llrrrr"), "",
        f"The reduction alone (ExposurePass's histogram of a 1280x720 RGBA32F frame, read-back "
        f"included, median of {args.repeats}): **{alone:.2f} ms**."])
