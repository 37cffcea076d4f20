"""Benchmark: shadows -- the cost of each shadowed light kind, map size against error, soft against
hard, and EEVEE (shadows on) beside us, all against Cycles (a benchmark, not a test).

    .venv/bin/python scripts/shadow_bench.py [--resolution 640x360] [--samples 256] [--frames 5]
                                             [--out docs/bench]

Scene: the shadow tests' sphere and torus over a white Lambert ground (tests/test_shadows.py),
one light casting: point, spot or sun, hard (radius 0) or soft (point 0.3 m, spot 0.3 m, sun 4
degrees). Error: the image's mean absolute luminance error over Cycles' mean (direct light only,
shadows on, ``--samples`` spp); *state* the fraction of pixels whose lit/shadowed state (radiance
with shadows over without > 0.5) differs from Cycles', a one-pixel band around Cycles' shadow
edges left out. Times: the engine's own (``engine.last_timings``: extraction, shadow maps, draw,
read-back), medians of ``--frames`` after a warm-up render; EEVEE's are whole-render wall times.

Writes ``OUT/shadows.md`` (also printed). Frame times are CPU-rasteriser times (Mesa llvmpipe):
compare ratios within one run.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts"), str(ROOT / "tests")]

import render as cli  # noqa: E402

CASES = (("POINT", 0.0), ("POINT", 0.3), ("SPOT", 0.0), ("SPOT", 0.3), ("SUN", 0.0), ("SUN", 4.0))
MAP_SIZES = ("512", "1024", "2048", "4096")


def _luminance(image):
    return image[..., :3].mean(-1)


def _error(ours, ref) -> float:
    import numpy as np

    return float(np.abs(_luminance(ours) - _luminance(ref)).mean() / _luminance(ref).mean())


def _state_error(ours_on, ours_off, ref_on, ref_off) -> float:
    import numpy as np
    from test_shadows import _edge_band

    def visible(on, off):
        lum_on, lum_off = _luminance(on), _luminance(off)
        return np.where(lum_off > 1e-3 * lum_off.max(), lum_on / np.maximum(lum_off, 1e-30), 1.0) > 0.5

    state_ours, state_ref = visible(ours_on, ours_off), visible(ref_on, ref_off)
    seen = _luminance(ref_off) > 0.02 * _luminance(ref_off).max()
    considered = seen & ~_edge_band(state_ref)
    return float((state_ours != state_ref)[considered].mean())


def _ours(scene, path: Path, frames: int) -> tuple:
    """(image, median engine ms) of ``frames`` renders after a warm-up."""
    import reference

    from addon.blender import engine

    image = reference.render_to_array(scene, path)
    times = []
    for _ in range(frames):
        engine.last_timings.clear()
        image = reference.render_to_array(scene, path)
        times.append(engine.last_timings["total_ms"])
    return image, statistics.median(times)


def _cycles(scene, path: Path, samples: int):
    from test_cycles import _cycles as cycles

    engine = scene.render.engine
    try:
        return cycles(scene, path, samples=samples)
    finally:
        scene.render.engine = engine


def _eevee(scene, path: Path, samples: int, frames: int) -> tuple:
    import reference

    engine = scene.render.engine
    scene.render.engine = reference.EEVEE
    scene.eevee.taa_render_samples = samples
    scene.eevee.light_threshold = 1e-6
    try:
        image = reference.render_to_array(scene, path)
        times = []
        for _ in range(frames):
            start = time.perf_counter()
            image = reference.render_to_array(scene, path)
            times.append((time.perf_counter() - start) * 1000.0)
        return image, statistics.median(times)
    finally:
        scene.render.engine = engine


def run(args, tmp: Path, progress) -> list[dict]:
    import bpy
    from test_shadows import _scene

    width, height = args.width, args.height
    rows = []
    for kind, size in CASES:
        scene, light = _scene(kind, size, resolution=width)
        scene.render.resolution_y = height
        tag = f"{kind}_{size}"
        light.data.use_shadow = False
        ref_off = _cycles(scene, tmp / f"{tag}_cycles_off.exr", args.samples)
        off, ms_off = _ours(scene, tmp / f"{tag}_off.exr", args.frames)
        light.data.use_shadow = True
        ref = _cycles(scene, tmp / f"{tag}_cycles.exr", args.samples)
        row = dict(kind=kind, size=size, ms_off=ms_off, sizes={})
        for map_size in MAP_SIZES:
            scene.shading_lab.shadow_map_size = map_size
            on, ms = _ours(scene, tmp / f"{tag}_{map_size}.exr", args.frames)
            row["sizes"][map_size] = dict(ms=ms, error=_error(on, ref),
                                          state=_state_error(on, off, ref, ref_off))
            progress(f"{tag} map {map_size}: {ms:.1f} ms")
        scene.shading_lab.shadow_map_size = "1024"
        row["error_unshadowed"] = _error(off, ref)
        for samples in (1, 16):
            image, ms = _eevee(scene, tmp / f"{tag}_eevee{samples}.exr", samples, args.frames)
            row[f"eevee{samples}"] = dict(ms=ms, error=_error(image, ref))
            progress(f"{tag} EEVEE {samples} spp: {ms:.0f} ms")
        rows.append(row)
        bpy.ops.wm.read_factory_settings(use_empty=True)
    return rows


def report(args, rows) -> str:
    lines = ["# Shadows", "",
             f"`scripts/shadow_bench.py` — {time.strftime('%Y-%m-%d %H:%M')}, {args.width} × {args.height}, "
             f"Cycles {args.samples} spp, medians of {args.frames} frames.", "",
             "The shadow tests' sphere and torus over a white Lambert ground, one light casting (soft: "
             "point and spot radius 0.3 m, sun 4°). Error: mean |luminance − Cycles'| / Cycles' mean "
             "(direct light only, shadows on); *state*: pixels whose lit/shadowed state differs from "
             "Cycles' outside a one-pixel band around its shadow edges. Ours: the engine's own time "
             "(shadow maps drawn every frame here: a final render); EEVEE: whole-render wall time. "
             "Llvmpipe times: ratios within this run only.", "",
             "## Cost and error per light kind (map 1024)", "",
             "| light | no shadows ms | shadows ms | shadow cost ms | error without | error with | state "
             "| EEVEE 1 spp ms / error | EEVEE 16 spp ms / error |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        s = r["sizes"]["1024"]
        label = f"{r['kind'].lower()} {'hard' if r['size'] == 0 else r['size']}"
        lines.append(f"| {label} | {r['ms_off']:.1f} | {s['ms']:.1f} | {s['ms'] - r['ms_off']:.1f} "
                     f"| {r['error_unshadowed']:.2%} | {s['error']:.2%} | {s['state']:.3%} "
                     f"| {r['eevee1']['ms']:.0f} / {r['eevee1']['error']:.2%} "
                     f"| {r['eevee16']['ms']:.0f} / {r['eevee16']['error']:.2%} |")
    lines += ["", "## Map size against error", "",
              "| light | " + " | ".join(f"{m} ms / error / state" for m in MAP_SIZES) + " |",
              "|---|" + "---:|" * len(MAP_SIZES)]
    for r in rows:
        label = f"{r['kind'].lower()} {'hard' if r['size'] == 0 else r['size']}"
        cells = [f"{r['sizes'][m]['ms']:.1f} / {r['sizes'][m]['error']:.2%} / {r['sizes'][m]['state']:.3%}"
                 for m in MAP_SIZES]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", default="640x360", metavar="WxH")
    parser.add_argument("--samples", type=int, default=256)
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "bench")
    args = parser.parse_args(argv)
    args.width, args.height = (int(x) for x in args.resolution.split("x"))
    cli.ensure_addon()
    with tempfile.TemporaryDirectory() as tmp:
        rows = run(args, Path(tmp), lambda text: print(text, flush=True))
    text = report(args, rows)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "shadows.md").write_text(text, encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
