"""The first render of each term set on each preset, against the second: what an artist waits for
the first time a term set is used in a session (a fresh process per case).

Each (preset, term set) runs in a fresh Python process (``process.run_case``), so that nothing is
cached in memory: compiled programs, lookup tables (shipped in addon/reference/tables.npz, loaded
and uploaded at first use), world precomputation. The process loads the preset, renders it twice
with the term set (wall time of ``bpy.ops.render.render``) and hands both back; the difference is
what the first render costs extra. Measured three times: cold, with Mesa's on-disk shader cache
disabled (MESA_SHADER_CACHE_DISABLE) and the add-on's world cache off (SHADING_LAB_CACHE=off), so
that every process compiles its programs and computes its world, as on a first start; warm, with
Mesa's cache on, in a folder of its own that an earlier process filled, as an artist's later
sessions find it; and warm with the world's maps cached too (``addon/plan/world_cache.py``, in a
folder the same earlier process filled), as a later session that renders a world seen before
finds it. Each is measured in ``--repeat`` fresh processes (the three kinds interleaved, as this
machine's load drifts) and the table holds the medians.
"""

from __future__ import annotations

import statistics
import tempfile
from pathlib import Path

from .harness import choices, page, process, standard

PAGE = "first_render.md"
QUICK = dict(resolution="160x90", presets="long_tail", term_sets="default", repeat=1)
BLENDER = False  # the cases load Blender, each in a process of its own
TERM_SETS = {"default": "CUSTOM", "principled": "PRINCIPLED", "multiscatter": "MULTISCATTER"}


def options(parser) -> None:
    standard(parser, resolution="1280x720", presets="all")
    parser.add_argument("--term-sets", type=choices(TERM_SETS), default=",".join(TERM_SETS),
                        help=f"of {', '.join(TERM_SETS)} (default: all)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="fresh processes per measurement; the table holds their medians (default 3)")


def case(preset: str, term_set: str, width: int, height: int) -> dict:
    """In the fresh process: render ``preset`` twice with ``term_set``; wall times (ms)."""
    from .harness import scenes, timing

    scene = scenes.preset(preset, (width, height))
    props = scene.shading_lab
    props.model = "PBR"
    props.term_set = "PRINCIPLED" if term_set == "PRINCIPLED" else "CUSTOM"
    props.multiscatter = term_set == "MULTISCATTER"
    first, second = (timing.render_timed(scene)["wall_ms"] for _ in range(2))
    return {"first_ms": first, "second_ms": second, "gl": page.gl_renderer()}


def measure(preset: str, term_set: str, size, cache: Path | None = None,
            world_cache: Path | None = None) -> dict:
    """Both renders in a fresh process: with Mesa's shader cache off, or (``cache``) with it in
    that folder; with the world cache off, or (``world_cache``) in that folder."""
    env = {"MESA_SHADER_CACHE_DISABLE": "true" if cache is None else None,
           "MESA_SHADER_CACHE_DIR": cache, "SHADING_LAB_CACHE": "off" if world_cache is None else world_cache}
    return process.run_case("first_render", "case", preset, term_set, *size, env=env)


def run(ctx) -> None:
    args = ctx.args
    rows, gl = [], ""
    ctx.progress.expect(len(args.presets) * len(args.term_sets) * (1 + 3 * max(args.repeat, 1)))
    with tempfile.TemporaryDirectory(prefix="sl_shader_cache_") as folder, \
            tempfile.TemporaryDirectory(prefix="sl_world_cache_") as worlds:
        for name in args.presets:
            for label in args.term_sets:
                term_set = TERM_SETS[label]
                # an earlier process fills both caches
                gl = measure(name, term_set, args.resolution, Path(folder), Path(worlds))["gl"]
                ctx.progress.step(f"{name} {label}: caches filled")
                runs = {"cold": [], "warm": [], "seen": []}
                for _ in range(max(args.repeat, 1)):  # interleaved: the machine's load drifts
                    for kind, caches in (("cold", ()), ("warm", (Path(folder),)),
                                         ("seen", (Path(folder), Path(worlds)))):
                        runs[kind].append(measure(name, term_set, args.resolution, *caches))
                        ctx.progress.step(f"{name} {label}: {kind}")
                extras = [statistics.median(r["first_ms"] - r["second_ms"] for r in runs[k])
                          for k in ("cold", "warm", "seen")]
                first, second = (statistics.median(r[k] for r in runs["cold"])
                                 for k in ("first_ms", "second_ms"))
                rows.append((name, label, first, second, *extras))
    table = [[n, t, f"{a:.0f}", f"{b:.0f}", f"+{c:.0f} ms", f"+{d:.0f} ms", f"+{e:.0f} ms"]
             for n, t, a, b, c, d, e in rows]
    worst = [max(rows, key=lambda r, k=k: r[k]) for k in (4, 5, 6)]
    ctx.page("The first render of a term set", [
        f"In a fresh process against the second, {page.res(args.resolution)}, physically based model; "
        f"wall time of the render operator; medians of {max(args.repeat, 1)} fresh processes each, the "
        "three kinds interleaved. *Cold*: Mesa's shader cache and the world cache off, so programs "
        "compile and the world's maps are computed as on a first start; *warm*: the shader cache filled "
        "by an earlier process, as from an artist's second session on (Mesa keeps it on disk by "
        "default), the world's maps computed: what is left is the add-on's own set-up (tables, the "
        "world's precomputation, scene upload); *world seen*: the world's maps also kept by that "
        "earlier process (`addon/plan/world_cache.py`, on by default), as a later session that renders "
        "a world seen before finds them.", "",
        *page.table(["preset", "term set", "first ms", "second ms", "first costs (cold)",
                     "first costs (warm)", "first costs (warm, world seen)"], table, "llrrrrr"), "",
        "Largest extra cost of a first render: " + ", ".join(
            f"**+{w[k]:.0f} ms** {what} ({w[0]}, {w[1]})"
            for w, k, what in zip(worst, (4, 5, 6), ("cold", "warm", "warm with the world seen")))],
        gl=gl)

