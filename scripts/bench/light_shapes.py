"""Light shapes: frame time per light shape, with each model (a benchmark, not a test).

    .venv/bin/python scripts/light_shape_bench.py [--resolution 1280x720] [--frames 5]
        [--table docs/bench/light_shapes.md]

Nine spheres of roughness 0.1 to 0.9 on a ground, under four lights of one shape at a time: point
lights of radius 0, sphere lights of radius 0.25 m (soft falloff on, then off), square area lights
of 1 m (spread 180 degrees, then 30 degrees). Shadows off, the world black: the shading's own cost
(glsl/light_shading.glsl; in the physically based model sphere and area lights are linearly
transformed cosines). Every configuration is rendered round-robin after a warm-up round, in one
process; the table gives medians of the engine's draw time (GPU work fenced by the read-back) and
the ratio to point lights. Times are CPU-rasteriser times (Mesa llvmpipe): compare ratios.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

MODELS = ("BLINN_PHONG", "PBR")
#: (label, light type, radius or size, soft falloff, spread in degrees)
SHAPES = (("point", "POINT", 0.0, True, 180.0), ("sphere 0.25 m, soft falloff", "POINT", 0.25, True, 180.0),
          ("sphere 0.25 m", "POINT", 0.25, False, 180.0), ("square 1 m", "AREA", 1.0, False, 180.0),
          ("square 1 m, spread 30 deg", "AREA", 1.0, False, 30.0))
LIGHTS = ((-2.0, -1.5, 2.5), (2.0, -1.5, 2.5), (-2.0, 2.0, 2.0), (2.0, 2.0, 3.0))


def build(w: int, h: int):
    import bpy
    import round_robin

    scene = round_robin.empty_scene(w, h)
    scene.shading_lab.shadows = False
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location, cam.rotation_euler = (0.0, -7.5, 5.0), (math.radians(56.0), 0.0, 0.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    bpy.ops.mesh.primitive_plane_add(size=20.0)
    for i in range(9):
        location = ((i % 3 - 1) * 1.4, (i // 3 - 1) * 1.4, 0.5)
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5, location=location)
        mat = bpy.data.materials.new(f"Rough{i}")
        mat.use_nodes = True
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Roughness"].default_value = 0.1 + 0.1 * i
        bsdf.inputs["Metallic"].default_value = float(i % 2)
        bpy.context.object.data.materials.append(mat)
    groups = {}
    for label, kind, size, soft, spread in SHAPES:
        objs = []
        for j, location in enumerate(LIGHTS):
            data = bpy.data.lights.new(f"{label}_{j}", kind)
            data.energy = 300.0
            if kind == "AREA":
                data.size, data.spread = size, math.radians(spread)
            else:
                data.shadow_soft_size, data.use_soft_falloff = size, soft
            obj = bpy.data.objects.new(data.name, data)
            obj.location = location
            obj.rotation_euler = (0.3 * (j - 1.5), 0.2 * (1.5 - j), 0.0)
            scene.collection.objects.link(obj)
            objs.append(obj)
        groups[label] = objs
    return scene, groups


def main() -> int:
    import round_robin

    args, w, h = round_robin.parse_args(__doc__, "light_shapes.md")

    scene, groups = build(w, h)
    if scene.world is not None:
        scene.world = None
    configs = [(model, label) for model in MODELS for label, *_ in SHAPES]

    def apply(config):
        model, label = config
        round_robin.show_only(groups, label)
        scene.shading_lab.model = model

    med = round_robin.median_draw_ms(configs, apply, args.frames)
    point = SHAPES[0][0]
    rows = [f"| {label} | " + " | ".join(f"{med[m, label]:.1f} | {med[m, label] / med[m, point]:.2f}x"
                                         for m in MODELS) + " |" for label, *_ in SHAPES]
    table = "\n".join([
        f"Light shapes, {w}x{h}: nine spheres on a ground under four lights of one shape, shadows off, "
        f"black world (`scripts/light_shape_bench.py`, {args.frames} frames per configuration after a "
        "warm-up, round-robin; draw + read-back ms, medians; ratios to point lights).",
        "",
        "| lights | Blinn-Phong ms | vs points | Physically based ms | vs points |",
        "|---|---:|---:|---:|---:|",
        *rows, ""])
    round_robin.write_table(args.table, table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
