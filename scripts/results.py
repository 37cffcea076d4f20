"""Regenerate docs/results.md: the seed's comparisons, measured (one command).

    .venv/bin/python scripts/results.py [--resolution 400x225] [--reference-samples 256]

For each phenomenon of the source report's section 2.4 (Fresnel, long-tailed highlights, HDR,
energy conservation), its stated aim (material portability, measured materials) and the world as
a light (Blender's startup file, the world preset under four HDRIs), renders the scene with
Blinn-Phong, Phong and the physically based model against the Cycles reference (direct light
only, world on and occluded, lights' shadows on, pixel-centre sampling) through compare.py, and
writes the labelled images to docs/results/ and the numbers and what they show to
docs/results.md.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

import compare  # noqa: E402
from bench.harness import page  # noqa: E402

from addon.scene.snapshot import MODEL_CHOICES  # noqa: E402

DOCS = ROOT / "docs"
OUT = DOCS / "results"


def run(scene: str, args, variant: str | None = None, tag: str = "", **terms) -> dict:
    ns = compare.parse_args([scene])  # compare.py's own defaults: every option it reads
    ns.tag, ns.resolution, ns.reference_samples = tag, args.resolution, args.reference_samples
    ns.variant, ns.out = variant, OUT
    for key, value in terms.items():
        setattr(ns, key, value)
    result = compare.compare(ns)
    print(f"  {result['stem']}: " + ", ".join(f"{k} FLIP {e.flip:.3f}" for k, e in result["errors"].items()),
          file=sys.stderr)
    return result


VARIANTS = ("studio", "noon", "sunset", "spot")
#: The Auto term set's bound for the material grid: above the default, to show what a looser
#: bound trades.
AUTO_BOUND = 1.0
WORLD_VARIANTS = ("forest", "city", "studio", "sunset")


def _portability_scene(args, variant):
    """The portability preset under ``variant``, ready for Shading Lab, and its Cycles reference."""
    import reference
    import render as cli

    cli.ensure_addon()
    scene, _ = cli.load_scene("portability", variant)
    w, h = cli.parse_resolution(args.resolution)
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
    scene.render.engine = "SHADING_LAB"
    ref, _ = reference.render_reference(scene, samples=args.reference_samples)
    return scene, ref


def _apply_blinn_phong(scene, spec_scale: float, shininess_scale: float, ambient: float) -> None:
    """Scale every material's Blinn-Phong specular colour and shininess (from its derived values)."""
    from addon.blender.materials import material_params

    scene.shading_lab.model = "BLINN_PHONG"
    scene.shading_lab.ambient = ambient
    for mat in {slot.material for obj in scene.objects for slot in obj.material_slots if slot.material}:
        props = mat.shading_lab
        props.use_specular_color = props.use_shininess = False
        p = material_params(mat)
        props.specular_color = tuple(min(c * spec_scale, 1e3) for c in p.specular_color)
        props.shininess = p.shininess * shininess_scale
        props.use_specular_color = props.use_shininess = True


