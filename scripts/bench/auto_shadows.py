"""Would a cheaper shadow filter per material pay as an Auto candidate? Per preset: each
material's error with hard shadows against soft ones, and the frame time of each (a benchmark,
not a test).

    .venv/bin/python scripts/auto_shadows.py [--resolution 640x360] [--frames 5]
        [--table docs/bench/auto_shadows.md] [--bound 0.5]

The only shadow setting a material could choose is the filter: soft shadows (penumbrae from the
light's size: a blocker search and a wider filter) or hard ones (a bilinear filter over one
texel). The maps themselves are drawn per light for every receiver. For every preset with a light
that casts a shadow, each material's Delta E_ITP at the Auto quantile between the frame with hard
shadows and the frame with soft ones (the Verify operator's measurement, with its reference
frame drawn with hard shadows), and how many materials a hard-shadow candidate would pass at
``--bound`` with Auto's margin; and the frame time with soft and with hard shadows (medians of
``--frames`` round-robin renders, the Principled set). Times are CPU-rasteriser times: compare
ratios.
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

PRESETS = ("fresnel", "furnace", "hdr", "long_tail", "material_grid", "portability", "roughness_sweep",
           "softbox", "world")


def main() -> int:
    import argparse

    import bpy
    import render
    import round_robin

    from addon.blender import engine
    from addon.plan import auto_terms

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolution", default="640x360")
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--bound", type=float, default=0.5)
    parser.add_argument("--table", type=Path, default=ROOT / "docs" / "bench" / "auto_shadows.md")
    args = parser.parse_args()
    w, h = (int(x) for x in args.resolution.split("x"))
    render.ensure_addon()
    principled = auto_terms.principled_snapshot

    def hard_reference(snapshot):  # the Verify operator's reference, drawn with hard shadows
        reference = principled(snapshot)
        return replace(reference, settings=replace(reference.settings, soft_shadows=False))

    rows = []
    for name in PRESETS:
        scene, _ = render.load_scene(name, None)
        scene.render.engine = "SHADING_LAB"
        scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
        props = scene.shading_lab
        lights = [obj.data for obj in scene.objects if obj.type == "LIGHT" and obj.data.use_shadow]
        if not (props.shadows and lights):
            continue
        sized = sum(1 for data in lights if data.type == "AREA"
                    or (data.angle if data.type == "SUN" else data.shadow_soft_size) > 0.0)
        # Auto at the smallest bound keeps every material on the Principled set: Verify then
        # measures hard shadows against soft ones alone
        props.term_set, props.auto_error_bound = "AUTO", 0.01
        auto_terms.principled_snapshot = hard_reference
        engine.request_verification()
        try:
            bpy.ops.render.render()
        finally:
            auto_terms.principled_snapshot = principled
        errors = sorted(v.measured for v in engine.last_verification.values())
        passing = sum(1 for e in errors if e * auto_terms.MARGIN <= args.bound)
        props.term_set = "PRINCIPLED"

        def apply(soft, props=props):
            props.soft_shadows = soft

        med = round_robin.median_draw_ms([True, False], apply, args.frames)
        props.soft_shadows = True
        spread = f"{errors[0]:.2f} – {errors[-1]:.2f}" if errors else "–"
        rows.append(f"| {name} | {len(lights)} ({sized} with a size) | {len(errors)} | {spread} | "
                    f"{passing} of {len(errors)} | {med[True]:.1f} | {med[False]:.1f} | "
                    f"{med[False] / med[True]:.2f}x |")
        print(rows[-1], flush=True)
    table = "\n".join([
        f"Shadows as an Auto candidate, {w}x{h} (`scripts/auto_shadows.py`). Per preset with casting "
        "lights: each material's Delta E_ITP at the 99th percentile of its pixels between hard and "
        f"soft shadows (the Verify operator's measurement), how many a hard-shadow candidate would "
        f"pass at bound {args.bound:g} with Auto's margin {auto_terms.MARGIN:g}, and the frame with "
        "soft and with hard shadows (the Principled set; draw + read-back ms, medians of "
        f"{args.frames} round-robin renders after a warm-up). A program holds the penumbrae's code "
        "only where a light with a shadow map has a size, so where none has one the two frames run "
        "the same program.",
        "",
        "| preset | casting lights | materials | hard vs soft Delta E_ITP | within the bound | soft ms "
        "| hard ms | hard / soft |",
        "|---|---|---:|---|---|---:|---:|---:|",
        *rows, ""])
    round_robin.write_table(args.table, table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
