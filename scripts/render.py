"""Render a scene with Shading Lab's models: OpenEXR (scene-linear HDR) and a display PNG each.

    python scripts/render.py SCENE [--model blinn-phong|phong|pbr|all] [--resolution WxH] [--out DIR]
    blender -b --python scripts/render.py -- SCENE [options]

SCENE is ``demo`` (the built-in demo scene) or a path to a ``.blend`` file. Writes
``DIR/<scene>_<model>.exr`` and ``.png`` per model, and ``DIR/<scene>_comparison.png`` (the models
side by side, in the order given) when there are several. Exits non-zero with one line on error.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODELS = {"blinn-phong": "BLINN_PHONG", "phong": "PHONG", "pbr": "PBR"}


class CliError(Exception):
    pass


def parse_args(argv: list[str]) -> argparse.Namespace:
    if "--" in argv:  # blender -b ... --python render.py -- ARGS
        argv = argv[argv.index("--") + 1:]
    parser = argparse.ArgumentParser(prog="render.py", description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", help="'demo' or a path to a .blend file")
    parser.add_argument("--model", default="all", choices=[*MODELS, "all"])
    parser.add_argument("--resolution", default=None, metavar="WxH",
                        help="output size in pixels (default: the scene's; demo: 1280x720)")
    parser.add_argument("--out", default="out", type=Path, help="output directory (default: out)")
    return parser.parse_args(argv)


def parse_resolution(text: str) -> tuple[int, int]:
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise CliError(f"--resolution must look like 1280x720, got {text!r}") from None
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise CliError(f"--resolution must be between 1x1 and 16384x16384, got {text!r}")
    return w, h


def ensure_addon():
    import bpy

    if not hasattr(bpy.types.Scene, "shading_lab"):
        sys.path.insert(0, str(ROOT))
        import addon

        addon.register()


def load_scene(name: str):
    import bpy

    if name == "demo":
        sys.path.insert(0, str(ROOT / "scripts"))
        import demo_scene

        bpy.ops.wm.read_factory_settings(use_empty=True)
        scene = bpy.context.scene
        demo_scene.build(scene)
        scene.render.resolution_x, scene.render.resolution_y = 1280, 720
        return scene, "demo"
    path = Path(name)
    if path.suffix.lower() != ".blend":
        raise CliError(f"SCENE must be 'demo' or a .blend file, got {name!r}")
    if not path.is_file():
        raise CliError(f"no such .blend file: {path}")
    try:
        bpy.ops.wm.open_mainfile(filepath=str(path.resolve()))
    except RuntimeError as exc:
        raise CliError(f"could not open {path}: {exc}") from None
    return bpy.context.scene, path.stem


def check_output_dir(out: Path) -> None:
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CliError(f"cannot create output directory {out}: {exc.strerror}") from None
    if not os.access(out, os.W_OK):
        raise CliError(f"output directory {out} is not writable")


def save(image, scene, path: Path, file_format: str) -> None:
    settings = scene.render.image_settings
    settings.file_format = file_format
    if file_format == "OPEN_EXR":
        settings.color_depth = "32"
        settings.exr_codec = "ZIP"
    else:
        settings.color_mode = "RGB"
        settings.color_depth = "8"
    image.save_render(filepath=str(path), scene=scene)


def side_by_side(paths: list[Path], out: Path) -> None:
    """Concatenate display PNGs left to right (same size) into one PNG."""
    import bpy
    import numpy as np

    tiles = []
    for p in paths:
        img = bpy.data.images.load(str(p))
        px = np.empty(img.size[0] * img.size[1] * 4, np.float32)
        img.pixels.foreach_get(px)
        tiles.append(px.reshape(img.size[1], img.size[0], 4))
        bpy.data.images.remove(img)
    strip = np.concatenate(tiles, axis=1)
    h, w = strip.shape[:2]
    img = bpy.data.images.new("comparison", w, h, alpha=False)
    img.pixels.foreach_set(strip.ravel())
    img.filepath_raw = str(out)
    img.file_format = "PNG"
    img.save()
    bpy.data.images.remove(img)


def run(args: argparse.Namespace) -> list[Path]:
    models = list(MODELS) if args.model == "all" else [args.model]
    check_output_dir(args.out)
    import bpy

    ensure_addon()
    scene, stem = load_scene(args.scene)
    if args.resolution:
        scene.render.resolution_x, scene.render.resolution_y = parse_resolution(args.resolution)
        scene.render.resolution_percentage = 100
    scene.render.engine = "SHADING_LAB"
    written, pngs = [], []
    for i, model in enumerate(models, 1):
        scene.shading_lab.model = MODELS[model]
        start = time.perf_counter()
        print(f"[{i}/{len(models)}] {stem}: {model} ...", end="", flush=True)
        bpy.ops.render.render()
        result = bpy.data.images.get("Render Result")
        if result is None:
            raise CliError(f"rendering {model} produced no image (see the messages above)")
        exr, png = args.out / f"{stem}_{model}.exr", args.out / f"{stem}_{model}.png"
        save(result, scene, exr, "OPEN_EXR")
        save(result, scene, png, "PNG")
        written += [exr, png]
        pngs.append(png)
        print(f" {1000 * (time.perf_counter() - start):.0f} ms -> {exr}, {png.name}")
    if len(pngs) > 1:
        comparison = args.out / f"{stem}_comparison.png"
        side_by_side(pngs, comparison)
        written.append(comparison)
        print(f"side by side ({', '.join(models)}): {comparison}")
    return written


def main(argv: list[str] | None = None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        if args.resolution:
            parse_resolution(args.resolution)
        run(args)
    except CliError as exc:
        print(f"\nrender.py: error: {exc}", file=sys.stderr)
        return 2
    except ImportError as exc:
        print(f"\nrender.py: error: Blender's Python module is missing ({exc}); "
              f"run through ./run or pip install bpy==5.0.1", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    if code:
        os._exit(code)  # inside `blender --python`, sys.exit would not end Blender's process
    sys.exit(code)
