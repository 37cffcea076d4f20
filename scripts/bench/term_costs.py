"""The Auto term set's cost table: each candidate term set's frame time against the default
terms', per light count, measured here (a benchmark, not a test).

    .venv/bin/python scripts/term_costs.py [--resolution 1280x720] [--frames 5]
        [--table docs/bench/term_costs.md] [--out addon/plan/term_costs.json] [--world-only]

A plane fills an orthographic view under N point lights that each reach all of it (N = 2, 8, 32;
no shadows, a black world: the shading is all the frame does), with a rough metal material.
Every (candidate, N) is rendered round-robin after a warm-up round, in one process; the medians
of the engine's draw time (GPU work fenced by the read-back) go to ``--out`` with their ratios to
the default terms (``relative``), which ``addon/plan/auto_terms.py`` orders its candidates by, with
the view's pixel count and a candidate program's first use (``first_use_ms``: its compile and
first draw, the driver's shader cache warm), which it weighs a program of its own against. Then
the world's specular (``world_ms``): the same plane under Blender's bundled forest world instead
of the black one (2 lights, world occlusion off), the Principled set with the split sum and with
the lobe sampled 16 and 64 times per pixel, which Auto weighs the split sum against where a scene
samples its world (``--world-only`` measures that alone and replaces it in ``--out`` and the
table, the candidates' times kept). Times are CPU-rasteriser times (Mesa llvmpipe): the add-on
uses them only against each other.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

COUNTS = (2, 8, 32)
#: Per-pixel world samples the sampled world specular is measured at.
WORLD_SAMPLES = (16, 64)
VIEW = 8.0  # the view's width (m)


def derive(draw_ms: dict[str, list[float]]) -> dict[str, list[float]]:
    """Each candidate's draw time over the default terms' at the same light count (4 decimals)."""
    base = draw_ms["DEFAULT"]
    return {name: [round(t / b, 4) for t, b in zip(times, base)] for name, times in draw_ms.items()}


def first_use_ms(names, apply) -> dict[str, float]:
    """Per candidate but the first, what its shading program's first use adds to a frame (its
    compile and first draw, with the driver's shader cache warm: every program was compiled
    before), at the first light count: the program library is emptied, the first candidate drawn
    (the frame's other programs and the tables come back), then each other one twice."""
    import bpy

    from addon.blender import engine
    from addon.frame import gpu_library

    gpu_library.LIBRARY.clear()
    out = {}
    for i, name in enumerate(names):
        times = []
        for _ in range(2):
            apply((name, COUNTS[0]))
            bpy.ops.render.render()
            times.append(engine.last_timings["draw_ms"])
        if i:
            out[name] = times[0] - times[1]
    return out


def world_costs(scene, groups, frames: int) -> dict:
    """The Principled set's draw time under the black world and under the bundled forest world:
    with the split sum, and with the lobe sampled WORLD_SAMPLES times per pixel (round-robin in
    one process, medians: the world's cost is the difference to the black world's)."""
    import os

    import bpy
    import round_robin

    folder = bpy.utils.system_resource("DATAFILES", path="studiolights/world")
    world = bpy.data.worlds.new("Forest")
    world.use_nodes = True
    tree = world.node_tree
    environment = tree.nodes.new("ShaderNodeTexEnvironment")
    environment.image = bpy.data.images.load(os.path.join(folder, "forest.exr"), check_existing=True)
    tree.links.new(environment.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    black = scene.world
    props = scene.shading_lab
    props.term_set, props.world_occlusion = "PRINCIPLED", False
    round_robin.show_only(groups, COUNTS[0])

    def apply(samples):
        scene.world = black if samples < 0 else world
        props.world_specular = "SAMPLED" if samples > 0 else "SPLIT_SUM"
        props.world_samples = max(samples, 1)

    med = round_robin.median_draw_ms([-1, 0, *WORLD_SAMPLES], apply, frames)
    return {"lights": COUNTS[0], "black": round(med[-1], 2), "split_sum": round(med[0], 2),
            "sampled": {str(n): round(med[n], 2) for n in WORLD_SAMPLES}}


WORLD_LINE = "The world's specular"


def world_line(world: dict) -> str:
    return (f"{WORLD_LINE}, Principled set, {world['lights']} lights: the black world {world['black']:.1f} "
            f"ms; the forest world with the split sum {world['split_sum']:.1f} ms, sampled " + ", ".join(
                f"{n} per pixel {t:.1f} ms" for n, t in world["sampled"].items()) + ".")


def build(w: int, h: int):
    import bpy
    import round_robin

    scene = round_robin.empty_scene(w, h)
    world = bpy.data.worlds.new("Black")
    world.color = (0.0, 0.0, 0.0)
    if world.node_tree is not None:
        for node in world.node_tree.nodes:
            if node.bl_idname == "ShaderNodeBackground":
                node.inputs["Strength"].default_value = 0.0
    scene.world = world
    round_robin.ortho_camera(scene, VIEW)
    bpy.ops.mesh.primitive_plane_add(size=2 * VIEW)
    mat = bpy.data.materials.new("Rough metal")
    props = mat.shading_lab
    props.use_base_color, props.base_color = True, (0.95, 0.64, 0.54)
    props.use_metalness, props.metalness = True, 1.0
    props.use_roughness, props.roughness = True, 0.5
    bpy.context.active_object.data.materials.append(mat)
    groups = {}
    for n in COUNTS:
        objs = []
        for i in range(n):
            data = bpy.data.lights.new(f"L{n}_{i}", "POINT")
            data.energy, data.shadow_soft_size, data.use_shadow = 200.0 / n, 0.0, False
            obj = bpy.data.objects.new(data.name, data)
            obj.location = ((i % 8 - 3.5) * 0.8, (i // 8 - 1.5) * 1.0, 3.0)
            scene.collection.objects.link(obj)
            objs.append(obj)
        groups[n] = objs
    scene.shading_lab.model = "PBR"
    scene.shading_lab.shadows = False
    scene.shading_lab.light_culling = False  # every light reaches every tile: nothing to cull
    return scene, groups


def main() -> int:
    import round_robin

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolution", default="1280x720")
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--table", type=Path, default=ROOT / "docs" / "bench" / "term_costs.md")
    parser.add_argument("--out", type=Path, default=ROOT / "addon" / "plan" / "term_costs.json")
    parser.add_argument("--world-only", action="store_true",
                        help="measure the world's specular only; keep the candidates' times")
    args = parser.parse_args()
    w, h = (int(x) for x in args.resolution.split("x"))

    from addon.plan import auto_terms

    scene, groups = build(w, h)
    if args.world_only:
        data = json.loads(args.out.read_text())
        if data.get("pixels") != w * h:
            raise SystemExit(f"{args.out} was measured at {data.get('pixels')} pixels, not {w}x{h}")
        data["world_ms"] = world_costs(scene, groups, args.frames)
        args.out.write_text(json.dumps(data, indent=1) + "\n")
        old = args.table.read_text().split("\n") if args.table.exists() else []
        kept = [line for line in old if not line.startswith(WORLD_LINE)]
        while kept and not kept[-1]:
            kept.pop()
        round_robin.write_table(args.table, "\n".join([*kept, "", world_line(data["world_ms"]), ""]))
        return 0
    props = scene.shading_lab
    names = list(auto_terms.CANDIDATE_TERMS)
    configs = [(name, n) for n in COUNTS for name in names]

    def apply(config):
        name, n = config
        terms = auto_terms.CANDIDATE_TERMS[name]
        props.term_set = "PRINCIPLED" if terms.principled else "CUSTOM"
        props.fresnel, props.ndf, props.visibility, props.diffuse = (
            terms.fresnel, terms.ndf, terms.visibility, terms.diffuse)
        props.multiscatter = terms.multiscatter
        round_robin.show_only(groups, n)

    med = round_robin.median_draw_ms(configs, apply, args.frames)
    draw_ms = {name: [round(med[(name, n)], 2) for n in COUNTS] for name in names}
    first_use = first_use_ms(names, apply)
    world = world_costs(scene, groups, args.frames)
    data = {
        "generated_by": "scripts/term_costs.py",
        "scene": f"plane filling an orthographic view, rough metal, N point lights reaching all of it, "
                 f"no shadows, black world, {w}x{h}, median of {args.frames} rounds",
        "lights": list(COUNTS),
        "pixels": w * h,
        "draw_ms": draw_ms,
        "relative": derive(draw_ms),
        "first_use_ms": round(statistics.median(first_use.values()), 1),
        "world_ms": world,
    }
    args.out.write_text(json.dumps(data, indent=1) + "\n")
    rows = ["| candidate | " + " | ".join(f"{n} light(s) ms (x default)" for n in COUNTS) + " |",
            "|---|" + "---:|" * len(COUNTS)]
    for name in names:
        cells = [f"{t:.1f} ({r:.3f}x)" for t, r in zip(draw_ms[name], data["relative"][name])]
        rows.append(f"| {auto_terms.LABELS[name]} | " + " | ".join(cells) + " |")
    order = {n: auto_terms.candidate_order(n, data) for n in COUNTS}
    text = "\n".join([
        "The Auto term set's candidates: draw time per light count (`scripts/term_costs.py`; "
        f"{data['scene']}). Written to `addon/plan/term_costs.json`, which orders the candidates.",
        "", *rows, "",
        f"A candidate's program's first use (compile and first draw, the driver's shader cache warm), "
        f"median of {len(first_use)}: {data['first_use_ms']:.1f} ms "
        f"({', '.join(f'{auto_terms.LABELS[n]} {t:.0f}' for n, t in first_use.items())}).", "",
        *[f"Order at {n} light(s), cheap -> accurate: " + " -> ".join(order[n]) for n in COUNTS], "",
        world_line(world), ""])
    round_robin.write_table(args.table, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
