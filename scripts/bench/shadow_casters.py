"""Shadow casters left out of the maps where their shadows fall where no view looks.

Scene: a town of 225 objects (spheres and boxes, 4 m apart, 1-5 m tall) on an 80 m ground, lit by
a sun (2 degrees) and four point lights (0.2 m), every light casting, as a file would have it.
Three cameras: at eye height down a street (most of the town behind or beside it), close to one
corner, and over the whole town (everything in view: what the test costs where it leaves nothing
out). Each is rendered with ``passes.VIEW_CULLED_CASTERS`` on and off, round-robin after a
warm-up, ``--frames`` rounds; times are the engine's own (``engine.last_timings``: extraction,
drawing, read-back), medians. *pairs*: (layer, caster) pairs the shadow pass drew; *max |d|*: the
largest difference between the two images (0: the same image bit for bit).
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

from .harness import engines, page, scenes, standard, timing

PAGE = "shadow_casters.md"
QUICK = dict(resolution="160x90", frames=1)
#: camera -> (location, rotation in degrees, lens in mm)
CAMERAS = {
    "street": ((-30.0, -33.0, 1.7), (88.0, 0.0, -45.0), 35.0),
    "corner": ((-33.0, -33.0, 4.0), (70.0, 0.0, -30.0), 50.0),
    "overview": ((0.0, -70.0, 60.0), (48.0, 0.0, 0.0), 28.0),
}


def options(parser) -> None:
    standard(parser, resolution="640x360", frames=5)


def build_town(size: tuple[int, int]):
    """The town, its lights and a camera (``place`` sets its placement)."""
    import bpy
    import numpy as np
    import scenes as test_scenes

    scene = test_scenes.reset(size=size[0])
    scene.render.resolution_y = size[1]
    scene.shading_lab.model = "PBR"
    mat = bpy.data.materials.new("White")
    bsdf = test_scenes.node_tree(mat).nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (0.8, 0.8, 0.8, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.6
    test_scenes.plane(scene, size=80.0, material=mat)
    rng = np.random.default_rng(5)
    for i in range(15):
        for j in range(15):
            x, y, h = -28.0 + 4.0 * i, -28.0 + 4.0 * j, float(rng.uniform(1.0, 5.0))
            if (i + j) % 2:
                bpy.ops.mesh.primitive_uv_sphere_add(radius=0.6, location=(x, y, h), segments=24,
                                                     ring_count=12)
            else:
                bpy.ops.mesh.primitive_cube_add(size=1.0, location=(x, y, 0.5 * h), scale=(1.0, 1.0, h))
            bpy.context.object.data.materials.append(mat)
    sun = test_scenes.light(scene, "SUN", energy=3.0, rotation=(math.radians(-35.0), math.radians(25.0), 0.0))
    sun.data.angle = math.radians(2.0)
    lights = [sun] + [test_scenes.light(scene, "POINT", energy=2000.0, location=(x, y, 6.0),
                                        shadow_soft_size=0.2)
                      for x, y in ((-20.0, -20.0), (-6.0, 10.0), (14.0, -8.0), (20.0, 22.0))]
    for light in lights:
        light.data.use_shadow = True
    camera = scenes.camera(scene, (0.0, 0.0, 0.0))
    camera.data.clip_start, camera.data.clip_end = 0.1, 500.0
    return scene


def place(scene, name: str) -> None:
    location, rotation, lens = CAMERAS[name]
    scene.camera.location = location
    scene.camera.rotation_euler = tuple(math.radians(a) for a in rotation)
    scene.camera.data.lens = lens


def measure(scene, name: str, frames: int, tmp: Path, progress) -> dict:
    """One camera: times, pairs drawn and images with the test on and off."""
    import numpy as np

    from addon.frame import passes

    drawn: list[int] = []
    original = passes.ShadowPass.run

    def counted(self, frame, views=None):
        done = original(self, frame, views)
        drawn.append(self.drawn_casters)
        return done

    pairs, images = {}, {}

    def render(culled):
        passes.VIEW_CULLED_CASTERS = culled
        if culled not in images:  # the warm-up round's render: its image and pairs
            images[culled] = engines.image(scene, tmp / f"{name}_{culled}.exr")[0]
            pairs[culled] = drawn[-1]
            return {}
        return timing.render_timed(scene)

    place(scene, name)
    passes.ShadowPass.run = counted
    try:
        on, off = (t["total_ms"] for t in timing.round_robin([True, False], frames, render, progress, name))
    finally:
        passes.ShadowPass.run = original
        passes.VIEW_CULLED_CASTERS = True
    return dict(camera=name, on_ms=on, off_ms=off, ratio=on / off, pairs_on=pairs[True],
                pairs_off=pairs[False], max_diff=float(np.abs(images[True] - images[False]).max()))


def run(ctx) -> None:
    args = ctx.args
    scene = build_town(args.resolution)
    with tempfile.TemporaryDirectory() as tmp:
        rows = [measure(scene, name, args.frames, Path(tmp), ctx.progress) for name in CAMERAS]
    ctx.page("Shadow casters left out where no view looks", [
        "A town of 225 objects on an 80 m ground, a sun (one map, four cascades where the view is "
        f"deep) and four point lights (six maps each) casting, {page.res(args.resolution)}, engine ms, "
        f"medians of {args.frames} round-robin rounds after a warm-up.", "",
        *page.table(["camera", "culled ms", "every caster ms", "ratio", "pairs drawn (culled / every)",
                     "max abs diff"],
                    [[r["camera"], f"{r['on_ms']:.1f}", f"{r['off_ms']:.1f}", f"{r['ratio']:.2f}x",
                      f"{r['pairs_on']} / {r['pairs_off']}", f"{r['max_diff']:.3g}"] for r in rows])])
