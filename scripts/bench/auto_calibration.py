"""The Auto term set's safety margin: its predicted error against the error measured in renders,
on random scenes kept apart from the tests' (a calibration: errors, no times).

Each seed's random scene (``tests/auto_scenes.py``: four spheres on a ground, each with a random
material, 1-8 lights of every kind casting shadows, a frontal or grazing view, 96 px) is rendered
with the Principled set once and with Auto at each bound, under each world:

- ``uniform``: the scene's own world, black or a uniform colour (half the seeds each);
- ``split-sum``: one of Blender's bundled image worlds, turned and scaled at random, World
  Specular: Split Sum (every candidate and the reference on the split sum);
- ``sampled``: the same worlds sampled 16 times a pixel (each candidate also on the split sum,
  the reference sampled).

Per material the measured error is Delta E_ITP at the Auto quantile (99th percentile) of the
pixels it covers, Auto's render against the Principled one; beside it Auto's prediction (before
the margin). The table gives per world and bound the share of materials within the bound and the
sets chosen, then over every material where either error is at least ``--floor`` the ratio
measured / predicted: its percentiles, the share within a factor 2, and the worst cases. The
margin (``auto_terms.MARGIN``, the factor a prediction is multiplied by before it is held to the
bound) should cover the ratio's upper percentiles. Programs are never merged (every material is
predicted; at 96 px no cheaper program would repay its first use).
"""

from __future__ import annotations

import csv
import tempfile
from pathlib import Path

import numpy as np

from .harness import choices, page

PAGE = "auto_calibration.md"
QUICK = dict(seeds="1000", bounds="4", worlds="uniform")
WORLDS = ("uniform", "split-sum", "sampled")
#: Of measured / predicted: the low ones show over-prediction (a cheaper set refused), the high
#: ones what the margin must cover.
PERCENTILES = (5, 25, 50, 75, 90, 95, 100)
SPECULAR = {"split-sum": "SPLIT_SUM", "sampled": "SAMPLED"}
#: World samples a pixel under ``sampled`` (as tests/test_auto_world.py).
WORLD_SAMPLES = 16


def seed_range(text: str) -> range:
    first, _, last = text.partition("-")
    return range(int(first), int(last or first) + 1)


def options(parser) -> None:
    parser.add_argument("--seeds", type=seed_range, default="1000-1029", help="first-last (inclusive)")
    parser.add_argument("--bounds", default="0.5,4", help="error bounds, comma-separated")
    parser.add_argument("--worlds", type=choices(WORLDS), default=",".join(WORLDS),
                        help=f"of {', '.join(WORLDS)}")
    parser.add_argument("--floor", type=float, default=0.1,
                        help="ratios only where the measured or predicted error is at least this")
    parser.add_argument("--rows", type=Path, help="also write every material's row here (CSV)")


def ratio_stats(rows, floor: float) -> dict:
    """Measured / predicted over the rows (not on the Principled set) where either is >= floor."""
    pairs = [(c.predicted, m, seed, name, c.name) for seed, name, c, m in rows
             if c.name != "PRINCIPLED" and max(c.predicted, m) >= floor]
    if not pairs:
        return {"count": 0}
    ratios = np.array([m / max(p, 1e-6) for p, m, *_ in pairs])
    worst = sorted(zip(ratios, pairs), key=lambda x: -x[0])[:3]
    return {"count": len(pairs),
            "percentiles": np.percentile(ratios, PERCENTILES),
            "within_2x": float(np.mean((ratios >= 0.5) & (ratios <= 2.0))),
            "worst": [(float(r), p) for r, p in worst]}


def measure(args, progress) -> dict:
    """{(world, bound): [(seed, material, Choice, measured)]} over every seed."""
    import auto_scenes

    from addon.plan import auto_terms

    auto_terms.PAYBACK_FRAMES = 1e12  # every material predicted (see the docstring)
    bounds = [float(b) for b in args.bounds.split(",")]
    rows = {(world, bound): [] for world in args.worlds for bound in bounds}
    progress.expect(len(args.worlds) * len(args.seeds))
    with tempfile.TemporaryDirectory() as folder:
        for world in args.worlds:
            for seed in args.seeds:
                if world == "uniform":
                    scene, camera, names = auto_scenes.random_scene(seed)
                else:
                    scene, camera, names = auto_scenes.world_scene(seed, SPECULAR[world], WORLD_SAMPLES)
                found = auto_scenes.render_pairs(scene, camera, names, seed, bounds, Path(folder))
                for bound, materials in found.items():
                    rows[world, bound] += materials
                progress.step(f"{world}: scene {seed}")
    return rows


def run(ctx) -> None:
    import auto_scenes
    from render import CliError

    from addon.plan import auto_terms

    args = ctx.args
    if args.rows is not None:  # before minutes of rendering, not after
        try:
            with args.rows.open("a"):  # an existing file is kept as it is until the end
                pass
        except OSError as error:
            raise CliError(f"cannot write {args.rows}: {error}") from None
    rows = measure(args, ctx.progress)
    lines = [
        f"Random scenes of `tests/auto_scenes.py` ({auto_scenes.SIZE} px, shadows on), seeds "
        f"{args.seeds.start}-{args.seeds.stop - 1} apart from the tests' (test_auto_terms 0-49, "
        "test_auto_world 2000-2011). Measured: Delta E_ITP at the 99th percentile of each material's "
        "pixels, Auto's render against the Principled set's; predicted: Auto's own figure before the "
        f"margin (MARGIN = {auto_terms.MARGIN}).", ""]
    table = []
    for (world, bound), found in rows.items():
        within, chosen, _over = auto_scenes.tally(found, bound)
        sets = ", ".join(f"{n} {auto_terms.label(name)}"
                         for name, n in sorted(chosen.items(), key=lambda x: -x[1]))
        table.append([world, f"{bound:g}", len(found), f"{within:.1%}", sets])
    lines += [*page.table(["world", "bound", "materials", "within the bound", "sets chosen"], table, "lllll"),
              "", f"Measured / predicted where either is >= {args.floor:g} (both bounds together; the "
              "Principled set, predicted 0 by construction, left out):", ""]
    table = []
    for world in args.worlds:
        stats = ratio_stats([row for (w, _b), found in rows.items() if w == world for row in found],
                            args.floor)
        if not stats["count"]:
            table.append([world, 0, *[""] * (len(PERCENTILES) + 2)])
            continue
        worst = "; ".join(f"{seed} {name} {auto_terms.label(chosen)} {p:.2f} / {m:.2f}"
                          for _r, (p, m, seed, name, chosen) in stats["worst"])
        table.append([world, stats["count"], f"{stats['within_2x']:.0%}",
                      *(f"{x:.2f}" for x in stats["percentiles"]), worst])
    lines += page.table(["world", "pairs", "within 2x", *(f"{q}th" for q in PERCENTILES[:-1]), "max",
                         "worst (seed, material, set, predicted, measured)"], table,
                        "l" * (len(PERCENTILES) + 4))
    if args.rows:
        with args.rows.open("w", newline="") as f:
            out = csv.writer(f)
            out.writerow(["world", "bound", "seed", "material", "set", "predicted", "measured"])
            out.writerows([world, bound, seed, name, c.name, f"{c.predicted:.4f}", f"{m:.4f}"]
                          for (world, bound), found in rows.items() for seed, name, c, m in found)
    ctx.page("Auto's margin: predicted against measured error", lines, timing=False)
