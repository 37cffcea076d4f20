"""Shading Lab's Principled set against EEVEE at 1 sample on every preset: wall time and error
against Cycles (the speed target's comparison alone).

Per preset, at ``--resolution``: Shading Lab's Principled set and its default terms, and EEVEE at
1 sample (lights as the file has them, shadows included, light threshold 1e-6: ``harness.engines``),
rendered round-robin in one process (a warm-up round, then ``--frames`` timed rounds, the order
rotated each round; a timed render that follows the other engine's is preceded by an untimed one
of its own: each engine in its steady state); wall time of ``bpy.ops.render.render()``, medians.
Errors against Cycles (cached; direct light, world on, lights as the file has them): mean
HDR-FLIP and mean relative luminance error on lit pixels. *Met*: EEVEE takes at least ``TARGET``x
our Principled set's time and its FLIP is higher. ``models`` measures the same peers beside every
configuration (48 min); this is the ten-minute version.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from .harness import engines, page, scenes, standard, timing
from .models import Config, apply

PAGE = "peers.md"
QUICK = dict(presets="long_tail", frames=1, resolution="160x90", reference_samples=16)
TARGET = 20.0  # EEVEE at 1 sample over our Principled set's time
#: Ours as ``models`` configures them, then EEVEE at 1 sample as ``models`` sets up its peers.
CONFIGS = (Config("principled", "Principled set", "PBR", principled=True),
           Config("pbr", "PBR default", "PBR"), "eevee-1")


def options(parser) -> None:
    standard(parser, resolution="640x360", frames=3, presets="all", reference_samples=128)


def key_of(config) -> str:
    return config.key if isinstance(config, Config) else config


def measure(name: str, args, progress, tmp: Path) -> dict:
    import metrics

    scene = scenes.preset(name, args.resolution)
    images = {}

    def run(config):
        ours, key = isinstance(config, Config), key_of(config)
        if ours:
            apply(scene, config)
        if key not in images:  # the warm-up round's render gives the image
            images[key] = engines.image(scene, tmp / f"{name}_{key}.exr", None if ours else key)[0]
            return {"wall_ms": 0.0}
        return timing.render_timed(scene) if ours else engines.timed(scene, key)

    times = timing.round_robin(list(CONFIGS), args.frames, run, progress, name,
                               state_of=lambda config: isinstance(config, Config))
    ref, cached = engines.cycles(scene, args.reference_samples)
    progress.step(f"{name} Cycles reference{' (cached)' if cached else ''}")
    return {"name": name, "lights": len(scenes.lights(scene)),
            "times": {key_of(c): t["wall_ms"] for c, t in zip(CONFIGS, times)},
            "errors": {key: metrics.errors(ref, image) for key, image in images.items()}}


def run(ctx) -> None:
    args = ctx.args
    with tempfile.TemporaryDirectory() as tmp:
        rows = [measure(name, args, ctx.progress, Path(tmp)) for name in args.presets]
    table, met = [], 0
    for row in rows:
        t, e = row["times"], row["errors"]
        ratio = t["eevee-1"] / t["principled"]
        ok = ratio >= TARGET and e["principled"].flip < e["eevee-1"].flip
        met += ok
        table.append([row["name"], row["lights"], *(f"{t[k]:.0f}" for k in ("principled", "pbr", "eevee-1")),
                      f"{ratio:.1f}x", *(f"{e[k].flip:.3f} / {100 * e[k].mean_relative:.1f}%"
                                         for k in ("principled", "eevee-1")), "yes" if ok else "no"])
    ctx.page("Shading Lab against EEVEE at 1 sample", [
        f"{page.res(args.resolution)}, wall ms of a whole render (medians of {args.frames} rounds after a "
        "warm-up, round-robin, order rotated; a render after the other engine's follows an untimed one of "
        f"its own), errors against Cycles at {args.reference_samples} spp. *Met*: EEVEE 1 spp takes >= "
        f"{TARGET:.0f}x our Principled set's time and has the higher FLIP. Each timed render renders a "
        "still scene again: its meshes come from the geometry memo (`blender.geometry.GEOMETRY_MEMO`) "
        "as at any "
        "re-render or a frame where they do not deform; nothing else is kept between renders "
        "(Persistent Data off: the shadow maps are drawn each time).", "",
        *page.table(["preset", "lights", "Principled ms", "default PBR ms", "EEVEE 1 spp ms",
                     "EEVEE / Principled", "Principled FLIP / rel", "EEVEE FLIP / rel", "met"], table,
                    "lrrrrrrrc"), "",
        f"Met on {met} of {len(rows)} presets."])
