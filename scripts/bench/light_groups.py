"""The light loop per group (a kind, with or without a shadow map) against one loop over every
light.

Two scenes, each configuration rendered with the groups (``programs.LIGHT_GROUPS``, the default)
and with one loop over every light that tests each light's kind and shadow map (the cost before
the groups: both sides of a test run on this machine's rasteriser):
- *furnace* (the preset: 12 spheres, 42 suns, soft shadows on, the Principled set) with the Cast
  Shadow of N suns on (N = 42, 21, 4, 1, 0; the last N in the file's order, so the casting ones
  are not listed first);
- *mixed kinds*: a plane and a sphere in an orthographic view under 16 point lights, alone, with
  an area light, with a spot light, and the area light alone (no shadows, the default terms).
Round-robin after a warm-up round, in one process (a case's first render after another case's,
which allocates its shadow maps' texture, untimed); medians of the engine's draw time (GPU work
fenced by the read-back), and the largest difference between the two images of each row.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from .harness import engines, page, scenes, standard, timing

PAGE = "light_groups.md"
QUICK = dict(resolution="160x90", frames=1)
CASTING = (42, 21, 4, 1, 0)
MIXES = (("points",), ("points", "area"), ("points", "spot"), ("area",))


def options(parser) -> None:
    standard(parser, resolution="640x360", frames=5)


def furnace(size):
    """The furnace preset and its configurations: N suns casting."""
    scene = scenes.preset("furnace", size)
    scene.shading_lab.term_set = "PRINCIPLED"
    suns = scenes.lights(scene)

    def apply(n):
        for i, data in enumerate(suns):
            data.use_shadow = i >= len(suns) - n

    return scene, apply, [(f"{n} of {len(suns)} suns casting", n) for n in CASTING]


def mixed_kinds(size):
    """16 point lights over a plane and a sphere, with an area or a spot light."""
    import bpy

    scene = scenes.empty(size)
    scenes.camera(scene, (0.0, 0.0, 5.0), ortho=8.0)
    bpy.ops.mesh.primitive_plane_add(size=16.0)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, location=(0.0, 0.0, 1.0))
    scene.shading_lab.shadows = False
    groups = {"points": [scenes.light(scene, f"Point {i}", "POINT",
                                      ((i % 4) * 2.0 - 3.0, (i // 4) * 1.2 - 1.8, 0.5),
                                      energy=20.0, use_shadow=False) for i in range(16)],
              "area": [scenes.light(scene, "Area", "AREA", (0.0, 0.0, 3.0), energy=200.0, use_shadow=False)],
              "spot": [scenes.light(scene, "Spot", "SPOT", (1.0, 0.0, 3.0), energy=200.0, use_shadow=False)]}

    def apply(mix):
        for name, objs in groups.items():
            for obj in objs:
                obj.hide_render = name not in mix

    return scene, apply, [(" + ".join(mix), mix) for mix in MIXES]


def run(ctx) -> None:
    from addon.plan import programs

    args = ctx.args
    rows = []
    try:
        for title, build in (("furnace", furnace), ("mixed kinds", mixed_kinds)):
            scene, set_up, cases = build(args.resolution)

            def apply(config, set_up=set_up):
                case, groups = config
                set_up(case)
                programs.LIGHT_GROUPS = groups

            def image(config, scene=scene, apply=apply) -> np.ndarray:
                apply(config)
                with tempfile.TemporaryDirectory() as tmp:
                    return engines.image(scene, Path(tmp) / "light_groups.exr")[0]

            differences = {case: float(np.abs(image((case, True)) - image((case, False))).max())
                           for _, case in cases}
            configs = [(case, groups) for _, case in cases for groups in (True, False)]
            med = timing.median_ms(configs, apply, args.frames, ctx.progress, title,
                                   state_of=lambda config: config[0])
            rows += [[title, label, f"{med[case, True]:.1f}", f"{med[case, False]:.1f}",
                      f"{med[case, True] / med[case, False]:.2f}x", f"{differences[case]:.3g}"]
                     for label, case in cases]
    finally:
        programs.LIGHT_GROUPS = True
    ctx.page("The light loop per group", [
        f"{page.res(args.resolution)}, {args.frames} frames per configuration after a warm-up, "
        "round-robin; draw + read-back ms, medians. *Groups*: a loop per kind of light with and "
        "without a shadow map, each holding its kind's code alone and the shadow lookup only with a "
        "map (the default); *one loop*: every light in one loop that tests its kind and its map (on "
        "this machine's rasteriser a test costs its body); the images' largest difference.", "",
        *page.table(["scene", "lights", "groups ms", "one loop ms", "groups / one loop",
                     "largest difference"], rows, "llrrrr")])