def blinn_phong_tuned_for_studio(args) -> dict:
    """Tune Blinn-Phong (specular scale, shininess scale, ambient) to the studio lighting by a
    grid search on FLIP against Cycles, then keep those parameters under the other lightings."""
    import tempfile

    import metrics
    import reference

    grid = [(k, m, a) for k in (0.0625, 0.125, 0.25, 0.5, 1.0, 2.0) for m in (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
            for a in (0.0, 0.05, 0.2)]
    scene, ref = _portability_scene(args, "studio")
    best = None
    with tempfile.TemporaryDirectory() as tmp:
        for params in grid:
            _apply_blinn_phong(scene, *params)
            flip = metrics.errors(ref, reference.render_to_array(scene, Path(tmp) / "bp.exr")).flip
            if best is None or flip < best[0]:
                best = (flip, params)
        tuned = {}
        for variant in VARIANTS:
            scene, ref = _portability_scene(args, variant)
            _apply_blinn_phong(scene, *best[1])
            tuned[variant] = metrics.errors(ref, reference.render_to_array(scene, Path(tmp) / "bp.exr")).flip
    print(f"  Blinn-Phong tuned on studio {best[1]}: " + ", ".join(f"{v} {f:.3f}" for v, f in tuned.items()),
          file=sys.stderr)
    return {"params": best[1], "grid": len(grid), "flip": tuned}


def _rel(path: Path) -> str:
    return path.relative_to(DOCS).as_posix()


def _flip(result, label):
    return result["errors"][label].flip


def _relerr(result, label):
    return result["errors"][label].mean_relative


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolution", default="400x225")
    parser.add_argument("--reference-samples", type=int, default=256)
    args = parser.parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    BP, PH, PBR = (choice.label for choice in MODEL_CHOICES)  # compare.py's labels

    print("rendering (each scene: three models and the Cycles reference)", file=sys.stderr)
    fresnel = run("fresnel", args)
    tails = run("long_tail", args)
    tails_beckmann = run("long_tail", args, tag="_beckmann", ndf="beckmann")
    hdr = run("hdr", args)
    sweep = run("roughness_sweep", args)
    sweep_ms = run("roughness_sweep", args, tag="_multiscatter", multiscatter=True)
    furnace = run("furnace", args)
    furnace_ms = run("furnace", args, tag="_multiscatter", multiscatter=True)
    grid = run("material_grid", args)
    grid_principled = run("material_grid", args, tag="_principled", principled=True)
    grid_auto = run("material_grid", args, tag="_auto", term_set="auto", error_bound=AUTO_BOUND)
    from addon.blender import engine
    from addon.plan import auto_terms

    grid_auto_sets = auto_terms.summary(engine.last_term_choices).removeprefix("Auto: ")
    lighting = {v: run("portability", args, variant=v) for v in VARIANTS}
    tuned = blinn_phong_tuned_for_studio(args)
    startup = run("startup", args)
    worlds = {v: run("world", args, variant=v) for v in WORLD_VARIANTS}
    softbox = run("softbox", args)

    def table(rows):
        return "\n".join(page.table(
            ["scene", "Blinn-Phong FLIP", "Phong FLIP", "PBR FLIP", "Blinn-Phong rel. error",
             "PBR rel. error"],
            [[name, *(f"{_flip(r, m):.3f}" for m in (BP, PH, PBR)), f"{_relerr(r, BP):.1%}",
              f"{_relerr(r, PBR):.1%}"] for name, r in rows]))

    port_bp = [_flip(r, BP) for r in lighting.values()]
    port_pbr = [_flip(r, PBR) for r in lighting.values()]
    doc = f"""# Results: what physically based shading gets right, measured

Generated by `.venv/bin/python scripts/results.py` (do not edit by hand). Every image is rendered
at {args.resolution} by Shading Lab's three models and compared with **Cycles** rendering the same
scene with **direct light only, the world lighting occluded by the objects and the lights as the
file has them** (shadows on, their sizes kept: the engine casts shadows with penumbrae and
shades sphere and area lights by their size), pixel-centre
sampling and {args.reference_samples} samples per pixel. Errors: mean HDR-FLIP (Andersson et al.
2020; 0 = indistinguishable, 1 = maximally different) and the mean relative error of luminance on
lit pixels. Panels: the three models and the reference through the same clip + sRGB display, then
each model's FLIP map. The physically based model uses its default terms (Schlick, GGX, Smith
height-correlated, Lambert) unless a section says otherwise; the presets' materials are Principled
BSDFs, so Cycles renders Blender's Principled BSDF (multiscatter GGX).

{table([("fresnel", fresnel), ("long_tail (GGX)", tails), ("long_tail (Beckmann)", tails_beckmann),
        ("hdr", hdr), ("roughness_sweep", sweep), ("roughness_sweep (+ multiscatter)", sweep_ms),
        ("furnace", furnace), ("furnace (+ multiscatter)", furnace_ms),
        ("material_grid", grid), ("material_grid (Principled set)", grid_principled),
        ("material_grid (Auto term set)", grid_auto)]
       + [(f"portability: {v}", r) for v, r in lighting.items()]
       + [("startup (Blender's default cube)", startup)]
       + [(f"world: {v}", r) for v, r in worlds.items()]
       + [("softbox (area lights, shadows)", softbox)])}

## The world as a light

![startup]({_rel(startup['png'])})

Blender's startup file as it opens: the default cube, its 1000 W point light and the grey world
(radiance 0.05). The faces the light does not reach are lit by the world alone; the physically
based model lights them as Cycles does (FLIP {_flip(startup, PBR):.3f}, relative error
{_relerr(startup, PBR):.1%}). Blinn-Phong and Phong keep the source report's constant ambient term
(*Ambient: Constant*), which is not the world's light (FLIP {_flip(startup, BP):.3f}).

The `world` preset: five library materials (gold, a smooth aluminium, red plastic, rubber, skin)
on a grey ground lit by nothing but one of Blender's bundled HDRI worlds. The metals show the world
in their reflections, the rough surfaces its irradiance, and the ground darkens around the spheres
(World Occlusion, screen-space: against Cycles, which occludes everything). Blinn-Phong and Phong
take the world's irradiance as their ambient light here (*Ambient: World*) and have no reflections.

| world | Blinn-Phong FLIP | Physically based FLIP | physically based rel. error |
|---|---:|---:|---:|
""" + "\n".join(f"| {v} | {_flip(r, BP):.3f} | {_flip(r, PBR):.3f} | {_relerr(r, PBR):.1%} |"
                for v, r in worlds.items()) + """

Below their equators the metal spheres reflect the ground, which Cycles, with direct light only,
leaves black: the specular occlusion (a cone of visible directions around the bent normal against
the reflection lobe) takes the world away there too. What is left: the screen-space occlusion
cannot see the ground hidden under each sphere, so their lower halves stay a little bright; the
sunset world's sun, split off as a light, casts its shadow from a shadow map; and the relative
error counts the few brightest pixels of each frame, which are the sky's own (Blinn-Phong and
Phong clamp them).

""" + "\n\n".join(f"![world, {v}]({_rel(r['png'])})" for v, r in worlds.items()) + f"""

## Light shapes: area lights, sphere lights and their shadows

![softbox]({_rel(softbox['png'])})

The `softbox` preset: the roughness sweep's gold and red plastic rows under a 1.6 m square softbox
and a 0.5 m square fill, shadows on. A smooth sphere reflects the softbox as a bright square, a
rough one spreads it into a wide glow, and the spheres' shadows soften with the lights' size. The
physically based model integrates the lobe over each light's polygon (linearly transformed
cosines, the project's own fit; FLIP {_flip(softbox, PBR):.3f}, relative error
{_relerr(softbox, PBR):.1%}); Blinn-Phong and Phong shade an area light by its irradiance and a
highlight from its centre, the same at every size of light (FLIP {_flip(softbox, BP):.3f}). What is
left of the physically based error is mostly the rough gold's colour (the default terms have no
multiple scattering) and the shadows' edges.

Measured one light at a time against Cycles (`tests/test_light_shapes.py`, shadows off, mean
|error| / mean over a white GGX metal sphere): area lights (square, rectangle, disk, ellipse) at
roughness 0.1 / 0.3 / 0.6 / 1: 0.6-1.0 % / 1.0-1.7 % / 1.2-1.5 % / 1.0-1.4 % (shaded as a point:
117-129 % / 45-59 % / 6-8 % / 5-6 %); sphere lights of 0.1 / 0.5 m at roughness 0.05: 0.6 % /
1.0-1.4 %, 0.2: 0.2 % / 1.0 %, 0.5: 0.3 % / 1.4 % (as a point: 93 % / 98 %, 11 % / 98 %, 0.3 % /
7 %); an area light's Spread of 20-60 degrees over a Lambert plane 1.7-2.4 %, on the sphere 4-5 %.
Shadows (`tests/test_shadows.py`): hard shadows' lit/shadowed state differs from Cycles' on
0-0.03 % of the pixels away from their edges; penumbrae within -13 ... +12 % of Cycles' width.
Frame time per light shape: `docs/bench/light_shapes.md`; per shadowed light kind and map size:
`docs/bench/shadows.md`.

## Fresnel effect

![fresnel]({_rel(fresnel['png'])})

A dark glossy floor seen towards the horizon under a low sun. Reflectance rises from F0 = 4 %
at normal incidence towards 100 % at grazing angles (Schlick's eq. 1.11), so the reference shows
a bright band of reflected sunlight that strengthens towards the horizon. The physically based
model reproduces it (FLIP {_flip(fresnel, PBR):.3f}); Blinn-Phong and Phong, with no Fresnel term,
keep the same highlight strength at every angle and miss it (FLIP {_flip(fresnel, BP):.3f} and
{_flip(fresnel, PH):.3f}). The test suite measures the same effect pixel by pixel: on a plane seen
at 0°–85° the physically based model's reflectance follows Schlick from 0.04 to 0.65 while
Blinn-Phong's highlight stays constant.

## Long-tailed highlights

![long tails]({_rel(tails['png'])})

Five dark glossy spheres, roughness 0.1 → 0.5, under one small light. GGX's highlight has a long
tail (its D falls as a power of the angle, Beckmann's exponentially): FLIP {_flip(tails, PBR):.3f} with
GGX against {_flip(tails_beckmann, PBR):.3f} with Beckmann (the reference is GGX, as Blender's
Principled BSDF). Blinn-Phong's lobe ((n·h)^s at the matched shininess) ends abruptly and carries no
energy scaling with roughness: FLIP {_flip(tails, BP):.3f}, relative error {_relerr(tails, BP):.0%}.

![long tails with Beckmann]({_rel(tails_beckmann['png'])})

## High dynamic range

![hdr]({_rel(hdr['png'])})

A 2000 W and a 2 W light in one scene. The physically based model keeps radiance far above 1 and
the weak light's contribution intact (FLIP {_flip(hdr, PBR):.3f}, relative error {_relerr(hdr, PBR):.1%});
Blinn-Phong and Phong clamp every pixel to [0, 1] in their LDR pipeline (the seed's renderer did
the same), so the strong light's pool is a flat white disc and the radiance is wrong by
{_relerr(hdr, BP):.0%} on average (FLIP {_flip(hdr, BP):.3f}).

## Energy conservation: the roughness sweep

![roughness sweep]({_rel(sweep['png'])})

Gold (back) and red plastic (front), roughness 0 → 1. As roughness grows a physically based
highlight widens and dims while the energy it reflects stays bounded; single-scatter microfacet
models lose energy at high roughness (the white-furnace albedo of a rough white metal drops to 0.31
at r = 1, `docs/figures/albedo.png`), which multiple-scattering compensation restores: FLIP
{_flip(sweep, PBR):.3f} without it, {_flip(sweep_ms, PBR):.3f} with it (relative error
{_relerr(sweep, PBR):.1%} → {_relerr(sweep_ms, PBR):.1%}). Blinn-Phong's unnormalised lobe simply fades
as shininess falls (FLIP {_flip(sweep, BP):.3f}).

![roughness sweep with multiscatter]({_rel(sweep_ms['png'])})

The furnace makes the loss visible on its own: white spheres (metal behind, dielectric in front),
roughness 0 → 1, under 42 suns from every direction that stand in for a uniform environment of
radiance 1, so each sphere's radiance is its albedo. Without compensation the rough white metals
darken (FLIP {_flip(furnace, PBR):.3f} against Cycles' Principled BSDF, which compensates); with it
they stay at 1 (FLIP {_flip(furnace_ms, PBR):.3f}). Blinn-Phong obeys no bound:
FLIP {_flip(furnace, BP):.3f}. (The smooth spheres show the suns as separate glints.)

![furnace]({_rel(furnace['png'])})

![furnace with multiscatter]({_rel(furnace_ms['png'])})

## Measured materials

![material grid]({_rel(grid['png'])})

Every material preset (measured F0 of gold, copper, aluminium, silver, iron, titanium; plastic,
rubber, glass, water, skin) on a sphere. With the default terms the physically based model reaches
FLIP {_flip(grid, PBR):.3f}; the Principled term set, which reproduces Blender's Principled BSDF
(exact Fresnel, per-lobe multiple scattering, the diffuse base under the specular layer's albedo),
{_flip(grid_principled, PBR):.3f}. Blinn-Phong: {_flip(grid, BP):.3f}.

![material grid, Principled set]({_rel(grid_principled['png'])})

The Auto term set (error bound {AUTO_BOUND:g}, twice the default: Delta E_ITP at the 99th percentile
of each material's pixels against the Principled set) chose per material: {grid_auto_sets}; FLIP
{_flip(grid_auto, PBR):.3f} (at the default bound 0.5 it keeps the Principled set's FLIP on every
benchmark preset). Where it lands in time and error among every term set and the peers:
the Pareto plot of `docs/bench/bench.md` (Auto at three bounds).

![Pareto plot](bench/pareto.png)

![material grid, Auto term set]({_rel(grid_auto['png'])})

## Material portability

The same five materials (gold, aluminium, red plastic, rubber, skin) under four lighting setups.
One set of physically based parameters stays right under every light: FLIP
{min(port_pbr):.3f}–{max(port_pbr):.3f}. Blinn-Phong's parameters (derived from the same materials) are
off by FLIP {min(port_bp):.3f}–{max(port_bp):.3f}, and by how much depends on the lighting — the
coupling of material and lighting the source report describes.

Tuned by hand, Blinn-Phong can do better under one light: a grid search over {tuned['grid']}
settings (specular colour × 1/16–2, shininess × 1/2–16, ambient 0–0.2) against the studio
reference picks specular × {tuned['params'][0]:g}, shininess × {tuned['params'][1]:g}, ambient
{tuned['params'][2]:g}. Kept for the other lightings, those parameters give:

| lighting | Blinn-Phong, derived | Blinn-Phong, tuned on studio | physically based |
|---|---:|---:|---:|
""" + "\n".join(f"| {v} | {_flip(r, BP):.3f} | {tuned['flip'][v]:.3f} | {_flip(r, PBR):.3f} |"
                for v, r in lighting.items()) + """

The physically based parameters needed no tuning at all.

""" + "\n\n".join(f"![portability, {v}]({_rel(r['png'])})" for v, r in lighting.items()) + "\n"
    (DOCS / "results.md").write_text(doc, encoding="utf-8")
    for bulky in [*OUT.glob("*_compare.exr"), *OUT.glob("*_metrics.md")]:  # the doc holds the numbers;
        bulky.unlink()  # the EXRs (~2 MB each) are for compare.py users, not the repository
    print(f"wrote {DOCS / 'results.md'} and {len(list(OUT.glob('*.png')))} images in {OUT}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
