"""Light shapes: frame time per light shape, with each model.

Nine spheres of roughness 0.1 to 0.9 on a ground, under four lights of one shape at a time: point
lights of radius 0, sphere lights of radius 0.25 m (soft falloff on, then off), square area lights
of 1 m (spread 180 degrees, then 30 degrees). Shadows off, the world black: the shading's own cost
(glsl/light_shading.glsl; in the physically based model sphere and area lights are linearly
transformed cosines). Every configuration is rendered round-robin after a warm-up round, in one
process; the table gives medians of the engine's draw time (GPU work fenced by the read-back) and
the ratio to point lights.
"""

from __future__ import annotations

import math

from .harness import page, scenes, standard, timing

PAGE = "light_shapes.md"
QUICK = dict(resolution="160x90", frames=1)
MODELS = ("BLINN_PHONG", "PBR")
#: (label, light type, radius or size, soft falloff, spread in degrees)
SHAPES = (("point", "POINT", 0.0, True, 180.0), ("sphere 0.25 m, soft falloff", "POINT", 0.25, True, 180.0),
          ("sphere 0.25 m", "POINT", 0.25, False, 180.0), ("square 1 m", "AREA", 1.0, False, 180.0),
          ("square 1 m, spread 30 deg", "AREA", 1.0, False, 30.0))
LIGHTS = ((-2.0, -1.5, 2.5), (2.0, -1.5, 2.5), (-2.0, 2.0, 2.0), (2.0, 2.0, 3.0))


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=5)


def build(size: tuple[int, int]):
    import bpy

    scene = scenes.empty(size)
    scene.shading_lab.shadows = False
    scene.world = None
    scenes.camera(scene, (0.0, -7.5, 5.0), (56.0, 0.0, 0.0))
    bpy.ops.mesh.primitive_plane_add(size=20.0)
    for i in range(9):
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5,
                                             location=((i % 3 - 1) * 1.4, (i // 3 - 1) * 1.4, 0.5))
        mat = bpy.data.materials.new(f"Rough{i}")
        mat.use_nodes = True
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Roughness"].default_value = 0.1 + 0.1 * i
        bsdf.inputs["Metallic"].default_value = float(i % 2)
        bpy.context.object.data.materials.append(mat)
    groups = {}
    for label, kind, size_m, soft, spread in SHAPES:
        shape = (dict(size=size_m, spread=math.radians(spread)) if kind == "AREA"
                 else dict(shadow_soft_size=size_m, use_soft_falloff=soft))
        groups[label] = [scenes.light(scene, f"{label}_{j}", kind, location,
                                      (0.3 * (j - 1.5), 0.2 * (1.5 - j), 0.0), energy=300.0, **shape)
                         for j, location in enumerate(LIGHTS)]
    return scene, groups


def run(ctx) -> None:
    args = ctx.args
    scene, groups = build(args.resolution)

    def apply(config):
        model, label = config
        scenes.show_only(groups, label)
        scene.shading_lab.model = model

    med = timing.median_ms([(model, label) for model in MODELS for label, *_ in SHAPES], apply, args.frames,
                           ctx.progress)
    point = SHAPES[0][0]
    rows = [[label, *(cell for m in MODELS for cell in (f"{med[m, label]:.1f}",
                                                         f"{med[m, label] / med[m, point]:.2f}x"))]
            for label, *_ in SHAPES]
    ctx.page("Light shapes", [
        f"{page.res(args.resolution)}: nine spheres on a ground under four lights of one shape, shadows "
        f"off, black world; {args.frames} frames per configuration after a warm-up, round-robin; draw "
        "+ read-back ms, medians; ratios to point lights.", "",
        *page.table(["lights", "Blinn-Phong ms", "vs points", "Physically based ms", "vs points"], rows)])
