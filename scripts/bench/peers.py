"""Benchmark: Shading Lab's Principled set against EEVEE at 1 sample on every preset -- wall time
and error against Cycles -- the speed target's comparison alone (a benchmark, not a test).

    .venv/bin/python scripts/peer_bench.py [--presets a,b] [--frames 3] [--resolution 640x360]
                                           [--reference-samples 128] [--out docs/bench]

Per preset, at ``--resolution``: Shading Lab's Principled set and its default terms, and EEVEE at
1 sample (lights as the file has them, shadows included, light threshold 1e-6: ``bench.set_peer``),
rendered round-robin in one process (a warm-up round, then ``--frames`` timed rounds, the order
rotated each round; a timed render that follows the other engine's is preceded by an untimed one
of its own, ``bench.round_robin``: each engine in its steady state); wall time of
``bpy.ops.render.render()``, medians. Errors against Cycles
(``reference.render_reference``, cached; direct light, world on, lights as the file has them):
mean HDR-FLIP and mean relative luminance error on lit pixels. *Met*: EEVEE takes at least
``TARGET``x our Principled set's time and its FLIP is higher. ``bench.py`` measures the same
peers beside every configuration (48 min); this is the ten-minute version.

Writes ``OUT/peers.md`` (also printed). Frame times are CPU-rasteriser times (Mesa llvmpipe):
compare ratios within one run.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts"), str(ROOT / "tests")]

import bench  # noqa: E402
import render as cli  # noqa: E402

TARGET = 20.0  # EEVEE at 1 sample over our Principled set's time
#: Ours as bench.py configures them (``bench.apply``), then EEVEE at 1 sample as bench.py sets up
#: its peers (``bench.set_peer``).
CONFIGS = (bench.Config("principled", "Principled set", "PBR", principled=True),
           bench.Config("pbr", "PBR default", "PBR"), "eevee-1")


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--presets", default="", help="comma-separated preset names (default: all shipped)")
    parser.add_argument("--frames", type=int, default=3, help="timed rounds after the warm-up (default 3)")
    parser.add_argument("--resolution", default="640x360", metavar="WxH")
    parser.add_argument("--reference-samples", type=int, default=128)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "bench")
    args = parser.parse_args(argv)
    if args.frames < 1:
        parser.error("--frames must be at least 1")
    return args


def key_of(config) -> str:
    return config.key if isinstance(config, bench.Config) else config


def measure(name: str, args, progress, tmp: Path) -> dict:
    import metrics
    import reference

    scene, _stem = cli.load_scene(name, None)
    bench.set_resolution(scene, args.size)
    images = {}

    def run(config):
        key = key_of(config)
        if isinstance(config, bench.Config):
            bench.apply(scene, config)
        else:
            bench.set_peer(scene, (key, reference.EEVEE, 1))
        if key not in images:  # the warm-up round's render gives the image
            images[key] = reference.render_to_array(scene, tmp / f"{name}_{key}.exr")
            return {"wall_ms": 0.0}
        return bench.render_timed(scene)

    times = bench.round_robin(list(CONFIGS), args.frames, run, progress, name,
                              engine_of=lambda config: isinstance(config, bench.Config))
    ref, cached = reference.render_reference(scene, samples=args.reference_samples)
    progress.step(f"{name} Cycles reference{' (cached)' if cached else ''}")
    return {"name": name, "lights": sum(1 for o in scene.objects if o.type == "LIGHT"),
            "times": {key_of(c): t["wall_ms"] for c, t in zip(CONFIGS, times)},
            "errors": {key: metrics.errors(ref, image) for key, image in images.items()}}


def report(args, rows, started: float, machine: dict) -> str:
    met = 0
    lines = [
        "# Shading Lab against EEVEE at 1 sample", "",
        f"`scripts/peer_bench.py {' '.join(args.argv) or '(defaults)'}` — {time.strftime('%Y-%m-%d %H:%M')}, "
        f"{(time.perf_counter() - started) / 60:.1f} min.", "",
        f"**Machine:** {machine['cpu']}; GPU: {machine['gl']}; commit {machine['git']}. Load average (1 min) "
        f"at start {machine['load'][0]}, at end {machine['load'][1]}. CPU-rasteriser times: ratios within "
        "this run only.", "",
        f"{bench.res(args.size)}, wall ms of a whole render (medians of {args.frames} rounds after a "
        "warm-up, round-robin, order rotated; a render after the other engine's follows an untimed one of "
        "its own), errors against Cycles at "
        f"{args.reference_samples} spp. *Met*: EEVEE 1 spp takes >= {TARGET:.0f}x our Principled set's time "
        "and has the higher FLIP. Each timed render renders a still scene again: its meshes come from "
        "the geometry memo (`extract.GEOMETRY_MEMO`) as at any re-render or a frame where they do not "
        "deform; nothing else is kept between renders (Persistent Data off: the shadow maps are drawn "
        "each time).", "",
        "| preset | lights | Principled ms | default PBR ms | EEVEE 1 spp ms | EEVEE / Principled | "
        "Principled FLIP / rel | EEVEE FLIP / rel | met |",
        "|---|---:|---:|---:|---:|---:|---:|---:|:---:|",
    ]
    for row in rows:
        t, e = row["times"], row["errors"]
        ratio = t["eevee-1"] / t["principled"]
        ok = ratio >= TARGET and e["principled"].flip < e["eevee-1"].flip
        met += ok
        lines.append(
            f"| {row['name']} | {row['lights']} | {t['principled']:.0f} | {t['pbr']:.0f} | "
            f"{t['eevee-1']:.0f} | "
            f"{ratio:.1f}x | {e['principled'].flip:.3f} / {100 * e['principled'].mean_relative:.1f}% | "
            f"{e['eevee-1'].flip:.3f} / {100 * e['eevee-1'].mean_relative:.1f}% | {'yes' if ok else 'no'} |")
    lines += ["", f"Met on {met} of {len(rows)} presets.", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    args.argv = sys.argv[1:] if argv is None else argv
    started = time.perf_counter()
    load_start = bench.load_average()
    try:
        args.size = cli.parse_resolution(args.resolution)
        cli.check_output_dir(args.out)
        cli.ensure_addon()
        from addon.scene import presets

        shipped = presets.scene_preset_names()
        names = [p.strip() for p in args.presets.split(",") if p.strip()] or shipped
        unknown = [p for p in names if p not in shipped]
        if unknown:
            raise cli.CliError(f"--presets: unknown {', '.join(unknown)}; shipped: {', '.join(shipped)}")
        progress = cli.Progress(len(names) * ((args.frames + 1) * len(CONFIGS) + 1))
        with tempfile.TemporaryDirectory() as tmp:
            rows = [measure(name, args, progress, Path(tmp)) for name in names]
        gl, _version = bench.gpu_info()
        machine = {"cpu": bench.cpu_model(), "gl": gl, "git": bench.git_state(),
                   "load": (load_start, bench.load_average())}
        text = report(args, rows, started, machine)
        (args.out / "peers.md").write_text(text, encoding="utf-8")
        print(text)
    except (cli.CliError, ValueError) as exc:
        print(f"\npeer_bench.py: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    sys.exit(code)
