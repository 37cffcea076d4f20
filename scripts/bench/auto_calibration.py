"""The Auto term set's safety margin: its predicted error against the error measured in renders,
on random scenes kept apart from the tests' (a calibration, not a test).

    .venv/bin/python scripts/auto_calibrate.py [--seeds 1000-1029] [--bounds 0.5,4]
        [--worlds uniform,split-sum,sampled] [--table docs/bench/auto_calibration.md]

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

import argparse
import csv
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts"), str(ROOT / "tests")]

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


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="1000-1029", help="first-last (inclusive)")
    parser.add_argument("--bounds", default="0.5,4", help="error bounds, comma-separated")
    parser.add_argument("--worlds", default=",".join(WORLDS), help=f"of {', '.join(WORLDS)}")
    parser.add_argument("--floor", type=float, default=0.1,
                        help="ratios only where the measured or predicted error is at least this")
    parser.add_argument("--table", type=Path, default=ROOT / "docs" / "bench" / "auto_calibration.md")
    parser.add_argument("--rows", type=Path, help="also write every material's row here (CSV)")
    args = parser.parse_args()
    seeds = seed_range(args.seeds)
    bounds = [float(b) for b in args.bounds.split(",")]
    worlds = args.worlds.split(",")
    unknown = sorted(set(worlds) - set(WORLDS))
    if unknown:
        print(f"auto_calibrate: unknown world(s) {', '.join(unknown)}; choose from {', '.join(WORLDS)}",
              file=sys.stderr)
        return 2
    for path in (args.table, args.rows):  # before minutes of rendering, not after
        if path is None:
            continue
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            with path.open("a"):  # an existing file is kept as it is until the end
                pass
        except OSError as error:
            print(f"auto_calibrate: cannot write {path}: {error}", file=sys.stderr)
            return 2

    import auto_scenes
    import render as cli

    cli.ensure_addon()
    import bench

    from addon.plan import auto_terms

    auto_terms.PAYBACK_FRAMES = 1e12  # every material predicted (see the docstring)
    rows = {(world, bound): [] for world in worlds for bound in bounds}
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        for world in worlds:
            for i, seed in enumerate(seeds):
                if world == "uniform":
                    scene, camera, names = auto_scenes.random_scene(seed)
                else:
                    scene, camera, names = auto_scenes.world_scene(seed, SPECULAR[world], WORLD_SAMPLES)
                found = auto_scenes.render_pairs(scene, camera, names, seed, bounds, Path(folder))
                for bound, materials in found.items():
                    rows[world, bound] += materials
                print(f"\r{world}: scene {i + 1}/{len(seeds)} ({time.perf_counter() - started:.0f} s)",
                      end="", file=sys.stderr, flush=True)
            print(file=sys.stderr)

    lines = [
        "# Auto's margin: predicted against measured error",
        "",
        f"`scripts/auto_calibrate.py --seeds {args.seeds} --bounds {args.bounds} --worlds {args.worlds}` "
        f"({bench.git_state()}, {time.strftime('%Y-%m-%d %H:%M')}; {time.perf_counter() - started:.0f} s). "
        f"Random scenes of `tests/auto_scenes.py` ({auto_scenes.SIZE} px, shadows on), seeds apart "
        "from the tests' (test_auto_terms 0-49, test_auto_world 2000-2011). Measured: Delta E_ITP at "
        "the 99th percentile of each material's pixels, Auto's render against the Principled set's; "
        f"predicted: Auto's own figure before the margin (MARGIN = {auto_terms.MARGIN}).",
        "",
        "| world | bound | materials | within the bound | sets chosen |",
        "|---|---|---|---|---|",
    ]
    for (world, bound), found in rows.items():
        within, chosen, _over = auto_scenes.tally(found, bound)
        sets = ", ".join(f"{n} {auto_terms.label(name)}"
                         for name, n in sorted(chosen.items(), key=lambda x: -x[1]))
        lines.append(f"| {world} | {bound:g} | {len(found)} | {within:.1%} | {sets} |")
    lines += ["", f"Measured / predicted where either is >= {args.floor:g} (both bounds together; the "
              "Principled set, predicted 0 by construction, left out):", "",
              "| world | pairs | within 2x | " + " | ".join(f"{q}th" for q in PERCENTILES[:-1])
              + " | max | worst (seed, material, set, predicted, measured) |",
              "|---" * (len(PERCENTILES) + 4) + "|"]
    for world in worlds:
        stats = ratio_stats([row for bound in bounds for row in rows[world, bound]], args.floor)
        if not stats["count"]:
            lines.append(f"| {world} | 0 |" + " |" * (len(PERCENTILES) + 2))
            continue
        worst = "; ".join(f"{seed} {name} {auto_terms.label(chosen)} {p:.2f} / {m:.2f}"
                          for _r, (p, m, seed, name, chosen) in stats["worst"])
        cells = " | ".join(f"{x:.2f}" for x in stats["percentiles"])
        lines.append(f"| {world} | {stats['count']} | {stats['within_2x']:.0%} | {cells} | {worst} |")
    if args.rows:
        with args.rows.open("w", newline="") as f:
            out = csv.writer(f)
            out.writerow(["world", "bound", "seed", "material", "set", "predicted", "measured"])
            out.writerows([world, bound, seed, name, c.name, f"{c.predicted:.4f}", f"{m:.4f}"]
                          for (world, bound), found in rows.items() for seed, name, c, m in found)
    text = "\n".join(lines) + "\n"
    print(text)
    args.table.write_text(text)
    print(f"wrote {args.table}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
