"""Materials: what a compiled node graph costs against the constant path, what compiling costs
as graphs grow, a file of many materials of a few structures, and the error against Cycles with
EEVEE beside.

(1) A grid of spheres under a sun and a point light (the Principled term set), each sphere's
material either a plain Principled BSDF (the constant path) or the same values given by a Value
and an RGB node (a compiled graph that computes what the constant path reads), or a graph that
sweeps base colour, roughness and metallic over the UVs; rendered round-robin in one process
after a warm-up (draw + read-back ms, medians). (2) Compile time against node count: a chain of
N Math nodes into Roughness, read from Blender, flattened and written as GLSL (the Python side,
median of several), and the shading program's GPU compile (the first render against the
second). (3) ``--materials`` materials of ten structures (a chain of 1 to 10 Math nodes, each
material its own values) on as many spheres: the programs compiled by the first render and its
time against the second's.
"""

from __future__ import annotations

import math
import statistics
import time

from .harness import page, scenes, standard, timing

PAGE = "materials.md"
QUICK = dict(resolution="160x90", frames=1, materials=30)
STRUCTURES = 10
#: Chain lengths timed, none of the many-materials file's (1 to 10): each compiles its own program.
CHAINS = (15, 30, 60, 120)


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=5)
    parser.add_argument("--materials", type=int, default=300,
                        help="materials (of ten structures) in the many-materials file (default 300)")


def _principled(name: str, base, roughness: float, metallic: float):
    import bpy

    mat = bpy.data.materials.new(name)
    tree = mat.node_tree
    if tree is None:
        mat.use_nodes = True
        tree = mat.node_tree
    bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*base, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    return mat, tree, bsdf


def _valued(name: str, base, roughness: float, metallic: float):
    """The same inputs through an RGB and two Value nodes: compiled, computing what the constant
    path reads."""
    mat, tree, bsdf = _principled(name, base, roughness, metallic)
    rgb = tree.nodes.new("ShaderNodeRGB")
    rgb.outputs[0].default_value = (*base, 1.0)
    tree.links.new(rgb.outputs[0], bsdf.inputs["Base Color"])
    for socket, value in (("Roughness", roughness), ("Metallic", metallic)):
        node = tree.nodes.new("ShaderNodeValue")
        node.outputs[0].default_value = value
        tree.links.new(node.outputs[0], bsdf.inputs[socket])
    return mat


def _swept(name: str):
    """Base colour mixed across u, roughness = v, metallic where u > 1/2."""
    mat, tree, bsdf = _principled(name, (0.8, 0.8, 0.8), 0.5, 0.0)
    coord, sep = tree.nodes.new("ShaderNodeTexCoord"), tree.nodes.new("ShaderNodeSeparateXYZ")
    tree.links.new(coord.outputs["UV"], sep.inputs[0])
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    tree.links.new(sep.outputs[0], mix.inputs[0])
    mix.inputs[6].default_value, mix.inputs[7].default_value = (0.9, 0.1, 0.1, 1.0), (0.1, 0.2, 0.9, 1.0)
    tree.links.new(mix.outputs[2], bsdf.inputs["Base Color"])
    tree.links.new(sep.outputs[1], bsdf.inputs["Roughness"])
    step = tree.nodes.new("ShaderNodeMath")
    step.operation = "GREATER_THAN"
    tree.links.new(sep.outputs[0], step.inputs[0])
    tree.links.new(step.outputs[0], bsdf.inputs["Metallic"])
    return mat


def _chain(name: str, length: int, offset: float = 0.0):
    """A chain of ``length`` Math nodes (alternating Multiply and Add, values from ``offset``) into
    Roughness: one structure per length."""
    mat, tree, bsdf = _principled(name, (0.7, 0.5, 0.3), 0.5, 0.0)
    value = tree.nodes.new("ShaderNodeValue")
    value.outputs[0].default_value = 0.5
    socket = value.outputs[0]
    for i in range(length):
        node = tree.nodes.new("ShaderNodeMath")
        node.operation = "MULTIPLY" if i % 2 == 0 else "ADD"
        node.inputs[1].default_value = 1.0 if i % 2 == 0 else offset / max(length, 1)
        tree.links.new(socket, node.inputs[0])
        socket = node.outputs[0]
    tree.links.new(socket, bsdf.inputs["Roughness"])
    return mat


