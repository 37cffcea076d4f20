"""Benchmark: the world as a light -- error against Cycles per roughness for each world variant,
EEVEE beside it, the precomputation cost and the frame cost (a benchmark, not a test).

    .venv/bin/python scripts/world_bench.py [--worlds forest,city] [--samples 1024] [--frames 5]
                                            [--out docs/bench]

Scenes: five spheres of roughness 0, 0.25, 0.5, 0.75, 1 in a row (200 x 40 px, orthographic),
white GGX metal (Glossy BSDF) or red Principled dielectric, under a bundled Blender world, nothing
occluded (the spheres' shadow, diffuse, glossy and transmission rays off). Errors are the mean
absolute error over each sphere divided by its mean radiance in Cycles (direct light only, world
on, ``--samples``). EEVEE renders the same scene at 1 and 16 samples with its default world
lighting (its sun threshold splits off the brightest texels too). Times are wall times of the
render (ours after a warm-up render that compiles the programs and precomputes the world).

Precomputation: the world's light built from a 1K bundled world (1024 x 512) and from the same
image resampled to 4K (4096 x 2048), medians of ``--frames`` rebuilds (the world's strength
nudged each time so that the cache does not answer). Frame cost: the demo scene at 1280 x 720
(its point light and sun) with a black world and with the forest world, medians of ``--frames``.

The world cache (``addon/plan/world_cache.py``) is off here: every build is computed, as a session's
first render of a world it has not seen computes it.

Writes ``OUT/world.md`` (also printed). Frame times are CPU-rasteriser times (Mesa llvmpipe):
compare ratios within one run.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
os.environ["SHADING_LAB_CACHE"] = "off"  # the precomputation is measured, not the cache
sys.path[:0] = [str(ROOT), str(ROOT / "scripts"), str(ROOT / "tests")]

import render as cli  # noqa: E402

ROUGHNESS = (0.0, 0.25, 0.5, 0.75, 1.0)
VARIANTS = (("split sum", dict(world_specular="SPLIT_SUM")),
            ("sampled 64", dict(world_specular="SAMPLED", world_samples=64)),
            ("sampled 256", dict(world_specular="SAMPLED", world_samples=256)),
            ("split sum, SH9 diffuse", dict(world_specular="SPLIT_SUM", world_diffuse="SH9")))


def _errors(ours, ref):
    import numpy as np
    from test_world_light import _sphere_masks

    out = []
    for mask in _sphere_masks():
        o, c = ours[..., :3][mask].mean(-1), ref[..., :3][mask].mean(-1)
        out.append(float(np.abs(o - c).mean() / c.mean()))
    return out


def _render(scene, path: Path):
    import reference

    start = time.perf_counter()
    image = reference.render_to_array(scene, path)
    return image, 1e3 * (time.perf_counter() - start)


def spheres(worlds, samples: int, tmp: Path, progress) -> list[dict]:
    """Per world and material: ours per variant, EEVEE 1 and 16 spp, each against Cycles."""
    import reference
    from test_cycles import _cycles
    from test_world_light import _hdri, _row_scene, _world

    rows = []
    for world in worlds:
        for kind in ("metal", "dielectric"):
            scene = _row_scene(kind)
            _world(scene, image=_hdri(world))
            ref = _cycles(scene, tmp / "cycles.exr", samples=samples)
            progress.step(f"{world} {kind}: Cycles")
            for label, settings in VARIANTS:
                for key, value in settings.items():
                    setattr(scene.shading_lab, key, value)
                scene.render.engine = "SHADING_LAB"
                _render(scene, tmp / "ours.exr")  # warm-up: programs and the world's light built
                image, ms = _render(scene, tmp / "ours.exr")
                rows.append(dict(world=world, kind=kind, who=f"Shading Lab, {label}", ms=ms,
                                 errors=_errors(image, ref)))
                scene.shading_lab.world_diffuse, scene.shading_lab.world_specular = "MAP", "SPLIT_SUM"
                progress.step(f"{world} {kind}: {label}")
            for spp in (1, 16):
                image, seconds = reference.render_peer(scene, reference.EEVEE, spp, tmp / "eevee.exr")
                rows.append(dict(world=world, kind=kind, who=f"EEVEE {spp} spp", ms=1e3 * seconds,
                                 errors=_errors(image, ref)))
                progress.step(f"{world} {kind}: EEVEE {spp}")
    return rows


def precomputation(frames: int, progress) -> dict:
    """Milliseconds to build the world's light from a 1K and a 4K image (GPU work fenced)."""
    import bpy
    import scenes
    from gpu_harness import run_on_gpu
    from test_world_light import _hdri, _world

    from addon.blender import extract
    from addon.frame import renderer

    out = {}
    for label, width in (("1K", 1024), ("4K", 4096)):
        scene = scenes.reset(size=16)
        scenes.ortho_camera(scene)
        scenes.plane(scene)
        source = _hdri("forest")
        if width != source.size[0]:
            image = source.copy()
            image.scale(width, width // 2)
        else:
            image = source
        _world(scene, image=image)
        times = []
        for k in range(frames + 1):
            scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0 + 0.01 * k

            def job(depsgraph):
                r = renderer.Renderer()
                try:
                    r.render(extract.snapshot(depsgraph, 16, 16))
                    return r.scene.environment.build_ms
                finally:
                    r.free()

            ms = run_on_gpu(job)
            if k:
                times.append(ms)
            progress.step(f"precomputation {label} {k}/{frames}")
        out[label] = (statistics.median(times), image.size[0], image.size[1])
        if image is not source:
            bpy.data.images.remove(image)
    return out


def frame_cost(frames: int, progress) -> dict:
    """The demo scene at 1280 x 720: lit by one point light, by the forest world, each model."""
    import bpy
    import demo_scene
    from test_world_light import _hdri, _world

    from addon.blender import engine

    scene = demo_scene.empty_scene(1280, 720)
    demo_scene.build(scene)
    configs = {"the demo's lights, black world": None,
               "+ the forest world (and its sun), split sum": "SPLIT_SUM",
               "+ the forest world (and its sun), sampled 64": "SAMPLED"}
    times = {k: [] for k in configs}
    for k in range(frames + 1):
        for label, specular in configs.items():
            if specular is None:
                _world(scene, color=(0.0, 0.0, 0.0))
            else:
                _world(scene, image=_hdri("forest"))
                scene.shading_lab.world_specular = specular
                scene.shading_lab.world_samples = 64
            engine.last_timings.clear()
            bpy.ops.render.render()
            if k:
                times[label].append(engine.last_timings["total_ms"])
            progress.step(f"frame cost {label} {k}/{frames}")
    return {k: statistics.median(v) for k, v in times.items()}


def report(args, rows, pre, frames) -> str:
    lines = ["# The world as a light", "",
             f"`scripts/world_bench.py {' '.join(args.argv)}` — {time.strftime('%Y-%m-%d %H:%M')}.", "",
             "Five spheres of roughness 0 / 0.25 / 0.5 / 0.75 / 1 under a bundled Blender world, nothing "
             "occluded; error = mean absolute error over the sphere / its mean radiance in Cycles "
             f"(direct light only, world on, {args.samples} spp). Frame times are llvmpipe times: ratios "
             "within this run only.", ""]
    for world in args.world_list:
        for kind in ("metal", "dielectric"):
            lines += [f"## {world}, {'white GGX metal' if kind == 'metal' else 'red Principled dielectric'}",
                      "", "| renderer | " + " | ".join(f"r {r}" for r in ROUGHNESS) + " | ms |",
                      "|---|" + "---:|" * (len(ROUGHNESS) + 1)]
            for row in rows:
                if row["world"] == world and row["kind"] == kind:
                    errs = " | ".join(f"{e:.2%}" for e in row["errors"])
                    lines.append(f"| {row['who']} | {errs} | {row['ms']:.0f} |")
            lines.append("")
    lines += ["## Precomputation", "", "| world image | texels | build ms (median) |", "|---|---|---:|"]
    for label, (ms, w, h) in pre.items():
        lines.append(f"| forest, {label} | {w} × {h} | {ms:.0f} |")
    lines += ["", "## Frame cost (demo scene, 1280 × 720, physically based)", "",
              "| lighting | total ms (median) | vs black world |", "|---|---:|---:|"]
    base = frames["the demo's lights, black world"]
    for label, ms in frames.items():
        lines.append(f"| {label} | {ms:.1f} | {ms / base:.2f}× |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", default="forest,city")
    parser.add_argument("--samples", type=int, default=1024, help="Cycles samples per pixel")
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "bench")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    args.argv = (sys.argv[1:] if argv is None else argv) or ["(defaults)"]
    args.world_list = [w.strip() for w in args.worlds.split(",") if w.strip()]
    try:
        cli.check_output_dir(args.out)
        cli.ensure_addon()
        total = (len(args.world_list) * 2 * (1 + len(VARIANTS) + 2) + 2 * (args.frames + 1)
                 + 3 * (args.frames + 1))
        progress = cli.Progress(total)
        with tempfile.TemporaryDirectory() as tmp:
            rows = spheres(args.world_list, args.samples, Path(tmp), progress)
            pre = precomputation(args.frames, progress)
        frames = frame_cost(args.frames, progress)
        text = report(args, rows, pre, frames)
        (args.out / "world.md").write_text(text, encoding="utf-8")
        print(text)
    except (cli.CliError, ValueError) as exc:
        print(f"world_bench.py: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
