"""Would a cheaper shadow filter per material pay as an Auto candidate? Per preset: each
material's error with hard shadows against soft ones, and the frame time of each.

The only shadow setting a material could choose is the filter: soft shadows (penumbrae from the
light's size: a blocker search and a wider filter) or hard ones (a bilinear filter over one
texel). The maps themselves are drawn per light for every receiver. For every preset with a light
that casts a shadow, each material's Delta E_ITP at the Auto quantile between the frame with hard
shadows and the frame with soft ones (the Verify operator's measurement, with its reference
frame drawn with hard shadows), and how many materials a hard-shadow candidate would pass at
``--bound`` with Auto's margin; and the frame time with soft and with hard shadows (medians of
``--frames`` round-robin renders, the Principled set).
"""

from __future__ import annotations

from dataclasses import replace

from .harness import page, scenes, standard, timing

PAGE = "auto_shadows.md"
QUICK = dict(resolution="160x90", frames=1, presets="softbox")
PRESETS = "fresnel,furnace,hdr,long_tail,material_grid,portability,roughness_sweep,softbox,world"


def options(parser) -> None:
    standard(parser, resolution="640x360", frames=5, presets=PRESETS)
    parser.add_argument("--bound", type=float, default=0.5, help="Delta E_ITP bound (default 0.5)")


def hard_vs_soft(props, auto_terms) -> list[float]:
    """Each material's error, hard shadows against soft: Auto at the smallest bound keeps every
    material on the Principled set, so Verify measures the shadows alone, against its reference
    drawn with hard shadows."""
    import bpy

    from addon.blender import engine

    principled = auto_terms.principled_snapshot

    def hard_reference(snapshot):
        reference = principled(snapshot)
        return replace(reference, settings=replace(reference.settings, soft_shadows=False))

    props.term_set, props.auto_error_bound = "AUTO", 0.01
    auto_terms.principled_snapshot = hard_reference
    engine.request_verification()
    try:
        bpy.ops.render.render()
    finally:
        auto_terms.principled_snapshot = principled
    return sorted(v.measured for v in engine.last_verification.values())


def run(ctx) -> None:
    from addon.plan import auto_terms

    args = ctx.args
    rows = []
    for name in args.presets:
        scene = scenes.preset(name, args.resolution)
        props = scene.shading_lab
        lights = scenes.lights(scene, casting=True)
        if not (props.shadows and lights):
            continue
        sized = sum(1 for data in lights if data.type == "AREA"
                    or (data.angle if data.type == "SUN" else data.shadow_soft_size) > 0.0)
        errors = hard_vs_soft(props, auto_terms)
        passing = sum(1 for e in errors if e * auto_terms.MARGIN <= args.bound)
        props.term_set = "PRINCIPLED"

        def apply(soft, props=props):
            props.soft_shadows = soft

        med = timing.median_ms([True, False], apply, args.frames, ctx.progress, name)
        props.soft_shadows = True
        rows.append([name, f"{len(lights)} ({sized} with a size)", len(errors),
                     f"{errors[0]:.2f} – {errors[-1]:.2f}" if errors else "–", f"{passing} of {len(errors)}",
                     f"{med[True]:.1f}", f"{med[False]:.1f}", f"{med[False] / med[True]:.2f}x"])
    ctx.page("Shadows as an Auto candidate", [
        f"{page.res(args.resolution)}. Per preset with casting lights: each material's Delta E_ITP at "
        "the 99th percentile of its pixels between hard and soft shadows (the Verify operator's "
        f"measurement), how many a hard-shadow candidate would pass at bound {args.bound:g} with "
        f"Auto's margin {auto_terms.MARGIN:g}, and the frame with soft and with hard shadows (the "
        f"Principled set; draw + read-back ms, medians of {args.frames} round-robin renders after a "
        "warm-up). A program holds the penumbrae's code only where a light with a shadow map has a "
        "size, so where none has one the two frames run the same program.", "",
        *page.table(["preset", "casting lights", "materials", "hard vs soft Delta E_ITP", "within the bound",
                     "soft ms", "hard ms", "hard / soft"], rows, "llrllrrr")])
