"""The Auto term set's cost table: each candidate term set's frame time against the default
terms', per light count, measured here.

A plane fills an orthographic view under N point lights that each reach all of it (N = 2, 8, 32;
no shadows, a black world: the shading is all the frame does), with a rough metal material.
Every (candidate, N) is rendered round-robin after a warm-up round, in one process; the medians
of the engine's draw time (GPU work fenced by the read-back) go to ``--json`` (default
``addon/plan/term_costs.json`` when the page goes to docs/bench, else beside the page) with their
ratios to the default terms (``relative``), which ``addon/plan/auto_terms.py`` orders its
candidates by, with the view's pixel count and a candidate program's first use (``first_use_ms``:
its compile and first draw, the driver's shader cache warm), which it weighs a program of its own
against. Then the world's specular (``world_ms``): the same plane under Blender's bundled forest
world instead of the black one (2 lights, world occlusion off), the Principled set with the split
sum and with the lobe sampled 16 and 64 times per pixel, which Auto weighs the split sum against
where a scene samples its world (``--world-only`` measures that alone and replaces it in the JSON
and the page, the candidates' times kept). The add-on uses these times only against each other.
"""

from __future__ import annotations

import json
import statistics
from pathlib import Path

from .harness import ROOT, page, scenes, standard, timing

PAGE = "term_costs.md"
COSTS = ROOT / "addon" / "plan" / "term_costs.json"
QUICK = dict(resolution="160x90", frames=1)
COUNTS = (2, 8, 32)
#: Per-pixel world samples the sampled world specular is measured at.
WORLD_SAMPLES = (16, 64)
VIEW = 8.0  # the view's width (m)


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=5)
    parser.add_argument("--json", type=Path, default=None,
                        help="the cost table written (default addon/plan/term_costs.json, or beside "
                             "the page)")
    parser.add_argument("--world-only", action="store_true",
                        help="measure the world's specular only; keep the candidates' times")


def derive(draw_ms: dict[str, list[float]]) -> dict[str, list[float]]:
    """Each candidate's draw time over the default terms' at the same light count (4 decimals)."""
    base = draw_ms["DEFAULT"]
    return {name: [round(t / b, 4) for t, b in zip(times, base)] for name, times in draw_ms.items()}


def first_use_ms(names, apply) -> dict[str, float]:
    """Per candidate but the first, what its shading program's first use adds to a frame (its
    compile and first draw, with the driver's shader cache warm: every program was compiled
    before), at the first light count: the program library is emptied, the first candidate drawn
    (the frame's other programs and the tables come back), then each other one twice."""
    from addon.frame import gpu_library

    gpu_library.LIBRARY.clear()
    out = {}
    for i, name in enumerate(names):
        apply((name, COUNTS[0]))
        first, second = (timing.render_timed()["draw_ms"] for _ in range(2))
        if i:
            out[name] = first - second
    return out


def world_costs(scene, groups, frames: int, progress) -> dict:
    """The Principled set's draw time under the black world and under the bundled forest world:
    with the split sum, and with the lobe sampled WORLD_SAMPLES times per pixel (round-robin in
    one process, medians: the world's cost is the difference to the black world's)."""
    import os

    import bpy

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
    scenes.show_only(groups, COUNTS[0])

    def apply(samples):
        scene.world = black if samples < 0 else world
        props.world_specular = "SAMPLED" if samples > 0 else "SPLIT_SUM"
        props.world_samples = max(samples, 1)

    med = timing.median_ms([-1, 0, *WORLD_SAMPLES], apply, frames, progress, "world")
    return {"lights": COUNTS[0], "black": round(med[-1], 2), "split_sum": round(med[0], 2),
            "sampled": {str(n): round(med[n], 2) for n in WORLD_SAMPLES}}


