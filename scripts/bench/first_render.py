"""The first render of each term set on each benchmark preset, against the second (a benchmark,
not a test): what an artist waits for the first time a term set is used in a session.

    .venv/bin/python scripts/first_render_bench.py [--presets a,b] [--resolution 1280x720]
        [--table docs/bench/first_render.md] [--repeat 3]

Each (preset, term set) runs in a fresh Python process, so that nothing is cached in memory:
compiled programs, lookup tables (shipped in addon/reference/tables.npz, loaded and uploaded at first use),
world precomputation. The process loads the preset, renders it twice with the term set (wall time
of ``bpy.ops.render.render``) and prints both; the difference is what the first render costs
extra. Measured three times: cold, with Mesa's on-disk shader cache disabled
(MESA_SHADER_CACHE_DISABLE) and the add-on's world cache off (SHADING_LAB_CACHE=off), so that every
process compiles its programs and computes its world, as on a first start; warm, with Mesa's cache
on, in a folder of its own that an earlier process filled, as an artist's later sessions find it;
and warm with the world's maps cached too (``addon/plan/world_cache.py``, in a folder the same earlier
process filled), as a later session that renders a world seen before finds it. Each is measured
in ``--repeat`` fresh processes (the three kinds interleaved, as this machine's load drifts) and
the table holds the medians. Times are CPU-rasteriser times (Mesa llvmpipe): compare them within
one run.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

TERM_SETS = {"default": "CUSTOM", "principled": "PRINCIPLED", "multiscatter": "MULTISCATTER"}


def child(preset: str, term_set: str, width: int, height: int) -> None:
    """Render ``preset`` twice with ``term_set``; print one JSON line of wall times (ms)."""
    import bpy
    import render as cli

    cli.ensure_addon()
    scene, _ = cli.load_scene(preset, None)
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.engine = "SHADING_LAB"
    props = scene.shading_lab
    props.model = "PBR"
    props.term_set = "PRINCIPLED" if term_set == "PRINCIPLED" else "CUSTOM"
    props.multiscatter = term_set == "MULTISCATTER"
    times = []
    for _ in range(2):
        start = time.perf_counter()
        bpy.ops.render.render()
        times.append(1e3 * (time.perf_counter() - start))
    print("RESULT " + json.dumps({"first_ms": times[0], "second_ms": times[1]}), flush=True)


def measure(preset: str, term_set: str, size: tuple[int, int], cache: Path | None = None,
            world_cache: Path | None = None) -> dict:
    """Both renders in a fresh process: with Mesa's shader cache off, or (``cache``) with it in
    that folder; with the world cache off, or (``world_cache``) in that folder."""
    env = dict(os.environ)
    if cache is None:
        env["MESA_SHADER_CACHE_DISABLE"] = "true"
    else:
        env.pop("MESA_SHADER_CACHE_DISABLE", None)
        env["MESA_SHADER_CACHE_DIR"] = str(cache)
    env["SHADING_LAB_CACHE"] = "off" if world_cache is None else str(world_cache)
    out = subprocess.run([sys.executable, __file__, "--child", preset, term_set, str(size[0]), str(size[1])],
                         capture_output=True, text=True, env=env, timeout=900, check=False)
    for line in out.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[len("RESULT "):])
    raise RuntimeError(f"{preset} / {term_set}: no result\n{out.stdout[-2000:]}\n{out.stderr[-2000:]}")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "--child":
        child(argv[1], argv[2], int(argv[3]), int(argv[4]))
        return 0
    from addon.scene import presets

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--presets", default=None, help="comma-separated preset names (default: all shipped)")
    parser.add_argument("--resolution", default="1280x720", metavar="WxH")
    parser.add_argument("--table", type=Path, default=ROOT / "docs" / "bench" / "first_render.md")
    parser.add_argument("--repeat", type=int, default=3,
                        help="fresh processes per measurement; the table holds their medians (default 3)")
    args = parser.parse_args(argv)
    size = tuple(int(x) for x in args.resolution.lower().split("x"))
    names = args.presets.split(",") if args.presets else presets.scene_preset_names()
    rows = []
    with tempfile.TemporaryDirectory(prefix="sl_shader_cache_") as folder, \
            tempfile.TemporaryDirectory(prefix="sl_world_cache_") as worlds:
        for name in names:
            for label, term_set in TERM_SETS.items():
                measure(name, term_set, size, Path(folder), Path(worlds))  # fills both caches
                runs = {"cold": [], "warm": [], "seen": []}
                for _ in range(max(args.repeat, 1)):  # interleaved: the machine's load drifts
                    runs["cold"].append(measure(name, term_set, size))
                    runs["warm"].append(measure(name, term_set, size, Path(folder)))
                    runs["seen"].append(measure(name, term_set, size, Path(folder), Path(worlds)))
                extras = [statistics.median(r["first_ms"] - r["second_ms"] for r in runs[k])
                          for k in ("cold", "warm", "seen")]
                first, second = (statistics.median(r[k] for r in runs["cold"])
                                 for k in ("first_ms", "second_ms"))
                rows.append((name, label, first, second, *extras))
                spread = ", ".join(f"{r['first_ms'] - r['second_ms']:+.0f}" for r in runs["warm"])
                print(f"{name:16s} {label:12s} first {first:8.1f} ms  second {second:8.1f} ms  first "
                      f"costs +{extras[0]:.1f} ms; shader cache warm: +{extras[1]:.1f} ms ({spread}); and "
                      f"the world cached: +{extras[2]:.1f} ms", flush=True)
    lines = [f"The first render of each term set in a fresh process against the second, "
             f"{size[0]}x{size[1]}, physically based model (`scripts/first_render_bench.py`; wall "
             f"time of the render operator; medians of {max(args.repeat, 1)} fresh processes each, "
             f"the three kinds interleaved). *Cold*: Mesa's shader cache and the world cache off, so "
             f"programs compile and the world's maps are computed as on a first start; *warm*: the "
             f"shader cache filled by an earlier process, as from an artist's second session on (Mesa "
             f"keeps it on disk by default), the world's maps computed: what is left is the add-on's "
             f"own set-up (tables, the world's precomputation, scene upload); *world seen*: the "
             f"world's maps also kept by that earlier process (`addon/plan/world_cache.py`, on by "
             f"default), as a later session that renders a world seen before finds them.", "",
             "| preset | term set | first ms | second ms | first costs (cold) | first costs (warm) "
             "| first costs (warm, world seen) |", "|---|---|---:|---:|---:|---:|---:|"]
    lines += [f"| {n} | {t} | {a:.0f} | {b:.0f} | +{c:.0f} ms | +{d:.0f} ms | +{e:.0f} ms |"
              for n, t, a, b, c, d, e in rows]
    worst = [max(rows, key=lambda r, k=k: r[k]) for k in (4, 5, 6)]
    lines += ["", "Largest extra cost of a first render: " + ", ".join(
        f"**+{w[k]:.0f} ms** {what} ({w[0]}, {w[1]})"
        for w, k, what in zip(worst, (4, 5, 6), ("cold", "warm", "warm with the world seen")))]
    args.table.parent.mkdir(parents=True, exist_ok=True)
    args.table.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.table}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
