"""The world as a light: error against Cycles per roughness for each world variant, EEVEE beside
it, the precomputation cost and the frame cost.

Scenes: five spheres of roughness 0, 0.25, 0.5, 0.75, 1 in a row (200 x 40 px, orthographic),
white GGX metal (Glossy BSDF) or red Principled dielectric, under a bundled Blender world, nothing
occluded (the spheres' shadow, diffuse, glossy and transmission rays off). Errors are the mean
absolute error over each sphere divided by its mean radiance in Cycles (direct light only, world
on, ``--reference-samples``; not cached: the cache's key misses the rays' visibility). EEVEE
renders the same scene at 1 and 16 samples with its default world lighting (its sun threshold
splits off the brightest texels too). Times are wall times of the render (ours after a warm-up
render that compiles the programs and precomputes the world).

Precomputation: the world's light built from a 1K bundled world (1024 x 512) and from the same
image resampled to 4K (4096 x 2048), medians of ``--frames`` rebuilds (the world's strength
nudged each time so that the cache does not answer). Frame cost: the demo scene at
``--resolution`` (its point light and sun) with a black world and with the forest world,
round-robin, medians of ``--frames``.

The world cache (``addon/plan/world_cache.py``) is off here: every build is computed, as a
session's first render of a world it has not seen computes it.
"""

from __future__ import annotations

import statistics
import tempfile
from pathlib import Path

from .harness import choices, engines, page, scenes, standard, timing

PAGE = "world.md"
QUICK = dict(worlds="forest", reference_samples=16, frames=1, images="1K", resolution="320x180",
             peers="eevee-1")
ENV = {"SHADING_LAB_CACHE": "off"}  # the precomputation is measured, not the cache
ROUGHNESS = (0.0, 0.25, 0.5, 0.75, 1.0)
VARIANTS = (("split sum", dict(world_specular="SPLIT_SUM")),
            ("sampled 64", dict(world_specular="SAMPLED", world_samples=64)),
            ("sampled 256", dict(world_specular="SAMPLED", world_samples=256)),
            ("split sum, SH9 diffuse", dict(world_specular="SPLIT_SUM", world_diffuse="SH9")))
IMAGES = {"1K": 1024, "4K": 4096}
EEVEE = ("eevee-1", "eevee-16")
FRAME_CONFIGS = {"the demo's lights, black world": None,
                 "+ the forest world (and its sun), split sum": "SPLIT_SUM",
                 "+ the forest world (and its sun), sampled 64": "SAMPLED"}


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=5, reference_samples=1024, peers=",".join(EEVEE))
    parser.add_argument("--worlds", default="forest,city", help="bundled worlds, comma-separated")
    parser.add_argument("--images", type=choices(IMAGES), default="1K,4K",
                        help="the world images the precomputation is timed on (default 1K,4K)")


def spheres(worlds, samples: int, peers, tmp: Path, progress) -> list[dict]:
    """Per world and material: ours per variant, EEVEE 1 and 16 spp, each against Cycles."""
    from test_world_light import _errors, _hdri, _row_scene, _world

    rows = []
    progress.expect(len(worlds) * 2 * (1 + len(VARIANTS) + len(peers)))
    for world in worlds:
        for kind in ("metal", "dielectric"):
            scene = _row_scene(kind)
            _world(scene, image=_hdri(world))
            ref = engines.cycles(scene, samples, cache=False)[0]
            progress.step(f"{world} {kind}: Cycles")
            for label, settings in VARIANTS:
                for key, value in settings.items():
                    setattr(scene.shading_lab, key, value)
                scene.render.engine = engines.OURS
                engines.image(scene, tmp / "ours.exr")  # warm-up: programs and the world's light built
                image, ms = engines.image(scene, tmp / "ours.exr")
                rows.append(dict(world=world, kind=kind, who=f"Shading Lab, {label}", ms=ms,
                                 errors=_errors(image, ref)))
                scene.shading_lab.world_diffuse, scene.shading_lab.world_specular = "MAP", "SPLIT_SUM"
                progress.step(f"{world} {kind}: {label}")
            for peer in peers:
                image, ms = engines.image(scene, tmp / "eevee.exr", peer)
                rows.append(dict(world=world, kind=kind, who=engines.label(peer), ms=ms,
                                 errors=_errors(image, ref)))
                progress.step(f"{world} {kind}: {engines.label(peer)}")
    return rows