def build(size: tuple[int, int]):
    import bpy

    scene = scenes.empty(size)
    scenes.black_world(scene)
    scenes.camera(scene, (0.0, 0.0, 5.0), ortho=VIEW)
    bpy.ops.mesh.primitive_plane_add(size=2 * VIEW)
    mat = bpy.data.materials.new("Rough metal")
    props = mat.shading_lab
    props.use_base_color, props.base_color = True, (0.95, 0.64, 0.54)
    props.use_metalness, props.metalness = True, 1.0
    props.use_roughness, props.roughness = True, 0.5
    bpy.context.active_object.data.materials.append(mat)
    groups = {n: [scenes.light(scene, f"L{n}_{i}", "POINT", ((i % 8 - 3.5) * 0.8, (i // 8 - 1.5) * 1.0, 3.0),
                               energy=200.0 / n, shadow_soft_size=0.0, use_shadow=False) for i in range(n)]
              for n in COUNTS}
    scene.shading_lab.model = "PBR"
    scene.shading_lab.shadows = False
    scene.shading_lab.light_culling = False  # every light reaches every tile: nothing to cull
    return scene, groups


def measure(scene, groups, args, progress) -> dict:
    """The cost table: every candidate's draw time per light count, first use, the world."""
    from addon.plan import auto_terms

    props = scene.shading_lab
    names = list(auto_terms.CANDIDATE_TERMS)

    def apply(config):
        name, n = config
        terms = auto_terms.CANDIDATE_TERMS[name]
        props.term_set = "PRINCIPLED" if terms.principled else "CUSTOM"
        props.fresnel, props.ndf, props.visibility, props.diffuse = (
            terms.fresnel, terms.ndf, terms.visibility, terms.diffuse)
        props.multiscatter = terms.multiscatter
        scenes.show_only(groups, n)

    med = timing.median_ms([(name, n) for n in COUNTS for name in names], apply, args.frames, progress,
                           "candidates")
    draw_ms = {name: [round(med[(name, n)], 2) for n in COUNTS] for name in names}
    first_use = first_use_ms(names, apply)
    w, h = args.resolution
    return {
        "generated_by": "scripts/bench/term_costs.py",
        "scene": f"plane filling an orthographic view, rough metal, N point lights reaching all of it, "
                 f"no shadows, black world, {w}x{h}, median of {args.frames} rounds",
        "lights": list(COUNTS),
        "pixels": w * h,
        "draw_ms": draw_ms,
        "relative": derive(draw_ms),
        "first_use_ms": round(statistics.median(first_use.values()), 1),
        "first_use_each_ms": {name: round(ms, 1) for name, ms in first_use.items()},
        "world_ms": world_costs(scene, groups, args.frames, progress),
    }


def world_line(world: dict) -> str:
    sampled = ", ".join(f"{n} per pixel {t:.1f} ms" for n, t in world["sampled"].items())
    return (f"The world's specular, Principled set, {world['lights']} lights: the black world "
            f"{world['black']:.1f} ms; the forest world with the split sum {world['split_sum']:.1f} ms, "
            f"sampled {sampled}.")


def report(data: dict) -> list[str]:
    """The page's body, from the cost table alone."""
    from addon.plan import auto_terms

    rows = [[auto_terms.LABELS[name], *(f"{t:.1f} ({r:.3f}x)" for t, r in zip(times, data["relative"][name]))]
            for name, times in data["draw_ms"].items()]
    each = data.get("first_use_each_ms", {})
    order = {n: auto_terms.candidate_order(n, data) for n in data["lights"]}
    return [f"The Auto term set's candidates: draw time per light count ({data['scene']}). Written to "
            "`addon/plan/term_costs.json`, which orders the candidates.", "",
            *page.table(["candidate", *(f"{n} light(s) ms (x default)" for n in data["lights"])], rows), "",
            "A candidate's program's first use (compile and first draw, the driver's shader cache warm), "
            f"median{f' of {len(each)}' if each else ''}: {data['first_use_ms']:.1f} ms"
            + (f" ({', '.join(f'{auto_terms.LABELS[n]} {t:.0f}' for n, t in each.items())})" if each else "")
            + ".", "",
            *[f"Order at {n} light(s), cheap -> accurate: " + " -> ".join(order[n])
              for n in data["lights"]], "",
            world_line(data["world_ms"])]


def run(ctx) -> None:
    args = ctx.args
    path = args.json or ctx.path(COSTS)
    scene, groups = build(args.resolution)
    if args.world_only:
        data = json.loads((path if path.exists() else COSTS).read_text())
        if data.get("pixels") != args.resolution[0] * args.resolution[1]:
            raise ValueError(f"{path} was measured at {data.get('pixels')} pixels, not "
                             f"{page.res(args.resolution)}")
        data["world_ms"] = world_costs(scene, groups, args.frames, ctx.progress)
    else:
        data = measure(scene, groups, args, ctx.progress)
    page.write(path, json.dumps(data, indent=1) + "\n")
    ctx.page("The Auto term set's cost table", report(data))
