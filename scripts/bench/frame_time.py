"""Frame time of each shading model on the demo scene.

Renders the demo scene with every model round-robin in one process, after a warm-up round
(program compiles). Reports medians of the engine's phases: scene extraction, GPU draw +
read-back (fenced by the read-back), and handing the pixels to Blender.
"""

from __future__ import annotations

from .harness import page, scenes, standard, timing

PAGE = "frame_time.md"
QUICK = dict(resolution="320x180", frames=1)


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=7)


def run(ctx) -> None:
    from addon.scene.snapshot import MODELS

    args = ctx.args
    scene = scenes.demo(args.resolution)

    def render(model):
        scene.shading_lab.model = model
        return timing.render_timed(scene)

    med = dict(zip(MODELS, timing.round_robin(list(MODELS), args.frames, render, ctx.progress)))
    base = med["BLINN_PHONG"]["total_ms"]
    faces = sum(len(o.data.polygons) for o in scene.objects if o.type == "MESH")
    ctx.page("Frame time per model, demo scene", [
        f"The demo scene (~{faces:,} faces), {page.res(args.resolution)}, {args.frames} frames per "
        "model after a warm-up, round-robin.", "",
        *page.table(["model", "total ms (median)", "extract ms", "draw + read-back ms", "result ms",
                     "vs Blinn-Phong"],
                    [[model, *(f"{m[k]:.1f}" for k in ("total_ms", "extract_ms", "draw_ms", "result_ms")),
                      f"{m['total_ms'] / base:.2f}x"] for model, m in med.items()])])
