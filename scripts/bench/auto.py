"""The Auto term set against the Principled set on every preset: frame time.

Per preset, Auto (at ``--bound``) and the Principled set are rendered alternately, one warm-up
round (program compiles, Auto's first prediction) then ``--frames`` rounds, in one process; each
timed render follows a render of the same set (after a switch of sets an untimed one: the switch
re-uploads what changed); the table gives the medians of the engine's total time (extraction,
including Auto's cached prediction, + draw + read-back + result) and their ratio, with the sets
Auto chose. Where Auto draws the very same programs as the Principled set, the ratio shows this
machine's noise (+-5 % between runs of 9 rounds; 0.997 and 0.995 over 40 renders each on fresnel
and material_grid). ``models`` times Auto among every configuration; this isolates the one
comparison, with fewer configurations sharing the noise. ``--world-samples N`` renders every
preset with World Specular: Sampled at N samples a pixel (where the world has images, Auto may
then take the split sum: its largest saving) and writes ``auto_world.md`` instead of ``auto.md``.
"""

from __future__ import annotations

from .harness import page, scenes, standard, timing

PAGE = "auto.md"
WORLD_PAGE = "auto_world.md"
QUICK = dict(resolution="160x90", frames=1, presets="long_tail")
PRESETS = "fresnel,furnace,hdr,long_tail,material_grid,portability,roughness_sweep,softbox,world"


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=7, presets=PRESETS)
    parser.add_argument("--bound", default="0.5", help="error bound(s), comma-separated (default 0.5)")
    parser.add_argument("--world-samples", type=int, default=0,
                        help="World Specular: Sampled at this many samples a pixel (0: the presets' own)")


def run(ctx) -> None:
    from addon.blender import engine
    from addon.plan import auto_terms

    args = ctx.args
    bounds = [float(b) for b in args.bound.split(",")]
    rows, ratios = [], []
    for name, bound in ((n, b) for n in args.presets for b in bounds):
        scene = scenes.preset(name, args.resolution)
        props = scene.shading_lab
        if args.world_samples:
            props.world_specular, props.world_samples = "SAMPLED", args.world_samples
        chosen = []

        def render(term_set, props=props, bound=bound, chosen=chosen):
            props.term_set, props.auto_error_bound = term_set, bound
            timings = timing.render_timed()
            if term_set == "AUTO":
                chosen[:] = [auto_terms.summary(engine.last_term_choices).removeprefix("Auto: ")]
            return timings

        auto, principled = (t["total_ms"] for t in timing.round_robin(
            ["AUTO", "PRINCIPLED"], args.frames, render, ctx.progress, name, state_of=lambda s: s))
        ratios.append(auto / principled)
        rows.append([name, f"{bound:g}", f"{auto:.1f}", f"{principled:.1f}", f"{auto / principled:.3f}×",
                     chosen[0]])
    n = args.world_samples
    ctx.page("The Auto term set against the Principled set", [
        f"{page.res(args.resolution)}, medians of {args.frames} alternating rounds after a warm-up"
        + (f"; World Specular: Sampled, {n} samples a pixel." if n else "."), "",
        *page.table(["preset", "bound", "Auto ms", "Principled ms", "Auto / Principled", "Auto chose"], rows,
                    "lrrrrl"), "",
        f"Geometric mean {page.geomean(ratios):.3f}× ({min(ratios):.3f}–{max(ratios):.3f}×)."],
        name=WORLD_PAGE if n else None)

