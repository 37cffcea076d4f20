"""Transparency layers: frame time and error against the number of depth-peeling layers.

The scene: five partly transparent spheres (coverage 0.5, each a different colour) in a row along
the view, so a pixel can look through up to ten transparent surfaces, over an opaque floor; a sun
and a point light; physically based model. For 1, 2, 3, 4, 6, 8, 10 and 16 layers, and for the same
scene with every sphere opaque (what transparency costs): the median draw time (round-robin after
a warm-up round) and the error of each image against 16 layers (exact here: no pixel has more than
ten layers) and against a Cycles render (``--reference-samples``, direct light, shadows off: the
same light transport; Cycles' stochastic transparency adds its noise). Writes transparency.md and
transparency.png.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

from .harness import engines, page, plots, scenes, standard, timing

PAGE = "transparency.md"
QUICK = dict(resolution="160x90", frames=1, reference_samples=16)
LAYERS = (1, 2, 3, 4, 6, 8, 10, 16)
COLOURS = ((0.9, 0.2, 0.1), (0.9, 0.7, 0.1), (0.2, 0.8, 0.2), (0.1, 0.4, 0.9), (0.7, 0.2, 0.8))
#: (label, layers, the spheres' coverage)
CONFIGS = (("opaque spheres", 1, 1.0), *((f"{n} layers", n, 0.5) for n in LAYERS))


def options(parser) -> None:
    standard(parser, resolution="640x360", frames=5, reference_samples=256)


def build(size: tuple[int, int]):
    import bpy

    from addon.blender.scene_builder import principled_material

    scene = scenes.empty(size)
    scene.shading_lab.model = "PBR"
    scenes.black_world(scene)
    scenes.camera(scene, (0.0, -7.0, 1.6), (84.0, 0.0, 0.0))
    spheres = []
    for i, colour in enumerate(COLOURS):
        bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.8,
                                             location=(0.3 * i - 0.6, 1.4 * i - 2.8, 0.9))
        obj = bpy.context.active_object
        bpy.ops.object.shade_smooth()
        spheres.append(principled_material(f"Glass {i}", colour, roughness=0.3))
        obj.data.materials.append(spheres[-1])
    bpy.ops.mesh.primitive_plane_add(size=20.0)
    bpy.context.active_object.data.materials.append(principled_material("Floor", (0.5, 0.5, 0.5)))
    scenes.light(scene, "Sun", "SUN", rotation=(math.radians(40.0), 0.0, math.radians(-30.0)), energy=3.0)
    scenes.light(scene, "Lamp", "POINT", (-3.0, -4.0, 4.0), energy=800.0, shadow_soft_size=0.0)
    return scene, spheres


def set_alpha(materials, alpha: float) -> None:
    for material in materials:
        node = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        node.inputs["Alpha"].default_value = alpha


def figure(path: Path, images: dict, cycles, rows, base: float) -> None:
    plt = plots.pyplot()
    peeled = [r for r in rows if r[2] < 1.0]
    fig = plt.figure(figsize=(10, 5.2), dpi=100)
    grid = fig.add_gridspec(2, 10, height_ratios=(1.0, 1.6))
    shown = [("1 layers", "1 layer"), ("2 layers", "2 layers"), ("4 layers", "4 layers"),
             (f"{LAYERS[-1]} layers", f"{LAYERS[-1]} layers")]
    for i, (key, title) in enumerate(shown + [(None, "Cycles")]):
        plots.image_panel(fig.add_subplot(grid[0, 2 * i:2 * i + 2]),
                          plots.display(images[key] if key is not None else cycles), title,
                          interpolation="nearest")
    ax_t = fig.add_subplot(grid[1, 0:5])
    ax_t.plot([r[1] for r in peeled], [r[3] for r in peeled], "o-", label="transparent spheres")
    ax_t.axhline(base, color="grey", ls="--", label="opaque spheres")
    ax_t.set_xlabel("transparency layers")
    ax_t.set_ylabel("draw + read-back ms (median)")
    ax_t.legend(fontsize=8)
    ax_e = fig.add_subplot(grid[1, 5:10])
    layers = [r[1] for r in peeled]
    ax_e.semilogy(layers, [max(r[5], 1e-6) for r in peeled], "o-", label="max |image − 16 layers|")
    ax_e.semilogy(layers, [r[6] for r in peeled], "s-", label="mean |image − Cycles|")
    ax_e.set_xlabel("transparency layers")
    ax_e.legend(fontsize=8)
    fig.tight_layout()
    plots.save(fig, path)


def run(ctx) -> None:
    import numpy as np

    args = ctx.args
    scene, spheres = build(args.resolution)
    images: dict[str, np.ndarray] = {}

    def render(config, tmp):
        label, layers, alpha = config
        set_alpha(spheres, alpha)
        scene.shading_lab.transparency_layers = layers
        if label not in images:  # the warm-up round: its image
            images[label] = engines.image(scene, tmp / f"{layers}-{alpha}.exr")[0][..., :3]
            return {}
        return timing.render_timed(scene)

    with tempfile.TemporaryDirectory() as tmp:
        med = timing.round_robin(CONFIGS, args.frames, lambda c: render(c, Path(tmp)), ctx.progress)
    set_alpha(spheres, 0.5)
    cycles, cached = engines.cycles(scene, args.reference_samples)
    cycles = cycles[..., :3]
    exact = images[f"{LAYERS[-1]} layers"]
    base = med[0]["draw_ms"]
    rows = [(label, layers, alpha, m["draw_ms"], m["draw_ms"] / base,
             np.abs(images[label] - exact).max() if alpha < 1.0 else float("nan"),
             np.abs(images[label] - cycles).mean()) for (label, layers, alpha), m in zip(CONFIGS, med)]
    figure(ctx.out / "transparency.png", images, cycles, rows, base)
    ctx.page("Transparency layers", [
        f"Scene: five coverage-0.5 spheres in a row along the view over an opaque floor, "
        f"{page.res(args.resolution)}, physically based; draw + read-back ms, median of {args.frames} "
        f"(one warm-up); Cycles {args.reference_samples} samples{' (cached)' if cached else ''}.", "",
        *page.table(["configuration", "draw ms", "vs opaque", "max abs error vs 16 layers",
                     "mean abs error vs Cycles"],
                    [[label, f"{ms:.1f}", f"{ratio:.2f}×", "—" if alpha >= 1.0 else f"{vs_exact:.4f}",
                      f"{vs_cycles:.4f}"] for label, _, alpha, ms, ratio, vs_exact, vs_cycles in rows])])
