"""Lights without shadows among lights with: frame time with them shaded in a loop of their own
(no shadow lookups) against one loop for every light (a benchmark, not a test).

    .venv/bin/python scripts/unshadowed_bench.py [--resolution 640x360] [--frames 5]
        [--table docs/bench/unshadowed.md]

The *furnace* preset (12 spheres, 42 suns, shadows and soft shadows on, the Principled set) with
the Cast Shadow of N of its suns on (N = 42, 21, 4, 1, 0; the last N in the file's order, so the
casting suns are not listed first). Each configuration is rendered round-robin after a warm-up
round, in one process, with the split on (``programs.SPLIT_UNSHADOWED``, the default) and off
(every light in one loop that tests for a shadow map: the cost before the split); the table gives
medians of the engine's draw time (GPU work fenced by the read-back) and the largest difference
between the two images of each N. Times are CPU-rasteriser times (Mesa llvmpipe): compare ratios.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

CASTING = (42, 21, 4, 1, 0)


def main() -> int:
    import bpy
    import render
    import round_robin

    from addon import programs

    args, w, h = round_robin.parse_args(__doc__, "unshadowed.md")
    render.ensure_addon()
    scene, _ = render.load_scene("furnace", None)
    scene.render.engine = "SHADING_LAB"
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
    scene.shading_lab.term_set = "PRINCIPLED"
    suns = [obj.data for obj in scene.objects if obj.type == "LIGHT"]

    def apply(config):
        n, split = config
        for i, data in enumerate(suns):
            data.use_shadow = i >= len(suns) - n
        programs.SPLIT_UNSHADOWED = split

    def image(config) -> np.ndarray:
        apply(config)
        path = Path(bpy.app.tempdir) / "unshadowed_bench.exr"
        scene.render.filepath = str(path)
        scene.render.image_settings.file_format = "OPEN_EXR"
        bpy.ops.render.render(write_still=True)
        return np.array(bpy.data.images.load(str(path), check_existing=False).pixels[:])

    differences = {n: float(np.abs(image((n, True)) - image((n, False))).max()) for n in CASTING}
    configs = [(n, split) for n in CASTING for split in (True, False)]
    med = round_robin.median_draw_ms(configs, apply, args.frames)
    programs.SPLIT_UNSHADOWED = True
    rows = [f"| {n} of {len(suns)} | {med[n, True]:.1f} | {med[n, False]:.1f} | "
            f"{med[n, True] / med[n, False]:.2f}x | {differences[n]:.3g} |" for n in CASTING]
    table = "\n".join([
        f"Lights without shadows, {w}x{h}: the *furnace* preset (42 suns, the Principled set, soft "
        f"shadows) with N suns casting (`scripts/unshadowed_bench.py`, {args.frames} frames per "
        "configuration after a warm-up, round-robin; draw + read-back ms, medians). *Apart*: the "
        "suns without a shadow map shaded in a loop without shadow lookups (the default); *one "
        "loop*: every light tested for a map in one loop (a test costs its body on this machine's "
        "rasteriser); the images' largest difference.",
        "",
        "| casting | apart ms | one loop ms | apart / one loop | largest difference |",
        "|---|---:|---:|---:|---:|",
        *rows, ""])
    round_robin.write_table(args.table, table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
