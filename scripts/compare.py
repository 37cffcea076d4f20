"""Compare Shading Lab's models with the Cycles reference on a preset (or .blend, or demo).

    .venv/bin/python scripts/compare.py PRESET [--resolution WxH] [--samples N] [--variant NAME]
                                               [--out DIR] [term options as in render.py]
                                               [--transparency-layers N] [shadow options as in render.py]

Renders Blinn-Phong, Phong and the physically based model (with the scene's terms, or those
given), and the Cycles reference (direct light only, the world lighting occluded by the objects,
the lights as the file has them, shadows included, pixel-centre sampling; cached on disk, see
reference.py). Writes ``DIR/<scene>_compare.exr``
(multi-layer OpenEXR: a layer per model, the reference, and each model's absolute error),
``DIR/<scene>_compare.png`` (labelled: the images through a simple display transform, then
FLIP error maps) and ``DIR/<scene>_metrics.md`` (mean HDR-FLIP, mean relative error on lit
pixels, max absolute error, time), and prints the table.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

import render as cli  # noqa: E402

from addon.scene.snapshot import MODEL_CHOICES  # noqa: E402

MODELS = tuple((c.cli, c.id, c.label) for c in MODEL_CHOICES)


def parse_args(argv):
    parser = argparse.ArgumentParser(prog="compare.py", description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", help="a preset name or .toml, a .blend, demo or startup")
    parser.add_argument("--resolution", default="480x270", metavar="WxH")
    parser.add_argument("--reference-samples", type=int, default=256,
                        help="Cycles samples per pixel (default 256)")
    parser.add_argument("--variant", default=None)
    parser.add_argument("--out", type=Path, default=Path("out"))
    base = cli.parse_args(["x"])  # reuse render.py's term options
    for family in cli.TERM_CHOICES:
        parser.add_argument(f"--{family}", choices=[cli._flag(c) for c in cli.TERM_CHOICES[family]])
    parser.add_argument("--multiscatter", action=argparse.BooleanOptionalAction, default=None)
    parser.add_argument("--principled", action=argparse.BooleanOptionalAction, default=None)
    parser.add_argument("--term-set", choices=("custom", "principled", "auto"))
    parser.add_argument("--error-bound", type=float, metavar="DE")
    parser.add_argument("--transparency-layers", type=int, metavar="N",
                        help="partly transparent surfaces blended per pixel in depth order (1-16)")
    cli.add_shadow_options(parser)
    args = parser.parse_args(argv)
    for name in ("normalized_blinn_phong", "tone_mapper", "exposure", "samples"):
        setattr(args, name, getattr(base, name))  # not offered here: pixel-centre radiance is compared
    return args


def write_multilayer(path: Path, layers: dict[str, np.ndarray]) -> None:
    """One multi-layer OpenEXR (float32), channels ``<layer>.R/G/B``; rows top first."""
    import OpenEXR

    channels = {}
    for name, image in layers.items():
        for i, c in enumerate("RGB"):
            channels[f"{name}.{c}"] = np.ascontiguousarray(np.asarray(image, np.float32)[..., i])
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    partial = path.with_name(f".{path.name}.partial")
    with OpenEXR.File(header, channels) as f:
        f.write(str(partial))
    partial.replace(path)


def labelled_png(path: Path, panels: list[tuple[str, np.ndarray]], flips: list[tuple[str, np.ndarray]],
                 title: str) -> None:
    """The panels through one display transform (clip to 1, exact sRGB: the panels compare;
    exposure is not adjusted), the FLIP maps below."""
    from bench.harness import plots

    h, w = panels[0][1].shape[:2]
    cols = len(panels)
    fig, axes = plots.pyplot().subplots(2, cols, figsize=(cols * 3.2, 2 * 3.2 * h / w + 0.8), dpi=100)
    for ax, (label, image) in zip(axes[0], panels):
        ax.imshow(plots.display(image))
        ax.set_title(label, fontsize=9)
        ax.axis("off")
    for ax, (label, fmap) in zip(axes[1], flips):
        ax.imshow(fmap, cmap="magma", vmin=0.0, vmax=1.0)
        ax.set_title(label, fontsize=8)
        ax.axis("off")
    for ax in axes[1][len(flips):]:
        ax.axis("off")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    plots.save(fig, path)


def main(argv=None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        result = compare(args)
        print(result["table"])
        print(f"wrote {result['exr']}, {result['png']}, {result['md']}")
    except (cli.CliError, ValueError) as exc:
        print(f"\ncompare.py: error: {exc}", file=sys.stderr)
        return 2
    return 0


def compare(args) -> dict:
    """Render, measure and write; returns the paths, the table and the errors per model."""
    w, h = cli.parse_resolution(args.resolution)
    cli.check_output_dir(args.out)
    import metrics
    import reference

    cli.ensure_addon()
    scene, stem = cli.load_scene(args.scene, args.variant)
    stem += getattr(args, "tag", "") or ""
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.resolution_percentage = 100
    scene.render.engine = "SHADING_LAB"
    cli.configure(scene, args)
    if scene.camera is None:
        raise cli.CliError(f"{args.scene}: the scene has no active camera")
    progress = cli.Progress(len(MODELS) + 1)
    images, times = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for key, model, label in MODELS:
            scene.shading_lab.model = model
            start = time.perf_counter()
            images[key] = reference.render_to_array(scene, Path(tmp) / f"{key}.exr")
            times[key] = time.perf_counter() - start
            progress.step(label)
        start = time.perf_counter()
        ref, cached = reference.render_reference(scene, samples=args.reference_samples)
        times["reference"] = time.perf_counter() - start
        progress.step("Cycles reference" + (" (cached)" if cached else ""))
    rows, flips, layers = [], [], {"reference": ref}
    for key, _model, label in MODELS:
        e = metrics.errors(ref, images[key])
        rows.append((label, e, times[key]))
        flips.append((f"{label}: FLIP {e.flip:.3f}", metrics.flip_error(ref, images[key])[1]))
        layers[key.replace("-", "_")] = images[key]
        layers["error_" + key.replace("-", "_")] = np.abs(images[key][..., :3] - ref[..., :3])
    exr = args.out / f"{stem}_compare.exr"
    write_multilayer(exr, layers)
    terms = scene.shading_lab
    term_text = ("Principled BSDF set" if terms.term_set == "PRINCIPLED" else
                 f"Auto term set (error bound {terms.auto_error_bound:g})" if terms.term_set == "AUTO" else
                 f"{terms.fresnel.lower()} / {terms.ndf.lower()} / {terms.visibility.lower()} / "
                 f"{terms.diffuse.lower()}{' + multiscatter' if terms.multiscatter else ''}")
    title = (f"{stem} — physically based terms: {term_text}. Reference: Cycles, "
             f"{args.reference_samples} spp, direct light only, world on and occluded, shadows on")
    png = args.out / f"{stem}_compare.png"
    labelled_png(png, [(label, images[key]) for key, _, label in MODELS] + [("Cycles reference", ref)],
                 flips, title)
    lines = [f"**{stem}** at {w}×{h}. {title}.", "",
             "| model | mean FLIP (HDR) | mean relative error (lit pixels) | max abs error | time s |",
             "|---|---:|---:|---:|---:|"]
    for label, e, seconds in rows:
        lines.append(f"| {label} | {e.flip:.4f} | {e.mean_relative:.2%} | {e.max_abs:.3g} "
                     f"| {seconds:.2f} |")
    lines.append(f"| Cycles reference | – | – | – | {times['reference']:.2f}"
                 f"{' (cached)' if cached else ''} |")
    table = "\n".join(lines) + "\n"
    md = args.out / f"{stem}_metrics.md"
    md.write_text(table, encoding="utf-8")
    return {"stem": stem, "exr": exr, "png": png, "md": md, "table": table, "title": title,
            "errors": {label: e for label, e, _ in rows},
            "times": {label: t for label, _, t in rows}, "reference_time": times["reference"],
            "cached": cached}


if __name__ == "__main__":
    sys.exit(main())
