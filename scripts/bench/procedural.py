"""Procedural textures: what each compiled procedural costs per pixel against an Image Texture
read, and the Noise Texture by Detail.

A plane fills the frame under a sun (the Principled term set, shadows off); its Base Color comes
from one texture node at the plane's Object coordinates times 8 (the procedurals at their
defaults but for what the table names), from an Image Texture of a 1024 x 1024 image (Linear), or
is a constant. Every configuration is rendered round-robin in one process after a warm-up (draw +
read-back ms, medians); a texture's cost per pixel is its frame time over the constant's, divided
by the pixels, and its ratio the cost over the Image Texture's. Only the procedurals the compiler
has (``codegen.EMITTERS``) are listed.
"""

from __future__ import annotations

import math

from . import materials
from .harness import page, scenes, standard, timing

PAGE = "procedural.md"
QUICK = dict(resolution="160x90", frames=1, bake_resolutions="64,128")

#: label -> (node kind, {property or input: value}, output): a procedural at one setting.
PROCEDURALS = {
    "White Noise 3D": ("ShaderNodeTexWhiteNoise", {}, "Color"),
    "White Noise 4D": ("ShaderNodeTexWhiteNoise", {"noise_dimensions": "4D"}, "Color"),
    "Noise 3D, Detail 2": ("ShaderNodeTexNoise", {}, "Color"),
    "Noise 4D, Detail 2": ("ShaderNodeTexNoise", {"noise_dimensions": "4D"}, "Color"),
    "Noise 3D Ridged Multifractal": ("ShaderNodeTexNoise", {"noise_type": "RIDGED_MULTIFRACTAL"}, "Color"),
    "Voronoi 3D F1": ("ShaderNodeTexVoronoi", {}, "Color"),
    "Voronoi 3D Smooth F1": ("ShaderNodeTexVoronoi", {"feature": "SMOOTH_F1"}, "Color"),
    "Voronoi 3D Distance to Edge": ("ShaderNodeTexVoronoi", {"feature": "DISTANCE_TO_EDGE"}, "Distance"),
    "Voronoi 4D F1": ("ShaderNodeTexVoronoi", {"voronoi_dimensions": "4D"}, "Color"),
    "Wave bands": ("ShaderNodeTexWave", {}, "Color"),
    "Gradient linear": ("ShaderNodeTexGradient", {}, "Color"),
    "Checker": ("ShaderNodeTexChecker", {}, "Color"),
    "Magic, depth 2": ("ShaderNodeTexMagic", {}, "Color"),
    "Brick": ("ShaderNodeTexBrick", {}, "Color"),
    "Gabor 2D": ("ShaderNodeTexGabor", {}, "Value"),
    "Gabor 3D": ("ShaderNodeTexGabor", {"gabor_type": "3D"}, "Value"),
}
#: The Noise Texture's Detail settings timed (3D fBM).
DETAILS = (0.0, 1.0, 2.0, 4.0, 8.0, 15.0)
#: The baked fallback's resolutions measured (the Noise Texture forced through the bake).
BAKE_RESOLUTIONS = (64, 128, 256, 512, 1024)
#: The AOV images' side in the bake comparison (pixel centres).
AOV_SIZE = 65


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=5)
    parser.add_argument("--bake-resolutions", default=",".join(map(str, BAKE_RESOLUTIONS)),
                        help="the baked fallback's resolutions measured, comma-separated")


def _material(name: str):
    """A Principled BSDF of a constant base colour (the materials benchmark's)."""
    return materials._principled(name, (0.6, 0.5, 0.4), 0.5, 0.0)


def _textured(name: str, kind: str, settings: dict, output: str):
    """Base Color from node ``kind`` (``settings``: its properties and input values) at the
    Object coordinates times 8."""
    mat, tree, bsdf = _material(name)
    coord = tree.nodes.new("ShaderNodeTexCoord")
    scale = tree.nodes.new("ShaderNodeVectorMath")
    scale.operation = "SCALE"
    scale.inputs["Scale"].default_value = 8.0
    tree.links.new(coord.outputs["Object"], scale.inputs[0])
    node = tree.nodes.new(kind)
    for key, value in settings.items():
        if key in node.inputs:
            node.inputs[key].default_value = value
        else:
            setattr(node, key, value)
    tree.links.new(scale.outputs["Vector"], node.inputs["Vector"])
    tree.links.new(node.outputs[output], bsdf.inputs["Base Color"])
    return mat


