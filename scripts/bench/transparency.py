"""Transparency layers: frame time and error against the number of depth-peeling layers.

    .venv/bin/python scripts/transparency.py [--resolution 640x360] [--frames 5] [--out docs/bench]

The scene: five partly transparent spheres (coverage 0.5, each a different colour) in a row along
the view, so a pixel can look through up to ten transparent surfaces, over an opaque floor; a sun
and a point light; physically based model. For 1, 2, 3, 4, 6, 8, 10 and 16 layers, and for the same
scene with every sphere opaque (what transparency costs), it prints the median frame time (models
interleaved round by round, one warm-up round) and the error of each image against 16 layers
(exact here: no pixel has more than ten layers) and against a Cycles render (256 samples, direct
light, shadows off: the same light transport; Cycles' stochastic transparency adds its noise).
Writes transparency.md and transparency.png under --out. CPU-rasteriser times (Mesa llvmpipe):
compare them as ratios within one run.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]

LAYERS = (1, 2, 3, 4, 6, 8, 10, 16)
COLOURS = ((0.9, 0.2, 0.1), (0.9, 0.7, 0.1), (0.2, 0.8, 0.2), (0.1, 0.4, 0.9), (0.7, 0.2, 0.8))


def build(scene):
    import bpy

    from addon.blender.scene_builder import principled_material

    scene.render.engine = "SHADING_LAB"
    scene.shading_lab.model = "PBR"
    world = bpy.data.worlds.new("Black")
    for node in (world.node_tree.nodes if world.node_tree is not None else []):
        if node.bl_idname == "ShaderNodeBackground":
            node.inputs["Strength"].default_value = 0.0
    world.color = (0.0, 0.0, 0.0)
    scene.world = world
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    cam.location = (0.0, -7.0, 1.6)
    cam.rotation_euler = (math.radians(84.0), 0.0, 0.0)
    scene.camera = cam
    spheres = []
    for i, colour in enumerate(COLOURS):
        bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.8,
                                             location=(0.3 * i - 0.6, 1.4 * i - 2.8, 0.9))
        obj = bpy.context.active_object
        bpy.ops.object.shade_smooth()
        material = principled_material(f"Glass {i}", colour, roughness=0.3)
        obj.data.materials.append(material)
        spheres.append(material)
    bpy.ops.mesh.primitive_plane_add(size=20.0)
    bpy.context.active_object.data.materials.append(principled_material("Floor", (0.5, 0.5, 0.5)))
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (math.radians(40.0), 0.0, math.radians(-30.0))
    lamp = bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", "POINT"))
    lamp.data.energy, lamp.data.shadow_soft_size = 800.0, 0.0
    lamp.location = (-3.0, -4.0, 4.0)
    for obj in (sun, lamp):
        scene.collection.objects.link(obj)
    return spheres


def set_alpha(materials, alpha: float) -> None:
    for material in materials:
        node = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        node.inputs["Alpha"].default_value = alpha


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolution", default="640x360")
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--reference-samples", type=int, default=256)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "bench")
    args = parser.parse_args()
    w, h = (int(x) for x in args.resolution.split("x"))

    import bpy
    import demo_scene
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    import reference

    from addon.blender import engine

    scene = demo_scene.empty_scene(w, h)
    spheres = build(scene)
    tmp = Path(tempfile.mkdtemp(prefix="shading_lab_transparency_"))

    # configurations: (label, layers, sphere coverage)
    configs = [("opaque spheres", 1, 1.0)] + [(f"{n} layers", n, 0.5) for n in LAYERS]
    times: dict[str, list[float]] = {label: [] for label, _, _ in configs}
    images: dict[str, np.ndarray] = {}
    for round_ in range(args.frames + 1):
        k = round_ % len(configs)
        for label, layers, alpha in configs[k:] + configs[:k]:
            set_alpha(spheres, alpha)
            scene.shading_lab.transparency_layers = layers
            if label not in images:  # the first render of each: its image (and the warm-up)
                images[label] = reference.render_to_array(scene, tmp / f"{layers}-{alpha}.exr")[..., :3]
                continue
            engine.last_timings.clear()
            bpy.ops.render.render()
            if not engine.last_timings:
                print("error: the render failed (see the console)", file=sys.stderr)
                return 1
            times[label].append(engine.last_timings["draw_ms"])
        print(f"round {round_}/{args.frames} done", file=sys.stderr)

    set_alpha(spheres, 0.5)
    cycles, cached = reference.render_reference(scene, samples=args.reference_samples)
    cycles = cycles[..., :3]
    exact = images[f"{LAYERS[-1]} layers"]
    base = statistics.median(times["opaque spheres"])
    rows = []
    for label, layers, alpha in configs:
        med = statistics.median(times[label])
        image = images[label]
        vs_exact = np.abs(image - exact).max() if alpha < 1.0 else float("nan")
        vs_cycles = np.abs(image - cycles).mean()
        rows.append((label, layers, alpha, med, med / base, vs_exact, vs_cycles))

    lines = [f"Scene: five coverage-0.5 spheres in a row along the view over an opaque floor, {w}x{h}, "
             f"physically based; draw + read-back ms, median of {args.frames} (one warm-up); Cycles "
             f"{args.reference_samples} samples{' (cached)' if cached else ''}.", "",
             "| configuration | draw ms | vs opaque | max abs error vs 16 layers "
             "| mean abs error vs Cycles |",
             "|---|---:|---:|---:|---:|"]
    for label, _, alpha, med, ratio, vs_exact, vs_cycles in rows:
        exact_text = "—" if alpha >= 1.0 else f"{vs_exact:.4f}"
        lines.append(f"| {label} | {med:.1f} | {ratio:.2f}× | {exact_text} | {vs_cycles:.4f} |")
    text = "\n".join(lines)
    print("\n" + text)
    args.out.mkdir(parents=True, exist_ok=True)
    header = "# Transparency layers\n\nWritten by `scripts/transparency.py`.\n\n"
    (args.out / "transparency.md").write_text(header + text + "\n")

    peeled = [r for r in rows if r[2] < 1.0]
    fig = plt.figure(figsize=(10, 5.2), dpi=100)
    grid = fig.add_gridspec(2, 10, height_ratios=(1.0, 1.6))
    shown = [("1 layers", "1 layer"), ("2 layers", "2 layers"), ("4 layers", "4 layers"),
             (f"{LAYERS[-1]} layers", f"{LAYERS[-1]} layers")]
    for i, (key, title) in enumerate(shown + [(None, "Cycles")]):
        ax = fig.add_subplot(grid[0, 2 * i:2 * i + 2])
        image = images[key] if key is not None else cycles
        ax.imshow(np.clip(image, 0.0, 1.0) ** (1 / 2.2), interpolation="nearest")
        ax.set_title(title, fontsize=8)
        ax.set_xticks([])
        ax.set_yticks([])
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
    fig.savefig(args.out / "transparency.png")
    print(f"wrote {args.out / 'transparency.md'} and {args.out / 'transparency.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
