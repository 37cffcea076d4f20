"""Render a scene with Shading Lab's models: OpenEXR (scene-linear HDR) and a display PNG each.

    python scripts/render.py SCENE [--model blinn-phong|phong|pbr|all] [--resolution WxH]
                             [--out DIR] [--frames A-B] [--variant NAME] [term options]
    blender -b --python scripts/render.py -- SCENE [options]

SCENE is ``demo`` (the built-in demo scene), ``startup`` (Blender's startup file: the default
cube, its light and grey world), a preset name (``fresnel``, ``long_tail`` ...; see
``--list``), a preset ``.toml`` file, or a ``.blend`` file. Writes ``DIR/<scene>_<model>.exr``
and ``.png`` per model (``_<frame>`` appended with ``--frames``), and ``DIR/<scene>_comparison.png``
with the models side by side when there are several. Files appear only when complete. Any error
prints one line and exits with status 2.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

# pure modules: no Blender needed to parse the arguments
from addon.reference.tonemap import TONE_MAPPER_CHOICES  # noqa: E402
from addon.scene.snapshot import MODEL_CHOICES, TERM_CHOICES, cli_names  # noqa: E402

MODELS = cli_names(MODEL_CHOICES)
TONE_MAPPERS = tuple(cli_names(TONE_MAPPER_CHOICES))


class CliError(Exception):
    pass


def _flag(value: str) -> str:
    return value.lower().replace("_", "-")


def parse_args(argv: list[str]) -> argparse.Namespace:
    if "--" in argv:  # blender -b ... --python render.py -- ARGS
        argv = argv[argv.index("--") + 1:]
    parser = argparse.ArgumentParser(prog="render.py", description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", nargs="?",
                        help="demo, startup, a preset name, a preset .toml or a .blend file")
    parser.add_argument("--list", action="store_true", help="list the shipped scene presets and exit")
    parser.add_argument("--model", default="all", choices=[*MODELS, "all"])
    parser.add_argument("--resolution", default=None, metavar="WxH",
                        help="output size in pixels (default: the scene's; demo: 1280x720)")
    parser.add_argument("--out", default="out", type=Path, help="output directory (default: out)")
    parser.add_argument("--frames", default=None, metavar="A-B",
                        help="render frames A to B (default: the current frame only)")
    parser.add_argument("--variant", default=None, help="a preset's lighting variant")
    terms = parser.add_argument_group("physically based terms (default: the scene's settings)")
    for family, choices in TERM_CHOICES.items():
        terms.add_argument(f"--{family}", choices=[_flag(c) for c in choices])
    terms.add_argument("--multiscatter", action=argparse.BooleanOptionalAction, default=None,
                       help="specular multiple-scattering energy compensation")
    terms.add_argument("--normalized-blinn-phong", action=argparse.BooleanOptionalAction, default=None)
    terms.add_argument("--principled", action=argparse.BooleanOptionalAction, default=None,
                       help="the Principled term set: Blender's Principled BSDF as Cycles evaluates it")
    terms.add_argument("--term-set", choices=("custom", "principled", "auto"),
                       help="custom (the terms above), principled, or auto: per material the cheapest "
                            "terms within --error-bound of the Principled set")
    terms.add_argument("--error-bound", type=float, metavar="DE",
                       help="with --term-set auto: the largest predicted Delta E_ITP against the "
                            "Principled set at the 99th percentile of a material's pixels (default 0.5)")
    display = parser.add_argument_group("display")
    display.add_argument("--tone-mapper", choices=TONE_MAPPERS)
    display.add_argument("--exposure", type=parse_exposure, metavar="EV|auto",
                         help="EV for the engine's own tone mappers, or 'auto': metered per frame (adapted "
                              "from frame to frame with --frames) and reported per image")
    display.add_argument("--exposure-compensation", type=float, metavar="EV",
                         help="with --exposure auto: stops added to the metered exposure")
    display.add_argument("--exposure-metering", choices=("histogram", "log-average"),
                         help="with --exposure auto: histogram (percentile-clipped, the default) or "
                              "log-average of every pixel")
    display.add_argument("--samples", type=int, help="N: N x N supersampling per pixel")
    display.add_argument("--transparency-layers", type=int, metavar="N",
                         help="partly transparent surfaces blended per pixel in depth order (1-16)")
    add_shadow_options(parser)
    args = parser.parse_args(argv)
    if not args.list and not args.scene:
        parser.error("SCENE is required (or --list)")
    return args


def parse_resolution(text: str) -> tuple[int, int]:
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise CliError(f"--resolution must look like 1280x720, got {text!r}") from None
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise CliError(f"--resolution must be between 1x1 and 16384x16384, got {text!r}")
    return w, h


def parse_exposure(text: str) -> float | str:
    if text.strip().lower() == "auto":
        return "auto"
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of stops or 'auto', got {text!r}") from None


def parse_frames(text: str | None) -> list[int] | None:
    if text is None:
        return None
    try:
        a, _, b = text.partition("-")
        first, last = int(a), int(b or a)
    except ValueError:
        raise CliError(f"--frames must look like 1-24 (or 7), got {text!r}") from None
    if last < first:
        raise CliError(f"--frames: the last frame {last} comes before the first {first}")
    if last - first >= 100_000:
        raise CliError("--frames: at most 100000 frames at once")
    return list(range(first, last + 1))


def ensure_addon():
    import bpy

    if not hasattr(bpy.types.Scene, "shading_lab"):
        import addon

        addon.register()


def load_scene(name: str, variant: str | None):
    """(scene, stem): the demo, Blender's startup file, a preset (name or .toml) or a .blend,
    loaded into Blender."""
    import bpy

    path = Path(name)
    if name == "demo":
        sys.path.insert(0, str(ROOT / "scripts"))
        import demo_scene

        bpy.ops.wm.read_factory_settings(use_empty=True)
        scene = bpy.context.scene
        demo_scene.build(scene)
        scene.render.resolution_x, scene.render.resolution_y = 1280, 720
        return scene, "demo"
    if name == "startup":
        bpy.ops.wm.read_factory_settings(use_empty=False)
        return bpy.context.scene, "startup"
    if path.suffix.lower() == ".blend":
        if not path.is_file():
            raise CliError(f"no such .blend file: {path}")
        try:
            bpy.ops.wm.open_mainfile(filepath=str(path.resolve()))
        except RuntimeError as exc:
            raise CliError(f"could not open {path}: {str(exc).strip()}") from None
        return bpy.context.scene, path.stem
    from addon.blender import scene_builder
    from addon.scene import presets

    if path.suffix.lower() == ".toml" and not path.is_file():
        raise CliError(f"no such preset file: {path}")
    if path.suffix.lower() not in ("", ".toml"):
        raise CliError(f"SCENE must be demo, startup, a preset name, a .toml preset or a .blend file, "
                       f"got {name!r}")
    preset = presets.load_scene_preset(path if path.suffix else name)  # PresetError names file and key
    if variant is not None and variant not in preset.variant_names:
        raise CliError(f"{name}: no lighting variant {variant!r}; it has: "
                       f"{', '.join(preset.variant_names) or 'none'}")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene_builder.build_scene(preset, scene, variant=variant)
    return scene, path.stem + (f"_{variant}" if variant else "")


SHADOW_MAP_SIZES = (512, 1024, 2048, 4096)


def add_shadow_options(parser) -> None:
    shadows = parser.add_argument_group("shadows (default: the scene's settings)")
    shadows.add_argument("--shadows", action=argparse.BooleanOptionalAction, default=None,
                         help="lights whose Cast Shadow is on cast shadows")
    shadows.add_argument("--shadow-map-size", type=int, choices=SHADOW_MAP_SIZES,
                         help="texels per side of each shadow map")
    shadows.add_argument("--soft-shadows", action=argparse.BooleanOptionalAction, default=None,
                         help="penumbrae from the lights' sizes")
    shadows.add_argument("--persistent-data", action=argparse.BooleanOptionalAction, default=None,
                         help="keep the shadow maps from one frame to the next where lights and casters "
                              "are the same (Blender's Persistent Data)")
    lights = parser.add_argument_group("lights (default: the scene's settings)")
    lights.add_argument("--light-threshold", type=float, metavar="W/M2",
                        help="irradiance below which a light stops (0: every light reaches everywhere)")
    lights.add_argument("--light-culling", action=argparse.BooleanOptionalAction, default=None,
                        help="shade each screen tile with only the lights that reach it")
    world = parser.add_argument_group("the world's light (default: the scene's settings)")
    world.add_argument("--world-specular", choices=("split-sum", "sampled"),
                       help="the specular lobe lit by the prefiltered world (split sum) or sampled per pixel")
    world.add_argument("--world-samples", type=int, metavar="N",
                       help="samples of the world per pixel for --world-specular sampled (1-1024)")
    world.add_argument("--world-diffuse", choices=("map", "sh9"),
                       help="the diffuse lobe lit by the irradiance map or nine spherical harmonics")
    world.add_argument("--world-occlusion", action=argparse.BooleanOptionalAction, default=None,
                       help="geometry occludes the world's light (screen-space)")


def configure(scene, args) -> None:
    props = scene.shading_lab
    for family in TERM_CHOICES:
        value = getattr(args, family)
        if value is not None:
            setattr(props, family, value.upper().replace("-", "_"))
    for name in ("multiscatter", "normalized_blinn_phong", "samples"):
        value = getattr(args, name)
        if value is not None:
            setattr(props, name, value)
    exposure = getattr(args, "exposure", None)
    compensation = getattr(args, "exposure_compensation", None)
    metering = getattr(args, "exposure_metering", None)
    if exposure == "auto":
        props.exposure_mode = "AUTO"
        props.exposure = compensation or 0.0
    elif exposure is not None:
        props.exposure_mode, props.exposure = "MANUAL", exposure
    if exposure != "auto" and (compensation is not None or metering):
        raise CliError("--exposure-compensation and --exposure-metering need --exposure auto")
    if metering:
        props.exposure_method = metering.upper().replace("-", "_")
    if args.principled is not None:
        props.term_set = "PRINCIPLED" if args.principled else "CUSTOM"
    term_set = getattr(args, "term_set", None)
    if term_set is not None:
        if args.principled is not None:
            raise CliError("give --term-set or --principled, not both")
        props.term_set = term_set.upper()
    bound = getattr(args, "error_bound", None)
    if bound is not None:
        if props.term_set != "AUTO":
            raise CliError("--error-bound needs --term-set auto")
        if not bound > 0.0:  # also refuses NaN
            raise CliError(f"--error-bound must be above 0 (Delta E_ITP), got {bound}")
        props.auto_error_bound = bound
    for name in ("shadows", "soft_shadows", "light_culling", "world_occlusion"):
        if getattr(args, name, None) is not None:
            setattr(props, name, getattr(args, name))
    for name in ("world_specular", "world_diffuse"):
        if getattr(args, name, None) is not None:
            setattr(props, name, getattr(args, name).upper().replace("-", "_"))
    world_samples = getattr(args, "world_samples", None)
    if world_samples is not None:
        if not 1 <= world_samples <= 1024:
            raise CliError(f"--world-samples must be between 1 and 1024, got {world_samples}")
        if props.world_specular != "SAMPLED":
            raise CliError("--world-samples needs --world-specular sampled (or a scene sampling its world)")
        props.world_samples = world_samples
    if getattr(args, "shadow_map_size", None) is not None:
        props.shadow_map_size = str(args.shadow_map_size)
    if getattr(args, "persistent_data", None) is not None:
        scene.render.use_persistent_data = args.persistent_data
    threshold = getattr(args, "light_threshold", None)
    if threshold is not None:
        if not threshold >= 0.0:  # also refuses NaN
            raise CliError(f"--light-threshold must be 0 or more (W/m^2), got {threshold}")
        props.light_threshold = threshold
    if args.samples is not None and not 1 <= args.samples <= 8:
        raise CliError(f"--samples must be between 1 and 8, got {args.samples}")
    if args.transparency_layers is not None:
        if not 1 <= args.transparency_layers <= 16:
            raise CliError(f"--transparency-layers must be between 1 and 16, got {args.transparency_layers}")
        props.transparency_layers = args.transparency_layers
    if args.tone_mapper is not None:
        props.tone_mapper = args.tone_mapper.upper()
        if props.tone_mapper != "BLENDER":
            scene.view_settings.view_transform = "Standard"  # the engine's curve already displays


def check_output_dir(out: Path) -> None:
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CliError(f"cannot create output directory {out}: {exc.strerror}") from None
    if not os.access(out, os.W_OK):
        raise CliError(f"output directory {out} is not writable")


def save(image, scene, path: Path, file_format: str) -> None:
    """Write through Blender to a temporary name, then move into place: no partial files."""
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = "IMAGE"
    settings.file_format = file_format
    if file_format == "OPEN_EXR":
        settings.color_mode = "RGBA"
        settings.color_depth = "32"
        settings.exr_codec = "ZIP"
    else:
        settings.color_mode = "RGB"
        settings.color_depth = "8"
    partial = path.with_name(f".{path.stem}.partial{path.suffix}")
    try:
        image.save_render(filepath=str(partial), scene=scene)
        os.replace(partial, path)
    except (RuntimeError, OSError) as exc:
        partial.unlink(missing_ok=True)
        raise CliError(f"could not write {path}: {str(exc).strip()}") from None


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
    partial = out.with_name(f".{out.stem}.partial.png")
    img.filepath_raw = str(partial)
    img.file_format = "PNG"
    img.save()
    bpy.data.images.remove(img)
    os.replace(partial, out)


class Progress:
    """A one-line progress bar on a terminal, plain lines otherwise (logs, CI)."""

    def __init__(self, total: int):
        self.total, self.done, self.start = total, 0, time.perf_counter()
        self.tty = sys.stderr.isatty()

    def step(self, label: str) -> None:
        self.done += 1
        width = 24
        filled = round(width * self.done / self.total)
        elapsed = time.perf_counter() - self.start
        line = f"[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} {label} ({elapsed:.1f} s)"
        print(("\r" + line) if self.tty else line, end="" if self.tty else "\n", file=sys.stderr, flush=True)
        if self.tty and self.done == self.total:
            print(file=sys.stderr)


def render_frame(args, scene, stem: str, models: list[str], frame: int | None, warned: dict,
                 progress: Progress) -> list[Path]:
    """Render ``frame`` (None: the current one) with each model; the files written."""
    import bpy

    from addon.blender import engine
    from addon.plan import auto_terms

    written = []
    if frame is not None:
        scene.frame_set(frame)
    pngs = []
    suffix = "" if frame is None else f"_{frame:04d}"
    for model in models:
        scene.shading_lab.model = MODELS[model]
        try:
            bpy.ops.render.render()
        except RuntimeError as exc:
            raise CliError(f"rendering {model}{suffix} failed: {str(exc).strip()}") from None

        warned.update(dict.fromkeys(engine.last_warnings))
        said = engine.exposure_text(engine.last_exposures)
        if said:
            print(f"{stem}_{model}{suffix}: exposure {said}")
        if scene.shading_lab.term_set == "AUTO" and MODELS[model] == "PBR":
            for name, choice in sorted(engine.last_term_choices.items()):
                why = f"; needs {choice.limiting} ({choice.reason})" if choice.limiting else ""
                if choice.samples and not choice.errors:
                    why += f"; too small for a program of its own (at most {choice.costs_ms:.2f} ms a frame)"
                if choice.alone:
                    why += (f"; shares a program (alone: {auto_terms.label(choice.alone)}, saving "
                            f"{choice.costs_ms:.2f} ms a frame)")
                print(f"{stem}_{model}{suffix}: material {name or '(none)'}: {choice.label}, predicted "
                      f"dE_ITP {choice.predicted:.2f}{why}")
        result = bpy.data.images.get("Render Result")
        if result is None:
            raise CliError(f"rendering {model}{suffix} produced no image")
        exr, png = args.out / f"{stem}_{model}{suffix}.exr", args.out / f"{stem}_{model}{suffix}.png"
        save(result, scene, exr, "OPEN_EXR")
        save(result, scene, png, "PNG")
        written += [exr, png]
        pngs.append(png)
        progress.step(f"{model}{suffix} -> {exr.name}")
    if len(pngs) > 1:
        comparison = args.out / f"{stem}_comparison{suffix}.png"
        side_by_side(pngs, comparison)
        written.append(comparison)
    return written


def run(args: argparse.Namespace) -> list[Path]:
    models = list(MODELS) if args.model == "all" else [args.model]
    frames = parse_frames(args.frames)
    resolution = parse_resolution(args.resolution) if args.resolution else None
    check_output_dir(args.out)

    ensure_addon()
    scene, stem = load_scene(args.scene, args.variant)
    if resolution:
        scene.render.resolution_x, scene.render.resolution_y = resolution
        scene.render.resolution_percentage = 100
    scene.render.engine = "SHADING_LAB"
    configure(scene, args)
    if scene.camera is None:
        raise CliError(f"{args.scene}: the scene has no active camera")
    written = []
    warned: dict[str, None] = {}
    progress = Progress(len(models) * len(frames or [None]))
    from addon.scene import exposure

    # with --frames, automatic exposure adapts from each frame to the next, as in an animation
    with exposure.TRACK.sequence() if frames else contextlib.nullcontext():
        for frame in frames or [None]:
            written += render_frame(args, scene, stem, models, frame, warned, progress)
    for warning in warned:  # each once, whatever the number of models and frames
        print(f"warning: {warning}", file=sys.stderr)
    print(f"wrote {len(written)} files to {args.out}/ (models left to right in the comparison: "
          f"{', '.join(models)})")
    return written


def main(argv: list[str] | None = None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        if args.list:
            from addon.scene import presets

            print(f"{'demo':18s} the built-in demo scene")
            print(f"{'startup':18s} Blender's startup file: the default cube, its light, the grey world")
            for name in presets.scene_preset_names():
                print(f"{name:18s} {presets.load_scene_preset(name).description}")
            return 0
        run(args)
    except CliError as exc:
        print(f"\nrender.py: error: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:  # presets.PresetError: names the file, the key and what was expected
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
