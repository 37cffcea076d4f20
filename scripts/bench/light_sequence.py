"""A scene of one or two lights shaded each by its own call against the loops.

The presets of one or two lights, the Principled set, each in three configurations:
- *calls* (the default): each light shaded by its own call, its index and kind constants
  (``programs.UNROLLED_LIGHTS``, ``Features.light_sequence``);
- *loops*: the loop over each group of lights (``UNROLLED_LIGHTS`` 0), whose index the CPU
  rasteriser's compiler cannot tell is the same at every pixel: each read of a light's data is a
  gather per pixel;
- *loops, tiles*: the loops with light culling's tiles wherever some light has a finite reach,
  as before the tiles were made only where a reach ends inside the scene and their lists leave
  out enough lights (``programs.uses_light_tiles`` without the scene's box, ``light_tiles.lists_pay``
  always).
Round-robin after a warm-up round, in one process; medians of the engine's draw time (GPU work
fenced by the read-back), and the largest difference between the images of *calls* and of each
other configuration.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from .harness import engines, page, scenes, standard, timing

PAGE = "light_sequence.md"
QUICK = dict(resolution="160x90", frames=1, presets="long_tail")
PRESETS = "long_tail,fresnel,hdr,material_grid,roughness_sweep,softbox"
CONFIGS = ("calls", "loops", "loops, tiles")


def options(parser) -> None:
    standard(parser, resolution="640x360", frames=5, presets=PRESETS)


def run(ctx) -> None:
    from addon.plan import light_tiles, programs

    args = ctx.args
    unrolled, uses_light_tiles = programs.UNROLLED_LIGHTS, programs.uses_light_tiles
    lists_pay = light_tiles.lists_pay

    def configure(config: str) -> None:
        programs.UNROLLED_LIGHTS = unrolled if config == "calls" else 0
        tiles = config == "loops, tiles"
        programs.uses_light_tiles = ((lambda snapshot, box=None: uses_light_tiles(snapshot)) if tiles
                                     else uses_light_tiles)
        light_tiles.lists_pay = (lambda lists, lights: lights > 0) if tiles else lists_pay

    rows = []
    try:
        for name in args.presets:
            scene = scenes.preset(name, args.resolution)
            scene.shading_lab.term_set = "PRINCIPLED"
            lights = sum(1 for obj in scene.objects if obj.type == "LIGHT" and not obj.hide_render)
            images = {}
            with tempfile.TemporaryDirectory() as tmp:
                for config in CONFIGS:
                    configure(config)
                    images[config] = engines.image(scene, Path(tmp) / f"{name}.exr")[0]
            differences = [float(np.abs(images["calls"] - images[c]).max()) for c in CONFIGS[1:]]
            med = timing.median_ms(CONFIGS, configure, args.frames, ctx.progress, name)
            rows.append([name, lights, *(f"{med[c]:.1f}" for c in CONFIGS),
                         f"{med['calls'] / med['loops']:.2f}x", f"{med['calls'] / med['loops, tiles']:.2f}x",
                         f"{differences[0]:.3g} / {differences[1]:.3g}"])
    finally:
        configure("calls")
    ctx.page("Each light by its own call", [
        f"A scene of one or two lights shaded each by its own call, {page.res(args.resolution)}, the "
        f"Principled set, {args.frames} frames per configuration after a warm-up, round-robin; draw + "
        "read-back ms, medians. *Calls*: each light by its own call, its index and kind constants "
        "(the default); *loops*: the loop over each group of lights, each read of a light's data a "
        "gather per pixel on this machine's rasteriser; *loops, tiles*: the loops with light "
        "culling's tiles wherever a light's reach is finite (before the tiles were made only where a "
        "reach ends inside the scene); the largest difference of each one's image from the calls'.", "",
        *page.table(["preset", "lights", "calls ms", "loops ms", "loops, tiles ms", "calls / loops",
                     "calls / loops, tiles", "largest difference"], rows)])
