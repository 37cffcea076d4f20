"""Material previews of the preset library, drawn by the engine (an image and a benchmark).

    .venv/bin/python scripts/previews.py [--rounds 5] [--out docs/images/previews.png]

For every material in presets/materials.toml and every model, asks Blender for the material's
preview (``ID.asset_generate_preview()``: the preview scene Blender builds — sphere, floor, two
area lights, its world — rendered by the scene's engine, 128 x 128). Writes one labelled grid
image and prints the median preview time per model: the engine's own time (scene reading, draw,
read-back) and the wall time of the whole call (Blender's preview set-up included). Models are
interleaved round by round so machine noise hits them alike; the first round (program compile)
is not counted. CPU-rasteriser times (Mesa llvmpipe): compare them as ratios within one run.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

from addon.scene.snapshot import MODEL_CHOICES  # noqa: E402  (pure module)

MODELS = tuple((c.id, c.label) for c in MODEL_CHOICES)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5, help="timed rounds after one warm-up round")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "images" / "previews.png")
    args = parser.parse_args()

    import bpy
    import demo_scene
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from addon.blender import engine, scene_builder
    from addon.scene import presets

    scene = demo_scene.empty_scene()
    library = presets.load_material_presets()
    materials = {name: scene_builder.apply_material_preset(bpy.data.materials.new(name), preset)
                 for name, preset in library.items()}

    images: dict[tuple[str, str], np.ndarray] = {}
    engine_ms: dict[str, list[float]] = {m: [] for m, _ in MODELS}
    wall_ms: dict[str, list[float]] = {m: [] for m, _ in MODELS}
    for round_ in range(args.rounds + 1):
        for model, _ in MODELS:
            scene.shading_lab.model = model
            for name, material in materials.items():
                engine.last_timings.clear()
                start = time.perf_counter()
                material.asset_generate_preview()
                wall = 1e3 * (time.perf_counter() - start)
                if not engine.last_timings:
                    print(f"error: the preview of {name} was not rendered by Shading Lab", file=sys.stderr)
                    return 1
                if round_ > 0:
                    engine_ms[model].append(engine.last_timings["total_ms"])
                    wall_ms[model].append(wall)
                preview = material.preview
                w, h = preview.image_size
                pixels = np.array(preview.image_pixels_float[:], np.float32).reshape(h, w, 4)
                images[model, name] = pixels[::-1, :, :3]  # top row first for the figure
        print(f"round {round_}/{args.rounds} done", file=sys.stderr)

    print(f"\nMaterial previews, 128 x 128, {len(materials)} materials x {args.rounds} rounds per model")
    print("| model | engine ms (median) | whole preview ms (median) | vs Blinn-Phong |")
    print("|---|---:|---:|---:|")
    base = statistics.median(engine_ms["BLINN_PHONG"])
    for model, label in MODELS:
        med = statistics.median(engine_ms[model])
        print(f"| {label} | {med:.1f} | {statistics.median(wall_ms[model]):.1f} | {med / base:.2f}x |")

    rows, cols = len(MODELS), len(materials)
    fig, axes = plt.subplots(rows, cols, figsize=(1.3 * cols, 1.45 * rows), dpi=100, squeeze=False)
    for r, (model, label) in enumerate(MODELS):
        for c, name in enumerate(materials):
            ax = axes[r][c]
            ax.imshow(images[model, name], interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(name, fontsize=8)
            if c == 0:
                ax.set_ylabel(label, fontsize=8)
    fig.suptitle("Material previews drawn by Shading Lab (preset library, Blender's preview scene)",
                 fontsize=9)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
