"""A scene of one or two lights shaded each by its own call against the loops (a benchmark, not a
test).

    .venv/bin/python scripts/light_sequence_bench.py [--resolution 640x360] [--frames 5]
        [--table docs/bench/light_sequence.md]

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
other configuration. Times are CPU-rasteriser times (Mesa llvmpipe): compare ratios.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

PRESETS = ("long_tail", "fresnel", "hdr", "material_grid", "roughness_sweep", "softbox")
CONFIGS = ("calls", "loops", "loops, tiles")


def main() -> int:
    import bpy
    import render
    import round_robin

    from addon.plan import light_tiles, programs

    args, w, h = round_robin.parse_args(__doc__, "light_sequence.md")
    render.ensure_addon()
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
        for name in PRESETS:
            scene, _ = render.load_scene(name, None)
            scene.render.engine = "SHADING_LAB"
            scene.render.resolution_x, scene.render.resolution_y = w, h
            scene.render.resolution_percentage = 100
            scene.shading_lab.term_set = "PRINCIPLED"
            lights = sum(1 for obj in scene.objects if obj.type == "LIGHT" and not obj.hide_render)

            def image(config: str, scene=scene, name=name) -> np.ndarray:
                configure(config)
                path = Path(bpy.app.tempdir) / f"light_sequence_bench_{name}.exr"
                scene.render.filepath = str(path)
                scene.render.image_settings.file_format = "OPEN_EXR"
                bpy.ops.render.render(write_still=True)
                return np.array(bpy.data.images.load(str(path), check_existing=False).pixels[:])

            images = {config: image(config) for config in CONFIGS}
            differences = [float(np.abs(images["calls"] - images[c]).max()) for c in CONFIGS[1:]]
            med = round_robin.median_draw_ms(CONFIGS, configure, args.frames)
            rows.append(f"| {name} | {lights} | {med['calls']:.1f} | {med['loops']:.1f} | "
                        f"{med['loops, tiles']:.1f} | {med['calls'] / med['loops']:.2f}x | "
                        f"{med['calls'] / med['loops, tiles']:.2f}x | {differences[0]:.3g} / "
                        f"{differences[1]:.3g} |")
    finally:
        configure("calls")
    table = "\n".join([
        f"A scene of one or two lights shaded each by its own call, {w}x{h}, the Principled set "
        f"(`scripts/light_sequence_bench.py`, {args.frames} frames per configuration after a "
        "warm-up, round-robin; draw + read-back ms, medians). *Calls*: each light by its own call, "
        "its index and kind constants (the default); *loops*: the loop over each group of lights, "
        "each read of a light's data a gather per pixel on this machine's rasteriser; *loops, "
        "tiles*: the loops with light culling's tiles wherever a light's reach is finite (before "
        "the tiles were made only where a reach ends inside the scene); the largest difference of "
        "each one's image from the calls'.",
        "",
        "| preset | lights | calls ms | loops ms | loops, tiles ms | calls / loops | "
        "calls / loops, tiles | largest difference |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
        *rows, ""])
    round_robin.write_table(args.table, table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
