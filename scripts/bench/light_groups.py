"""The light loop per group (a kind, with or without a shadow map) against one loop over every
light (a benchmark, not a test).

    .venv/bin/python scripts/light_groups_bench.py [--resolution 640x360] [--frames 5]
        [--table docs/bench/light_groups.md]

Two scenes, each configuration rendered with the groups (``programs.LIGHT_GROUPS``, the default)
and with one loop over every light that tests each light's kind and shadow map (the cost before
the groups: both sides of a test run on this machine's rasteriser):
- *furnace* (the preset: 12 spheres, 42 suns, soft shadows on, the Principled set) with the Cast
  Shadow of N suns on (N = 42, 21, 4, 1, 0; the last N in the file's order, so the casting ones
  are not listed first);
- *mixed kinds*: a plane and a sphere in an orthographic view under 16 point lights, alone, with
  an area light, with a spot light, and the area light alone (no shadows, the default terms).
Round-robin after a warm-up round, in one process (a case's first render in a round, which
allocates its shadow maps' texture, untimed); medians of the engine's draw time (GPU work
fenced by the read-back), and the largest difference between the two images of each row. Times
are CPU-rasteriser times (Mesa llvmpipe): compare ratios.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

CASTING = (42, 21, 4, 1, 0)
MIXES = (("points",), ("points", "area"), ("points", "spot"), ("area",))


def furnace(w: int, h: int):
    """The furnace preset and its configurations: N suns casting."""
    import render

    scene, _ = render.load_scene("furnace", None)
    scene.render.engine = "SHADING_LAB"
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
    scene.shading_lab.term_set = "PRINCIPLED"
    suns = [obj.data for obj in scene.objects if obj.type == "LIGHT"]

    def apply(n):
        for i, data in enumerate(suns):
            data.use_shadow = i >= len(suns) - n

    return scene, apply, [(f"{n} of {len(suns)} suns casting", n) for n in CASTING]


def mixed_kinds(w: int, h: int):
    """16 point lights over a plane and a sphere, with an area or a spot light."""
    import bpy
    import round_robin

    scene = round_robin.empty_scene(w, h)
    round_robin.ortho_camera(scene, 8.0)
    bpy.ops.mesh.primitive_plane_add(size=16.0)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, location=(0.0, 0.0, 1.0))
    scene.shading_lab.shadows = False
    groups = {"points": [], "area": [], "spot": []}

    def add(name, kind, location, energy):
        data = bpy.data.lights.new(name, kind)
        data.energy, data.use_shadow = energy, False
        obj = bpy.data.objects.new(name, data)
        obj.location = location
        scene.collection.objects.link(obj)
        return obj

    for i in range(16):
        location = ((i % 4) * 2.0 - 3.0, (i // 4) * 1.2 - 1.8, 0.5)
        groups["points"].append(add(f"Point {i}", "POINT", location, 20.0))
    groups["area"].append(add("Area", "AREA", (0.0, 0.0, 3.0), 200.0))
    groups["spot"].append(add("Spot", "SPOT", (1.0, 0.0, 3.0), 200.0))

    def apply(mix):
        for name, objs in groups.items():
            for obj in objs:
                obj.hide_render = name not in mix

    return scene, apply, [(" + ".join(mix), mix) for mix in MIXES]


def main() -> int:
    import bpy
    import render
    import round_robin

    from addon.plan import programs

    args, w, h = round_robin.parse_args(__doc__, "light_groups.md")
    render.ensure_addon()
    rows = []
    for title, build in (("furnace", furnace), ("mixed kinds", mixed_kinds)):
        scene, set_up, cases = build(w, h)

        last = []

        def apply(config, set_up=set_up, last=last):
            case, groups = config
            set_up(case)
            programs.LIGHT_GROUPS = groups
            if last != [case]:  # a new case: its first render makes the shadow maps' texture
                last[:] = [case]
                bpy.ops.render.render()

        def image(config, scene=scene, apply=apply) -> np.ndarray:
            apply(config)
            path = Path(bpy.app.tempdir) / "light_groups_bench.exr"
            scene.render.filepath = str(path)
            scene.render.image_settings.file_format = "OPEN_EXR"
            bpy.ops.render.render(write_still=True)
            return np.array(bpy.data.images.load(str(path), check_existing=False).pixels[:])

        differences = {case: float(np.abs(image((case, True)) - image((case, False))).max())
                       for _, case in cases}
        configs = [(case, groups) for _, case in cases for groups in (True, False)]
        med = round_robin.median_draw_ms(configs, apply, args.frames)
        programs.LIGHT_GROUPS = True
        rows += [f"| {title} | {label} | {med[case, True]:.1f} | {med[case, False]:.1f} | "
                 f"{med[case, True] / med[case, False]:.2f}x | {differences[case]:.3g} |"
                 for label, case in cases]
    table = "\n".join([
        f"The light loop per group, {w}x{h} (`scripts/light_groups_bench.py`, {args.frames} frames per "
        "configuration after a warm-up, round-robin; draw + read-back ms, medians). *Groups*: a loop "
        "per kind of light with and without a shadow map, each holding its kind's code alone and the "
        "shadow lookup only with a map (the default); *one loop*: every light in one loop that tests "
        "its kind and its map (on this machine's rasteriser a test costs its body); the images' "
        "largest difference.",
        "",
        "| scene | lights | groups ms | one loop ms | groups / one loop | largest difference |",
        "|---|---|---:|---:|---:|---:|",
        *rows, ""])
    round_robin.write_table(args.table, table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
