"""The README's artist-workflow images, rendered by the engine from the demo scene.

    .venv/bin/python scripts/workflow_images.py [--resolution 640x360] [--out docs/images]

Writes ``compare_split.png`` (A|B split, Blinn-Phong left of the divider, physically based right),
``compare_difference.png`` (the luminance difference as a heat map, range 1, with its scale strip) and
``passes.png`` (Combined, Diffuse Direct and Glossy Direct side by side, each through the same
display transform). Every image is the engine's final render, saved as Blender saves it.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolution", default="640x360")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "images")
    args = parser.parse_args()
    w, h = (int(x) for x in args.resolution.split("x"))

    import bpy
    import demo_scene
    import numpy as np
    import OpenEXR
    from bench.harness import plots

    from addon.blender import engine

    scene = demo_scene.empty_scene(w, h)
    demo_scene.build(scene)
    scene.view_settings.view_transform = "Standard"
    props = scene.shading_lab
    args.out.mkdir(parents=True, exist_ok=True)

    def render_png(path: Path) -> None:
        settings = scene.render.image_settings
        if hasattr(settings, "media_type"):
            settings.media_type = "IMAGE"
        settings.file_format = "PNG"
        bpy.ops.render.render()
        if not engine.last_timings:
            raise SystemExit("the render failed (see the console)")
        bpy.data.images["Render Result"].save_render(filepath=str(path), scene=scene)
        print(f"wrote {path}")

    props.compare_a, props.compare_b = "BLINN_PHONG", "PBR"
    props.compare_mode, props.compare_split = "SPLIT", 0.5
    render_png(args.out / "compare_split.png")
    props.compare_mode, props.compare_range = "DIFFERENCE", 1.0
    render_png(args.out / "compare_difference.png")
    props.compare_mode = "OFF"

    # light passes: a multilayer EXR, shown through the sRGB curve side by side
    layer = scene.view_layers[0]
    layer.use_pass_diffuse_direct = layer.use_pass_glossy_direct = True
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    bpy.ops.render.render()
    exr = Path(tempfile.mkdtemp(prefix="shading_lab_passes_")) / "passes.exr"
    bpy.data.images["Render Result"].save_render(filepath=str(exr), scene=scene)
    names = ["Combined", *engine.LIGHT_PASSES]
    images = {}
    with OpenEXR.File(str(exr)) as f:  # channels grouped per pass: "<layer>.<pass>" -> RGBA pixels
        for part in f.parts:
            for key, channel in part.channels.items():
                images[key.split(".")[-1]] = np.asarray(channel.pixels, np.float32)[..., :3]
    fig, axes = plots.pyplot().subplots(1, len(names), figsize=(4.2 * len(names), 4.2 * h / w + 0.5), dpi=100)
    for ax, name in zip(axes, names):
        plots.image_panel(ax, plots.display(images[name]), name, fontsize=10)
    fig.tight_layout()
    plots.save(fig, args.out / "passes.png")
    print(f"wrote {args.out / 'passes.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