def _image_material(folder):
    import bpy
    import numpy as np

    side = 1024
    image = bpy.data.images.new("Bench1024", side, side, float_buffer=False)
    rng = np.random.default_rng(7)
    image.pixels.foreach_set(rng.uniform(0.0, 1.0, side * side * 4).astype(np.float32))
    image.filepath_raw = str(folder / "bench1024.png")
    image.file_format = "PNG"
    image.save()
    mat, tree, bsdf = _material("Image")
    tex = tree.nodes.new("ShaderNodeTexImage")
    tex.image, tex.interpolation = image, "Linear"
    coord = tree.nodes.new("ShaderNodeTexCoord")
    tree.links.new(coord.outputs["UV"], tex.inputs["Vector"])
    tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    return mat


def _scene(args):
    scene, plane = scenes.filled_plane(args.resolution)
    scenes.light(scene, "Sun", "SUN", rotation=(math.radians(20.0), math.radians(-15.0), 0.0), energy=3.0,
                 angle=0.0, use_shadow=False)
    return scene, plane


def _compiled(kind: str) -> bool:
    from addon.materials import codegen

    return kind in codegen.EMITTERS


def _timed(args, ctx, plane, materials: dict) -> dict:
    def apply(config):
        plane.data.materials.clear()
        plane.data.materials.append(materials[config])

    return timing.median_ms(list(materials), apply, args.frames, ctx.progress, "procedural")


def _cost(args, ctx, folder) -> list[str]:
    scene, plane = _scene(args)
    pixels = args.resolution[0] * args.resolution[1]
    materials = {"constant": _material("Constant")[0], "Image Texture": _image_material(folder)}
    materials.update({label: _textured(label, *spec) for label, spec in PROCEDURALS.items()
                      if _compiled(spec[0])})
    med = _timed(args, ctx, plane, materials)
    image = med["Image Texture"] - med["constant"]
    rows = []
    for label, ms in med.items():
        extra = ms - med["constant"]
        rows.append([label, f"{ms:.1f}", f"{1e6 * extra / pixels:.1f}",
                     "" if label == "constant" else f"{extra / image:.2f}x" if image > 0 else "n/a"])
    missing = [label for label, spec in PROCEDURALS.items() if not _compiled(spec[0])]
    return ["### Cost per pixel against an Image Texture read", "",
            f"{page.res(args.resolution)}, a plane filling the frame, one sun, the Principled term set; "
            f"{args.frames} frames per configuration after a warm-up, round-robin; draw + read-back ms, "
            "medians. *ns per pixel*: the frame time over the constant material's, per pixel; *vs image*: "
            "that over the Image Texture's.", "",
            *page.table(["Base Color from", "ms", "ns per pixel", "vs image"], rows), "",
            *([f"Not compiled yet, so not timed: {', '.join(missing)}.", ""] if missing else [])]


def _details(args, ctx) -> list[str]:
    if not _compiled("ShaderNodeTexNoise"):
        return []
    scene, plane = _scene(args)
    pixels = args.resolution[0] * args.resolution[1]
    materials = {"constant": _material("Constant")[0]}
    materials.update({f"Detail {d:g}": _textured(f"Detail{d:g}", "ShaderNodeTexNoise", {"Detail": d}, "Fac")
                      for d in DETAILS})
    med = _timed(args, ctx, plane, materials)
    rows = [[label, f"{ms:.1f}", f"{1e6 * (ms - med['constant']) / pixels:.1f}"] for label, ms in med.items()]
    return ["### The Noise Texture by Detail", "",
            "3D fBM into Base Color (its Fac), the scene above.", "",
            *page.table(["Noise", "ms", "ns per pixel"], rows), ""]


def _aov_values(scene, path):
    """The AOV "noise" of the last render, saved to ``path``: (pixels,) float64."""
    import bpy
    import numpy as np
    import OpenEXR

    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):  # Blender 5.0 groups formats by media type
        settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format, settings.color_depth = "OPEN_EXR_MULTILAYER", "32"
    bpy.data.images["Render Result"].save_render(filepath=str(path), scene=scene)
    with OpenEXR.File(str(path)) as f:
        channels = {name: np.asarray(ch.pixels, np.float64) for part in f.parts
                    for name, ch in part.channels.items()}
    return channels["ViewLayer.noise.X"]