def _spheres(scene, count: int, spacing: float = 1.0) -> list:
    import bpy

    side = math.ceil(math.sqrt(count))
    objs = []
    for i in range(count):
        bpy.ops.mesh.primitive_uv_sphere_add(segments=24, ring_count=12, radius=0.45,
                                             location=((i % side - (side - 1) / 2) * spacing,
                                                       (i // side - (side - 1) / 2) * spacing, 0.0))
        bpy.ops.object.shade_smooth()
        objs.append(bpy.context.active_object)
    return objs


def _lit(size, view: float):
    scene = scenes.empty(size)
    scene.shading_lab.model = "PBR"
    scene.shading_lab.term_set = "PRINCIPLED"
    scenes.camera(scene, (0.0, 0.0, 10.0), ortho=view)
    scenes.light(scene, "Sun", "SUN", rotation=(math.radians(30.0), math.radians(-20.0), 0.0),
                 energy=3.0, angle=0.0, use_shadow=False)
    scenes.light(scene, "Point", "POINT", (2.0, 1.5, 4.0), energy=800.0, shadow_soft_size=0.0,
                 use_shadow=False)
    return scene


def _frame_cost(args, ctx) -> list[str]:
    scene = _lit(args.resolution, 6.0)
    objs = _spheres(scene, 25, 1.1)
    rng_values = [((0.2 + 0.6 * (i % 5) / 4, 0.3, 0.8 - 0.6 * (i // 5) / 4), 0.2 + 0.03 * i, (i % 3) / 2.0)
                  for i in range(len(objs))]
    sets = {
        "constant": [_principled(f"Plain{i}", *v)[0] for i, v in enumerate(rng_values)],
        "graph, same values": [_valued(f"Valued{i}", *v) for i, v in enumerate(rng_values)],
        "graph, UV-swept": [_swept(f"Swept{i}") for i in range(len(objs))],
    }

    def apply(config):
        for obj, mat in zip(objs, sets[config]):
            obj.data.materials.clear()
            obj.data.materials.append(mat)

    med = timing.median_ms(list(sets), apply, args.frames, ctx.progress, "materials")
    rows = [[name, f"{ms:.1f}", f"{ms / med['constant']:.2f}x"] for name, ms in med.items()]
    return ["### Frame time: compiled graph against the constant path", "",
            f"{page.res(args.resolution)}: 25 spheres (1,152 triangles each) under a sun and a point "
            "light, Principled term set, shadows off; each configuration's 25 materials; "
            f"{args.frames} frames per configuration after a warm-up, round-robin; draw + read-back ms, "
            "medians.", "", *page.table(["materials", "ms", "vs constant"], rows), ""]


def _compile_cost(args, ctx) -> list[str]:
    from addon.blender import nodes
    from addon.frame import gpu_library
    from addon.materials import surface

    rows = []
    for length in CHAINS:
        scene = _lit(args.resolution, 2.0)
        obj = _spheres(scene, 1)[0]
        mat = _chain(f"Chain{length}", length)
        obj.data.materials.append(mat)
        python = []
        for _ in range(5):
            start = time.perf_counter()
            surface.compile_material(*nodes.read_material(mat))
            python.append(1e3 * (time.perf_counter() - start))
        compiles = gpu_library.LIBRARY.compiles
        first = timing.render_timed(scene)["wall_ms"]
        second = timing.render_timed(scene)["wall_ms"]
        ctx.progress.step(f"compile {length}")
        rows.append([str(length + 1), f"{statistics.median(python):.2f}",
                     str(gpu_library.LIBRARY.compiles - compiles), f"{first - second:.0f}"])
    return ["### Compile time against node count", "",
            "A Value node and a chain of Math nodes into Roughness: read from Blender, flattened and "
            "written as GLSL (Python, median of 5), and the first render's extra wall time over the "
            "second's (the programs it compiles, Mesa's shader cache as this machine has it).", "",
            *page.table(["nodes", "read + compile ms", "programs compiled", "first render extra ms"], rows),
            ""]


def _many(args, ctx) -> list[str]:
    from addon.frame import gpu_library

    count = args.materials
    scene = _lit(args.resolution, 1.1 * math.ceil(math.sqrt(count)))
    objs = _spheres(scene, count, 1.1)
    for i, obj in enumerate(objs):
        obj.data.materials.append(_chain(f"M{i}", 1 + i % STRUCTURES, offset=i / count))
    compiles = gpu_library.LIBRARY.compiles
    first = timing.render_timed(scene)
    compiled = gpu_library.LIBRARY.compiles - compiles
    second = timing.render_timed(scene)
    ctx.progress.step("many materials")
    return ["### A file of many materials", "",
            f"{count} spheres, each its own material of {STRUCTURES} structures (a chain of 1 to "
            f"{STRUCTURES} Math nodes into Roughness, each material its own values).", "",
            *page.table(["materials", "structures", "programs compiled", "first render ms",
                         "second render ms"],
                        [[str(count), str(STRUCTURES), str(compiled), f"{first['wall_ms']:.0f}",
                          f"{second['wall_ms']:.0f}"]]), ""]


def _normal_mapped(name: str):
    """A tangent-space Normal Map of a constant tilted colour into Normal, and Base Color from a
    Color Ramp over u (a compiled graph with a bent normal)."""
    mat, tree, bsdf = _principled(name, (0.7, 0.6, 0.5), 0.5, 0.0)
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    normal_map.inputs["Color"].default_value = (0.75, 0.6, 0.85, 1.0)
    tree.links.new(normal_map.outputs["Normal"], bsdf.inputs["Normal"])
    coord, sep = tree.nodes.new("ShaderNodeTexCoord"), tree.nodes.new("ShaderNodeSeparateXYZ")
    tree.links.new(coord.outputs["UV"], sep.inputs[0])
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (0.8, 0.2, 0.1, 1.0)
    ramp.color_ramp.elements[1].color = (0.1, 0.3, 0.8, 1.0)
    tree.links.new(sep.outputs[0], ramp.inputs[0])
    tree.links.new(ramp.outputs[0], bsdf.inputs["Base Color"])
    return mat


def _masked(name: str):
    """The swept material with Alpha = (u < 0.3): an alpha mask (half the visible side cut away)."""
    mat = _swept(name)
    tree = mat.node_tree
    bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    sep = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeSeparateXYZ")
    step = tree.nodes.new("ShaderNodeMath")
    step.operation = "LESS_THAN"
    tree.links.new(sep.outputs[0], step.inputs[0])
    step.inputs[1].default_value = 0.3
    tree.links.new(step.outputs[0], bsdf.inputs["Alpha"])
    return mat


ERROR_SCENES = {"UV-swept Principled inputs": _swept, "normal map and ramp": _normal_mapped,
                "alpha mask": _masked}


def _error(args, ctx) -> list[str]:
    """Each scene rendered by us, EEVEE (16 samples) and Cycles (direct light): FLIP and mean
    relative error of the lit pixels against Cycles."""
    import tempfile
    from pathlib import Path

    import bpy
    import numpy as np
    from metrics import flip_error

    from .harness import engines

    rows = []
    folder = Path(tempfile.mkdtemp(prefix="materials-"))
    for label, make in ERROR_SCENES.items():
        scene = _lit(args.resolution, 2.4)
        scenes.black_world(scene)  # the materials, not the world's occlusion
        obj = _spheres(scene, 1)[0]
        obj.data.materials.append(make(label))
        bpy.ops.mesh.primitive_plane_add(size=6.0, location=(0.0, 0.0, -1.0))
        ground, _, _ = _principled("Ground", (0.5, 0.5, 0.5), 0.6, 0.0)
        bpy.context.active_object.data.materials.append(ground)
        ref, _ = engines.cycles(scene, 64, cache=False)
        row = [label]
        for peer in (None, "eevee-16"):
            image, _ = engines.image(scene, folder / f"{len(rows)}_{peer or 'ours'}.exr", peer)
            ours, cyc = image[..., :3].astype(np.float64), ref[..., :3].astype(np.float64)
            lit = cyc.max(-1) > 0.02 * cyc.max()
            rel = np.abs(ours - cyc).max(-1)[lit] / cyc.max(-1)[lit]
            row += [f"{flip_error(cyc, ours)[0]:.4f}", f"{rel.mean():.2%}"]
        rows.append(row)
        ctx.progress.step(f"error {label}")
    return ["### Error against Cycles, EEVEE beside", "",
            "A sphere (shading its UVs as above) over a grey ground, the two lights (shadows off), a "
            "black world, Cycles direct light at 64 samples as the reference, EEVEE at 16 samples: "
            "mean HDR-FLIP and mean relative error of the lit pixels.", "",
            *page.table(["scene", "Shading Lab FLIP", "Shading Lab mean", "EEVEE FLIP", "EEVEE mean"],
                        rows), ""]


def run(ctx) -> None:
    args = ctx.args
    ctx.progress.expect(len(CHAINS) + 1 + len(ERROR_SCENES))
    lines = _frame_cost(args, ctx) + _compile_cost(args, ctx) + _many(args, ctx) + _error(args, ctx)
    ctx.page("Materials", [
        "Compiled node graphs (addon/materials/) against the constant path, the cost of compiling, "
        "and many materials of a few structures.", "", *lines])