def precomputation(images, frames: int, progress) -> dict:
    """Milliseconds to build the world's light from a 1K and a 4K image (GPU work fenced)."""
    import bpy
    import scenes as test_scenes
    from gpu_harness import run_on_gpu
    from test_world_light import _hdri, _world

    from addon.blender import extract
    from addon.frame import renderer

    def job(depsgraph):
        r = renderer.Renderer()
        try:
            r.render(extract.snapshot(depsgraph, 16, 16))
            return r.scene.environment.build_ms
        finally:
            r.free()

    out = {}
    progress.expect(len(images) * (frames + 1))
    for label in images:
        width = IMAGES[label]
        scene = test_scenes.reset(size=16)
        test_scenes.ortho_camera(scene)
        test_scenes.plane(scene)
        source = _hdri("forest")
        image = source if width == source.size[0] else source.copy()
        if image is not source:
            image.scale(width, width // 2)
        _world(scene, image=image)
        times = []
        for k in range(frames + 1):
            scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0 + 0.01 * k
            ms = run_on_gpu(job)
            if k:
                times.append(ms)
            progress.step(f"precomputation {label} {k}/{frames}")
        out[label] = (statistics.median(times), image.size[0], image.size[1])
        if image is not source:
            bpy.data.images.remove(image)
    return out


def frame_cost(size, frames: int, progress) -> dict:
    """The demo scene: lit by its lights alone, and by the forest world too."""
    from test_world_light import _hdri, _world

    scene = scenes.demo(size)

    def apply(label):
        specular = FRAME_CONFIGS[label]
        if specular is None:
            _world(scene, color=(0.0, 0.0, 0.0))
        else:
            _world(scene, image=_hdri("forest"))
            scene.shading_lab.world_specular, scene.shading_lab.world_samples = specular, 64

    return timing.median_ms(list(FRAME_CONFIGS), apply, frames, progress, "frame cost", key="total_ms")


def run(ctx) -> None:
    args = ctx.args
    worlds = [w.strip() for w in args.worlds.split(",") if w.strip()]
    with tempfile.TemporaryDirectory() as tmp:
        rows = spheres(worlds, args.reference_samples, args.peers, Path(tmp), ctx.progress)
        pre = precomputation(args.images, args.frames, ctx.progress)
    frames = frame_cost(args.resolution, args.frames, ctx.progress)
    lines = ["Five spheres of roughness 0 / 0.25 / 0.5 / 0.75 / 1 under a bundled Blender world, nothing "
             "occluded; error = mean absolute error over the sphere / its mean radiance in Cycles "
             f"(direct light only, world on, {args.reference_samples} spp).", ""]
    for world in worlds:
        for kind in ("metal", "dielectric"):
            material = "white GGX metal" if kind == "metal" else "red Principled dielectric"
            lines += [f"## {world}, {material}", "",
                      *page.table(["renderer", *(f"r {r}" for r in ROUGHNESS), "ms"],
                                  [[row["who"], *(f"{e:.2%}" for e in row["errors"]), f"{row['ms']:.0f}"]
                                   for row in rows if row["world"] == world and row["kind"] == kind]), ""]
    base = frames["the demo's lights, black world"]
    lines += ["## Precomputation", "",
              *page.table(["world image", "texels", "build ms (median)"],
                          [[f"forest, {label}", f"{w} × {h}", f"{ms:.0f}"]
                           for label, (ms, w, h) in pre.items()],
                          "llr"), "",
              f"## Frame cost (demo scene, {page.res(args.resolution)}, physically based)", "",
              *page.table(["lighting", "total ms (median)", "vs black world"],
                          [[label, f"{ms:.1f}", f"{ms / base:.2f}×"] for label, ms in frames.items()])]
    ctx.page("The world as a light", lines)