def _bake(args, ctx, folder) -> list[str]:
    """The Noise Texture's Fac (at the UV times 6, 3D fBM) into an AOV on a plane, drawn compiled
    and forced through the baked fallback at each resolution, against Cycles' AOV of it (one
    sample, pixel centres): the bake's time (``bake.CACHE``: both of its bakes) and the largest
    and mean differences."""
    import bpy
    import numpy as np

    from addon.blender import bake
    from addon.materials import codegen

    scene = scenes.empty((AOV_SIZE, AOV_SIZE))
    scenes.camera(scene, (0.0, 0.0, 5.0), ortho=2.0)
    scenes.black_world(scene)
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    mat, tree, bsdf = _material("Baked")
    bpy.context.active_object.data.materials.append(mat)
    coord = tree.nodes.new("ShaderNodeTexCoord")
    scale = tree.nodes.new("ShaderNodeVectorMath")
    scale.operation = "SCALE"
    scale.inputs["Scale"].default_value = 6.0
    tree.links.new(coord.outputs["UV"], scale.inputs[0])
    noise = tree.nodes.new("ShaderNodeTexNoise")
    tree.links.new(scale.outputs["Vector"], noise.inputs["Vector"])
    aov = scene.view_layers[0].aovs.add()
    aov.name, aov.type = "noise", "VALUE"
    out = tree.nodes.new("ShaderNodeOutputAOV")
    out.aov_name = "noise"
    tree.links.new(noise.outputs["Fac"], out.inputs["Value"])
    c = scene.cycles
    scene.render.engine = "CYCLES"
    c.device, c.samples, c.use_adaptive_sampling, c.use_denoising = "CPU", 1, False, False
    c.pixel_filter_type, c.filter_width, c.max_bounces = "GAUSSIAN", 0.01, 0
    bpy.ops.render.render()
    cycles = _aov_values(scene, folder / "cycles.exr")
    scene.render.engine = "SHADING_LAB"

    def ours(name):
        bpy.ops.render.render()
        return _aov_values(scene, folder / f"{name}.exr")

    compiled = np.abs(ours("compiled") - cycles)
    rows = [["compiled", "", f"{compiled.max():.1e}", f"{compiled.mean():.1e}"]]
    previous = codegen.FORCE_BAKE
    codegen.FORCE_BAKE = frozenset({"ShaderNodeTexNoise"})
    try:
        for resolution in (int(r) for r in args.bake_resolutions.split(",")):
            scene.shading_lab.bake_resolution = resolution
            bake.CACHE.clear()
            diff = np.abs(ours(f"baked{resolution}") - cycles)
            seconds = sum(b.seconds for b in bake.CACHE._entries.values())
            rows.append([f"baked at {resolution}²", f"{seconds:.2f}", f"{diff.max():.1e}",
                         f"{diff.mean():.1e}"])
            ctx.progress.step(f"bake {resolution}")
    finally:
        codegen.FORCE_BAKE = previous
        bake.CACHE.clear()
    return ["### The baked fallback against the compiled node", "",
            f"The Noise Texture's Fac (3D fBM, Detail 2, at the UV times 6) into an AOV on a plane "
            f"filling a {AOV_SIZE}×{AOV_SIZE} view, compiled, and forced through the baked fallback (the "
            "Noise node baked by Cycles on the UV map, sampled as an image), each against Cycles' AOV of "
            "it (one sample at pixel centres). *Bake s*: the bake's time, its two Cycles bakes (the "
            "value, and the one its measured error comes from).", "",
            *page.table(["Noise drawn", "bake s", "largest difference", "mean difference"], rows), ""]


def run(ctx) -> None:
    import tempfile
    from pathlib import Path

    folder = Path(tempfile.mkdtemp(prefix="procedural-"))
    lines = _cost(ctx.args, ctx, folder) + _details(ctx.args, ctx) + _bake(ctx.args, ctx, folder)
    ctx.page("Procedural textures", [
        "What the compiled procedural textures (addon/materials/textures.py) cost per pixel, against an "
        "Image Texture read; what a baked subgraph costs and how far it is from the compiled node.", "",
        *lines])
