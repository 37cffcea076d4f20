"""Light culling: frame time against the number of lights that each reach a sixteenth of the
screen, with culling on and off.

A plane fills an orthographic view; N point lights (N = 4, 16, 64, on a grid over the view, 0.25 m
above the plane) each reach, by their Custom Distance, a disc of a sixteenth of the view's area.
Every configuration (model x N x culling) is rendered round-robin after a warm-up round, in one
process; the table gives medians of the engine's draw time (GPU work fenced by the read-back) and
the ratio to 4 lights.
"""

from __future__ import annotations

import math

from .harness import page, scenes, standard, timing

PAGE = "light_culling.md"
QUICK = dict(resolution="160x90", frames=1)
COUNTS = (4, 16, 64)
MODELS = ("BLINN_PHONG", "PBR")
HEIGHT = 0.25  # the lights above the plane (m)
VIEW = 8.0  # the view's width (m)


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=5)


def build(size: tuple[int, int]):
    import bpy

    scene = scenes.empty(size)
    scenes.camera(scene, (0.0, 0.0, 5.0), ortho=VIEW)
    bpy.ops.mesh.primitive_plane_add(size=2 * VIEW)
    view_h = VIEW * size[1] / size[0]
    disc = math.sqrt(VIEW * view_h / 16.0 / math.pi)  # a sixteenth of the view's area
    reach = math.hypot(disc, HEIGHT)
    groups = {}
    for n in COUNTS:
        side = int(math.sqrt(n))
        groups[n] = [scenes.light(scene, f"L{n}_{i}", "POINT",
                                  (((i % side) + 0.5) / side * VIEW - VIEW / 2,
                                   ((i // side) + 0.5) / side * view_h - view_h / 2, HEIGHT),
                                  energy=20.0, shadow_soft_size=0.0, use_shadow=False,
                                  use_custom_distance=True, cutoff_distance=reach) for i in range(n)]
    return scene, groups


def run(ctx) -> None:
    args = ctx.args
    scene, groups = build(args.resolution)

    def apply(config):
        model, n, culling = config
        scenes.show_only(groups, n)
        scene.shading_lab.model, scene.shading_lab.light_culling = model, culling

    configs = [(model, n, culling) for model in MODELS for n in COUNTS for culling in (True, False)]
    med = timing.median_ms(configs, apply, args.frames, ctx.progress)
    rows = []
    for model in MODELS:
        for n in COUNTS:
            on, off = med[model, n, True], med[model, n, False]
            rows.append([model, n, f"{on:.1f}", f"{on / med[model, COUNTS[0], True]:.2f}x", f"{off:.1f}",
                         f"{off / med[model, COUNTS[0], False]:.2f}x", f"{off / on:.2f}x"])
    ctx.page("Light culling", [
        f"{page.res(args.resolution)}: a plane under N point lights that each reach a sixteenth of the "
        "view (points without radius, Cast Shadow off: the plane alone would cast nothing, and 64 "
        "lights' six maps each are not what this measures; tests/test_light_tiles.py renders culling "
        f"with shadows on); {args.frames} frames per configuration after a warm-up, round-robin; draw "
        "+ read-back ms, medians.", "",
        *page.table(["model", "lights", "culled ms", "vs 4 lights", "every light ms", "vs 4 lights",
                     "culling speed-up"], rows)])
