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
    import numpy as np
    from bench.harness import page, plots, timing

    from addon.blender import engine, scene_builder
    from addon.scene import presets

    scene = demo_scene.empty_scene()
    library = presets.load_material_presets()
    materials = {name: scene_builder.apply_material_preset(bpy.data.materials.new(name), preset)
                 for name, preset in library.items()}
    images: dict[tuple[str, str], np.ndarray] = {}

    def preview(item) -> dict[str, float]:
        model, name = item
        scene.shading_lab.model = model
        engine.last_timings.clear()
        start = time.perf_counter()
        materials[name].asset_generate_preview()
        wall = 1e3 * (time.perf_counter() - start)
        if not engine.last_timings:
            raise SystemExit(f"error: the preview of {name} was not rendered by Shading Lab")
        w, h = materials[name].preview.image_size
        pixels = np.array(materials[name].preview.image_pixels_float[:], np.float32).reshape(h, w, 4)
        images[model, name] = pixels[::-1, :, :3]  # top row first for the figure
        return {"engine_ms": engine.last_timings["total_ms"], "wall_ms": wall}

    # round-robin over every (model, material), one warm-up round (program compiles)
    items = [(model, name) for model, _ in MODELS for name in materials]
    samples = dict(zip(items, timing.collect(items, args.rounds, preview, timing.Progress(), "previews")))
    per_model = {m: [t for (model, _), ts in samples.items() if model == m for t in ts] for m, _ in MODELS}
    base = statistics.median(t["engine_ms"] for t in per_model["BLINN_PHONG"])
    print(f"\nMaterial previews, 128 x 128, {len(materials)} materials x {args.rounds} rounds per model")
    print("\n".join(page.table(
        ["model", "engine ms (median)", "whole preview ms (median)", "vs Blinn-Phong"],
        [[label, f"{statistics.median(t['engine_ms'] for t in per_model[m]):.1f}",
          f"{statistics.median(t['wall_ms'] for t in per_model[m]):.1f}",
          f"{statistics.median(t['engine_ms'] for t in per_model[m]) / base:.2f}x"] for m, label in MODELS])))

    rows, cols = len(MODELS), len(materials)
    fig, axes = plots.pyplot().subplots(rows, cols, figsize=(1.3 * cols, 1.45 * rows), dpi=100, squeeze=False)
    for r, (model, label) in enumerate(MODELS):
        for c, name in enumerate(materials):
            plots.image_panel(axes[r][c], images[model, name], name if r == 0 else "",
                              ylabel=label if c == 0 else "", interpolation="nearest")
    fig.suptitle("Material previews drawn by Shading Lab (preset library, Blender's preview scene)",
                 fontsize=9)
    fig.tight_layout()
    plots.save(fig, args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
