"""Every model and term variant: frame time and error against Cycles, the peers (EEVEE,
Workbench), and how the frame time scales.

For each preset, every configuration (Blinn-Phong, Phong, and the physically based model with its
default terms, each Fresnel, Beckmann, each masking-shadowing, each diffuse, multiple scattering,
the Principled set and Auto at three bounds) is rendered in the same process, round-robin (one
warm-up round, then ``--frames`` timed rounds, the order rotated each round) so that machine noise
hits them alike. Frame times are the engine's own phase times (``engine.last_timings``; GPU work is
fenced by the read-back inside ``draw_ms``) plus the wall time of ``bpy.ops.render.render``. Errors
are against the Cycles reference (cached on disk) at ``--reference-resolution``: every image
compared is rendered at that resolution, and the peers are timed there too, next to Shading Lab in
the same rounds. Then: frame time against the number of point lights and the number of triangles,
extraction time against triangles, and the draw time of the scene's specialised program against
one generic program (every light kind compiled in, 64 light slots). Writes ``bench.md``,
``pareto.png`` (time against FLIP) and ``scaling.png``; ``--quick``: one preset, fewer variants.
"""

from __future__ import annotations

import dataclasses
import math
import statistics
import tempfile
import time
from pathlib import Path

import render as cli

from addon.blender.geometry import MEMO_CORNERS
from addon.scene.snapshot import LIGHT_KINDS, TERM_CHOICES

from .harness import engines, page, plots, scenes, shipped_presets, size, standard, timing

PAGE = "bench.md"
QUICK = dict(presets="long_tail", resolution="320x180", frames=1, peer_frames=1, reference_samples=16,
             peers="eevee-1,workbench")
DEFAULT_TERMS = {family: choices[0] for family, choices in TERM_CHOICES.items()}
LIGHT_COUNTS = (1, 2, 4, 8, 16, 32, 64)
TRIANGLE_COUNTS = (10_000, 100_000, 1_000_000)
GENERIC_MAX_LIGHTS = 64
AUTO_BOUNDS = (0.5, 1.0, 3.0)  # Delta E_ITP at the 99th percentile of a material's pixels
QUICK_PRESET = "long_tail"
SCALING_PRESET = "material_grid"


# --- configurations ---------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Config:
    key: str
    label: str
    model: str
    terms: tuple[tuple[str, str], ...] = ()  # (family, choice) overriding the defaults
    multiscatter: bool = False
    principled: bool = False
    normalized: bool = False  # energy-normalised Blinn-Phong
    auto_bound: float | None = None  # the Auto term set at this error bound

    @property
    def group(self) -> str:
        return {"BLINN_PHONG": "Blinn-Phong", "PHONG": "Phong"}.get(self.model, "PBR")


def all_configs(quick: bool) -> list[Config]:
    configs = [Config("blinn-phong", "Blinn-Phong", "BLINN_PHONG"), Config("phong", "Phong", "PHONG"),
               Config("pbr", "PBR default (Schlick, GGX, Smith corr., Lambert)", "PBR")]
    if not quick:
        configs.insert(1, Config("blinn-phong-norm", "Blinn-Phong, energy-normalised", "BLINN_PHONG",
                                 normalized=True))
    for family, choices in TERM_CHOICES.items():
        for choice in choices[1:]:
            if quick and choice not in ("EXACT", "BECKMANN"):
                continue
            name = cli._flag(choice)
            configs.append(Config(f"pbr-{family}-{name}", f"PBR {family} {name}", "PBR", ((family, choice),)))
    configs.append(Config("pbr-multiscatter", "PBR multiscatter", "PBR", multiscatter=True))
    configs.append(Config("pbr-principled", "PBR Principled set", "PBR", principled=True))
    for bound in AUTO_BOUNDS:
        configs.append(Config(f"pbr-auto-{bound:g}", f"PBR Auto, bound {bound:g}", "PBR", auto_bound=bound))
    return configs


def apply(scene, config: Config) -> None:
    scene.render.engine = "SHADING_LAB"
    props = scene.shading_lab
    props.model = config.model
    props.term_set = "PRINCIPLED" if config.principled else "AUTO" if config.auto_bound else "CUSTOM"
    if config.auto_bound:
        props.auto_error_bound = config.auto_bound
    terms = {**DEFAULT_TERMS, **dict(config.terms)}
    for family, choice in terms.items():
        if getattr(props, family) != choice:
            setattr(props, family, choice)
    props.multiscatter = config.multiscatter
    props.normalized_blinn_phong = config.normalized


# --- measuring --------------------------------------------------------------------------------


def generic_from_snapshot(original):
    """A Features.from_snapshot that compiles every light kind in and 64 light slots."""

    def generic(cls, snapshot, **options):
        f = original.__func__(cls, snapshot, **options)
        return dataclasses.replace(f, light_kinds=frozenset(LIGHT_KINDS),
                                   max_lights=max(GENERIC_MAX_LIGHTS, f.max_lights))

    return classmethod(generic)


def specialised_vs_generic(scene, frames: int, progress, label: str) -> dict:
    """Draw + read-back ms of the scene's program and of the generic one, on one snapshot and one
    Renderer (geometry uploaded once), alternating, inside a test-only engine's GPU context."""
    import gpu_harness
    import numpy as np

    from addon.blender import extract
    from addon.frame.renderer import Renderer
    from addon.plan import programs

    original = programs.Features.__dict__["from_snapshot"]
    generic = generic_from_snapshot(original)

    def job(depsgraph):
        w, h = extract.render_size(depsgraph.scene)
        snap = extract.snapshot(depsgraph, w, h)
        features = programs.Features.from_snapshot(snap)
        renderer = Renderer()
        images = {}

        def draw(mode):
            if mode == "generic":
                programs.Features.from_snapshot = generic
            try:
                start = time.perf_counter()
                images[mode] = renderer.render(snap)
                return {"ms": 1e3 * (time.perf_counter() - start)}
            finally:
                programs.Features.from_snapshot = original

        try:
            renderer.sync(snap)
            specialised, generic_ms = (t["ms"] for t in timing.round_robin(
                ["specialised", "generic"], frames, draw, progress, f"{label} specialised vs generic"))
        finally:
            renderer.free()
        diff = float(np.abs(images["specialised"] - images["generic"]).max())
        return {"kinds": sorted(features.light_kinds), "max_lights": features.max_lights,
                "lights": len(snap.lights), "specialised": specialised, "generic": generic_ms,
                "max_diff": diff}

    return gpu_harness.run_on_gpu(job)


# --- the phases -------------------------------------------------------------------------------


def scene_triangles(scene) -> int:
    """Triangles of the evaluated meshes (n-gons fanned: n - 2 each)."""
    import bpy
    import numpy as np

    depsgraph = bpy.context.evaluated_depsgraph_get()
    total = 0
    for obj in scene.objects:
        if obj.type == "MESH":
            mesh = obj.evaluated_get(depsgraph).data
            sides = np.empty(len(mesh.polygons), np.int32)
            mesh.polygons.foreach_get("loop_total", sides)
            total += int((sides - 2).sum())
    return total


def bench_preset(name: str, args, configs, peers, progress, tmp: Path) -> dict:
    import metrics

    from addon.blender import engine
    from addon.plan import auto_terms

    scene = scenes.preset(name, args.size)
    out = {"name": name, "times": {}, "errors": {}, "peer_times": {}, "peer_errors": {}}
    out["triangles"] = scene_triangles(scene)
    out["lights"] = sum(1 for o in scene.objects if o.type == "LIGHT")

    def run_config(config):
        apply(scene, config)
        return timing.render_timed(scene)

    for size_ in args.sizes:
        scenes.ready(scene, size_)
        med = timing.round_robin(configs, args.frames, run_config, progress, f"{name} {page.res(size_)}")
        out["times"][size_] = {c.key: m for c, m in zip(configs, med)}

    scenes.ready(scene, args.ref_size)
    ref, cached = engines.cycles(scene, args.reference_samples)
    out["reference_cached"] = cached
    progress.step(f"{name} Cycles reference{' (cached)' if cached else ''}")
    out["auto_sets"] = {}
    for config in configs:
        apply(scene, config)
        image = engines.image(scene, tmp / f"{name}_{config.key}.exr")[0]
        out["errors"][config.key] = metrics.errors(ref, image)
        if config.auto_bound:
            out["auto_sets"][config.key] = auto_terms.summary(engine.last_term_choices).removeprefix("Auto: ")
        progress.step(f"{name} error {config.key}")

    images = {}

    def run_peer(peer):
        if peer not in engines.PEERS:
            apply(scene, next(c for c in configs if c.key == peer.removeprefix("sl-")))
            return timing.render_timed(scene)
        if peer not in images:  # the warm-up round: the image compared
            images[peer], ms = engines.image(scene, tmp / f"{name}_{peer}.exr", peer)
            return {"wall_ms": ms}
        return engines.timed(scene, peer)

    med = timing.round_robin(peers, args.peer_frames, run_peer, progress, f"{name} peers",
                             state_of=lambda p: engines.PEERS[p][1] if p in engines.PEERS else engines.OURS)
    apply(scene, configs[0])
    out["peer_times"] = dict(zip(peers, med))
    for key, image in images.items():
        out["peer_errors"][key] = metrics.errors(ref, image)
        progress.step(f"{name} error {key}")

    scenes.ready(scene, args.size)
    apply(scene, next(c for c in configs if c.key == "pbr"))
    out["generic"] = specialised_vs_generic(scene, args.frames, progress, name)
    return out


def bench_lights(args, progress) -> dict:
    """Frame time against the number of point lights on one preset (its lights replaced by a ring of
    point lights; the first N are rendered, the others hidden from the render)."""
    import bpy

    scene = scenes.preset(args.scaling_preset, args.size)
    for obj in [o for o in scene.objects if o.type == "LIGHT"]:
        bpy.data.objects.remove(obj)
    meshes = [o for o in scene.objects if o.type == "MESH"]
    centre = [sum(o.location[i] for o in meshes) / max(len(meshes), 1) for i in range(3)]
    radius = 2.0 + max((math.dist(o.location, centre) for o in meshes), default=1.0)
    counts = args.light_counts
    lights = []
    golden = math.pi * (3.0 - math.sqrt(5.0))  # any prefix of the ring is spread evenly
    for i in range(max(counts)):
        a = i * golden
        lights.append(scenes.light(scene, f"Bench point {i}", "POINT",
                                   (centre[0] + radius * math.cos(a), centre[1] + radius * math.sin(a),
                                    centre[2] + 3.0 + 0.5 * math.sin(3 * a)), shadow_soft_size=0.0))
    total_power = 3000.0
    models = [c for c in all_configs(True) if c.key in ("blinn-phong", "phong", "pbr")]
    items = [(n, m) for n in counts for m in models]

    def run(item):
        n, model = item
        for i, obj in enumerate(lights):
            obj.hide_render = i >= n
            obj.data.energy = total_power / n
        apply(scene, model)
        return timing.render_timed(scene)

    med = timing.round_robin(items, args.frames, run, progress, "lights scaling")
    return {"preset": args.scaling_preset, "rows": {(n, m.key): t for (n, m), t in zip(items, med)}}


def bench_triangles(args, progress) -> dict:
    """Frame time and extraction time against triangles: one subdivided grid per size filling the
    view, only one rendered at a time, two point lights, Blender's default surface."""
    import bpy

    scene = scenes.empty(args.size)
    scenes.camera(scene, (0.0, 0.0, 3.0))
    for i, loc in enumerate(((1.0, 0.8, 1.5), (-1.2, -0.6, 2.0))):
        scenes.light(scene, f"Point {i}", "POINT", loc, energy=200.0, shadow_soft_size=0.0)
    grids = {}
    for target in args.triangle_counts:
        n = max(1, round(math.sqrt(target / 2)))
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=n, y_subdivisions=n, size=4.0)
        obj = bpy.context.active_object
        grids[target] = (obj, 2 * len(obj.data.polygons))
    models = [c for c in all_configs(True) if c.key in ("blinn-phong", "pbr")]
    items = [(t, m) for t in args.triangle_counts for m in models]

    def run(item):
        target, model = item
        for t, (obj, _) in grids.items():
            obj.hide_render = t != target
        apply(scene, model)
        return timing.render_timed(scene)

    med = timing.round_robin(items, args.frames, run, progress, "triangles scaling")
    return {"triangles": {t: tris for t, (_, tris) in grids.items()},
            "rows": {(t, m.key): x for (t, m), x in zip(items, med)}}


# --- report -----------------------------------------------------------------------------------


def report(args, results, lights, tris, configs, peers) -> list[str]:
    """The page's body (the harness writes the header)."""
    main, ref = args.size, args.ref_size
    res, table, geomean = page.res, page.table, page.geomean
    others = [p for p in peers if p in engines.PEERS]
    lines = [f"Method: per preset, every configuration is rendered round-robin (one warm-up round that "
             f"compiles the programs, then {args.frames} timed rounds, order rotated each round), all "
             f"in one process. *total* is the engine's own time (`engine.last_timings`): scene "
             f"extraction + draw + read-back (the read-back fences the GPU work) + handing pixels to "
             f"Blender; *wall* is `bpy.ops.render.render()` as a whole (a still scene rendered again: "
             f"its meshes of up to {MEMO_CORNERS:,} corners come from the geometry memo, "
             f"`blender.geometry.GEOMETRY_MEMO`, as at any re-render). Errors are against Cycles "
             f"(direct light only, world on and occluded, lights as the file has them, shadows included, "
             f"pixel centres, "
             f"{args.reference_samples} spp, "
             f"`harness.engines.cycles`, cached) **at {res(ref)}**: every compared image, ours and "
             f"the peers', is rendered at {res(ref)}. FLIP is mean HDR-FLIP; *rel* the mean relative "
             f"luminance error on lit pixels. Peers (EEVEE, Workbench) are timed at {res(ref)} in the "
             f"same rounds as Shading Lab's Blinn-Phong and default PBR (wall times, median of "
             f"{args.peer_frames} after a warm-up; a timed render that follows another engine's is "
             f"preceded by an untimed one of its own, so that each engine is timed in its steady state: "
             f"`harness.timing.collect`), lights as for the reference.", ""]
    summary_at = len(lines)

    # 1. headline per preset
    lines += [f"## Per preset: models at {res(main)}", ""]
    rows = []
    for r in results:
        t = r["times"][main]
        e = r["errors"]
        bp = t["blinn-phong"]["total_ms"]
        ratio = t["pbr"]["total_ms"] / bp
        rows.append([r["name"], f"{r['triangles']:,}", str(r["lights"]),
                     f"{bp:.1f}", f"{t['phong']['total_ms']:.1f}", f"{t['pbr']['total_ms']:.1f}",
                     f"{ratio:.2f}×", f"{t['pbr-principled']['total_ms'] / bp:.2f}×",
                     *(f"{e[k].flip:.3f} / {e[k].mean_relative:.1%}" for k in
                       ("blinn-phong", "phong", "pbr", "pbr-principled"))])
    lines += table(["preset", "tris", "lights", "BP ms", "Phong ms", "PBR ms", "PBR / BP", "Princ. / BP",
                    "BP FLIP / rel", "Phong FLIP / rel", "PBR FLIP / rel", "Princ. FLIP / rel"], rows)
    lines += ["", f"ms: median *total* at {res(main)}; FLIP / rel at {res(ref)}. PBR = default terms "
              f"(Schlick, GGX, Smith height-correlated, Lambert); Princ. = the Principled term set.", ""]

    # 2. peers
    lines += [f"## Peers at {res(ref)} (wall ms, same rounds)", ""]
    rows = []
    for r in results:
        pt, pe = r["peer_times"], r["peer_errors"]
        ours = pt["sl-pbr"]["wall_ms"]
        cells = [r["name"], f"{pt['sl-blinn-phong']['wall_ms']:.0f}", f"{ours:.0f}"]
        for p in others:
            cells.append(f"{pt[p]['wall_ms']:.0f} ({pt[p]['wall_ms'] / ours:.0f}×)")
            cells.append(f"{pe[p].flip:.3f} / {pe[p].mean_relative:.1%}")
        cells.append(f"{r['errors']['pbr'].flip:.3f} / {r['errors']['pbr'].mean_relative:.1%}")
        rows.append(cells)
    header = ["preset", "SL BP ms", "SL PBR ms"]
    for p in others:
        header += [f"{engines.label(p)} ms (× SL PBR)", f"{engines.label(p)} FLIP / rel"]
    lines += table(header + ["SL PBR FLIP / rel"], rows)
    lines += ["", "Set up by `harness.engines` (`reference.use_engine`): EEVEE with light threshold "
              "1e-6 and the lights as the file has them (shadows on); Workbench with its default "
              "studio lighting (not the scene's lights), so its error is large by design. The "
              "reference samples pixel centres (no anti-aliasing): EEVEE at 1 sample does too, EEVEE "
              "at 16 samples jitters over Blender's 1.5 px film filter, and the metrics count that "
              "smoothing as error — which is why 16 samples can score worse than 1 here. Peer times "
              "are whole-render wall times, including EEVEE's per-render set-up.", ""]

    # 3. variants across presets
    lines += [f"## Every configuration, across presets ({len(results)})", ""]
    rows = []
    names = [r["name"] for r in results]
    for c in configs:
        ratio_bp = geomean(r["times"][main][c.key]["total_ms"] / r["times"][main]["blinn-phong"]["total_ms"]
                           for r in results)
        ratio_pbr = geomean(r["times"][main][c.key]["total_ms"] / r["times"][main]["pbr"]["total_ms"]
                            for r in results)
        draw = statistics.mean(r["times"][main][c.key]["draw_ms"] for r in results)
        flip = statistics.mean(r["errors"][c.key].flip for r in results)
        rel = statistics.mean(r["errors"][c.key].mean_relative for r in results)
        cells = [c.label, f"{ratio_bp:.2f}×", f"{ratio_pbr:.2f}×", f"{draw:.1f}"]
        if ref != main:
            cells.append(f"{statistics.mean(r['times'][ref][c.key]['wall_ms'] for r in results):.1f}")
        rows.append(cells + [f"{flip:.4f}", f"{rel:.2%}"])
    header = ["configuration", "time / BP", "time / PBR default", f"draw ms {res(main)}"]
    if ref != main:
        header.append(f"wall ms {res(ref)}")
    lines += table(header + ["mean FLIP", "mean rel"], rows)
    lines += ["", "time ratios: geometric mean over presets of the median *total* at "
              f"{res(main)}; draw ms and errors: arithmetic means over {', '.join(names)}.", ""]

    # 4. scaling
    lines += [f"## Scaling at {res(main)}", ""]
    if lights:
        rows_l = lights["rows"]
        counts = sorted({n for n, _ in rows_l})
        keys = [k for k in ("blinn-phong", "phong", "pbr") if (counts[0], k) in rows_l]
        rows = [[str(n), *(f"{rows_l[(n, k)]['total_ms']:.1f} / {rows_l[(n, k)]['draw_ms']:.1f}"
                           for k in keys)] for n in counts]
        lines += [f"**Point lights** on `{lights['preset']}` (its lights replaced by N point lights, the "
                  "same total power); total / draw ms:", ""]
        lines += table(["lights", *(MODEL_LABELS[k] for k in keys)], rows)
        slopes, growth = {}, {}
        for k in keys:
            ys = [rows_l[(n, k)]["draw_ms"] for n in counts]
            mx, my = statistics.mean(counts), statistics.mean(ys)
            slopes[k] = (sum((x - mx) * (y - my) for x, y in zip(counts, ys))
                         / sum((x - mx) ** 2 for x in counts))
            growth[k] = rows_l[(counts[-1], k)]["total_ms"] / rows_l[(counts[0], k)]["total_ms"]
        lines += ["", "Least-squares draw ms per extra light: "
                  + ", ".join(f"{MODEL_LABELS[k]} {slopes[k]:.2f}" for k in keys)
                  + f"; total at {counts[-1]} lights / at {counts[0]}: "
                  + ", ".join(f"{MODEL_LABELS[k]} {growth[k]:.1f}×" for k in keys) + ".", ""]
    if tris:
        targets = sorted(tris["triangles"])
        keys = [k for k in ("blinn-phong", "pbr") if (targets[0], k) in tris["rows"]]
        rows = []
        for t in targets:
            pbr = tris["rows"][(t, keys[-1])]
            rows.append([f"{tris['triangles'][t]:,}",
                         *(f"{tris['rows'][(t, k)]['total_ms']:.1f}" for k in keys),
                         f"{pbr['extract_ms']:.1f}", f"{pbr['draw_ms']:.1f}", f"{pbr['result_ms']:.1f}"])
        lines += ["**Triangles**: a subdivided grid filling the view, two point lights; the engine "
                  "re-reads and re-uploads the mesh every final render (draw includes the upload).", ""]
        lines += table(["triangles", *(f"{MODEL_LABELS[k]} total ms" for k in keys), "PBR extract ms",
                        "PBR draw ms", "PBR result ms"], rows)
        lines.append("")

    # 5. specialised vs generic
    lines += [f"## Scene-specialised program vs one generic program (PBR default, {res(main)})", ""]
    rows = []
    for r in results:
        g = r["generic"]
        saving = 1.0 - g["specialised"] / g["generic"]
        program = f"{g['lights']}: {', '.join(k.lower() for k in g['kinds'])}, slots {g['max_lights']}"
        rows.append([r["name"], program, f"{g['specialised']:.1f}", f"{g['generic']:.1f}", f"{saving:+.1%}",
                     f"{g['max_diff']:.1e}"])
    lines += table(["preset", "scene's program: lights, kinds, slots", "specialised draw ms",
                    "generic draw ms", "saving", "max |Δ| image"], rows)
    lines += ["", "How: a test-only engine (`tests/gpu_harness.py`) extracts one snapshot, uploads its "
              "geometry once into one `renderer.Renderer`, and times `Renderer.render` (draw + "
              "read-back) alternately with the scene's features and with `Features.from_snapshot` "
              f"monkeypatched to return every light kind and {GENERIC_MAX_LIGHTS} light slots (medians of "
              f"{args.frames} after a warm-up). Caveat: the generic program still loops over the "
              "scene's real light count (the loop breaks at it), and the model and the PBR terms "
              "stay compile-time (the product has no runtime switch for them), so this is the "
              "saving of light specialisation alone — a lower bound for \"one program for "
              "everything\". Images agree (max |Δ| above).", ""]

    # 6. the Auto term set
    autos = [c for c in configs if c.auto_bound]
    if autos:
        lines += [f"## The Auto term set ({res(main)} times; errors and choices at {res(ref)})", ""]
        rows = []
        for r in results:
            t, e = r["times"][main], r["errors"]
            for c in autos:
                rows.append([r["name"], f"{c.auto_bound:g}",
                             f"{t[c.key]['total_ms'] / t['pbr-principled']['total_ms']:.3f}×",
                             f"{t[c.key]['total_ms'] / t['pbr']['total_ms']:.3f}×",
                             f"{e[c.key].flip:.4f} / {e['pbr-principled'].flip:.4f}",
                             r["auto_sets"].get(c.key, "")])
        lines += table(["preset", "bound", "time / Principled", "time / default", "FLIP Auto / Principled",
                        "chosen sets"], rows)
        lines += ["", "Bound: Delta E_ITP at the 99th percentile of a material's pixels against the "
                  "Principled set (`addon/plan/auto_terms.py`). Times include the prediction (in "
                  "extraction).",
                  ""]

    # 7. detail per preset
    lines += ["## Detail per preset", ""]
    for r in results:
        lines += [f"### {r['name']} ({r['triangles']:,} triangles, {r['lights']} lights; Cycles reference "
                  f"{'cached' if r['reference_cached'] else 'rendered this run'})", ""]
        rows = []
        t = r["times"][main]
        for c in configs:
            m, e = t[c.key], r["errors"][c.key]
            cells = [c.label, f"{m['total_ms']:.1f}", f"{m['extract_ms']:.1f}", f"{m['draw_ms']:.1f}",
                     f"{m['total_ms'] / t['blinn-phong']['total_ms']:.2f}×"]
            if ref != main:
                cells.append(f"{r['times'][ref][c.key]['total_ms']:.1f}")
            rows.append(cells + [f"{e.flip:.4f}", f"{e.mean_relative:.2%}", f"{e.max_abs:.3g}"])
        for p in others:
            e = r["peer_errors"][p]
            cells = [engines.label(p), "–", "–", "–", "–"]
            if ref != main:
                cells.append(f"{r['peer_times'][p]['wall_ms']:.0f} (wall)")
            rows.append(cells + [f"{e.flip:.4f}", f"{e.mean_relative:.2%}", f"{e.max_abs:.3g}"])
        header = ["configuration", "total ms", "extract ms", "draw ms", "/ BP"]
        if ref != main:
            header.append(f"total ms {res(ref)}")
        lines += table(header + ["FLIP", "rel", "max abs"], rows)
        lines.append("")
    lines[summary_at:summary_at] = summary(args, results, lights, tris, others)
    return lines


def _spread(values: list[float], fmt: str) -> str:
    """geometric mean (min–max) of positive values."""
    if len(values) == 1:
        return format(values[0], fmt)
    return f"{format(page.geomean(values), fmt)} ({format(min(values), fmt)}–{format(max(values), fmt)})"


def summary(args, results, lights, tris, peers) -> list[str]:
    """The summary's bullets; ``peers``: the other engines' keys."""
    main, ref = args.size, args.ref_size
    res = page.res
    n = len(results)
    ratio = {k: [r["times"][main][k]["total_ms"] / r["times"][main]["blinn-phong"]["total_ms"]
                 for r in results] for k in ("phong", "pbr", "pbr-principled")}
    flip = {k: statistics.mean(r["errors"][k].flip for r in results)
            for k in ("blinn-phong", "phong", "pbr", "pbr-principled")}
    rel = {k: statistics.mean(r["errors"][k].mean_relative for r in results) for k in flip}
    peer_ratio = {p: [r["peer_times"][p]["wall_ms"] / r["peer_times"]["sl-pbr"]["wall_ms"] for r in results]
                  for p in peers}
    out = ["## Summary", "",
           f"- Time / Blinn-Phong at {res(main)} (geometric mean over {n} preset(s), min–max): Phong "
           f"{_spread(ratio['phong'], '.2f')}×, PBR default {_spread(ratio['pbr'], '.2f')}×, Principled "
           f"set {_spread(ratio['pbr-principled'], '.2f')}×.",
           "- Mean FLIP / mean relative error vs Cycles: " + "; ".join(
               f"{label} {flip[k]:.3f} / {rel[k]:.1%}" for k, label in
               (("blinn-phong", "Blinn-Phong"), ("phong", "Phong"), ("pbr", "PBR default"),
                ("pbr-principled", "Principled set"))) + "; " + "; ".join(
               f"{engines.label(p)} {statistics.mean(r['peer_errors'][p].flip for r in results):.3f} / "
               f"{statistics.mean(r['peer_errors'][p].mean_relative for r in results):.1%}"
               for p in peers) + ".",
           f"- Peers' wall time / Shading Lab PBR's at {res(ref)}: " + ", ".join(
               f"{engines.label(k)} {_spread(v, '.0f')}×" for k, v in peer_ratio.items()) + "."]
    if lights:
        rows_l = lights["rows"]
        counts = sorted({c for c, _ in rows_l})
        first, last = rows_l[(counts[0], "pbr")]["total_ms"], rows_l[(counts[-1], "pbr")]["total_ms"]
        out.append(f"- Point lights ({lights['preset']}, PBR): {counts[0]} → {counts[-1]} lights: "
                   f"{first:.1f} → {last:.1f} ms total ({last / first:.1f}×).")
    if tris:
        targets = sorted(tris["triangles"])
        rows_t = tris["rows"]
        out.append("- Triangles (PBR, grid): " + ", ".join(
            f"{tris['triangles'][t]:,}: {rows_t[(t, 'pbr')]['total_ms']:.0f} ms total, "
            f"{rows_t[(t, 'pbr')]['extract_ms']:.0f} ms extraction" for t in targets) + ".")
    savings = [1.0 - r["generic"]["specialised"] / r["generic"]["generic"] for r in results]
    spread = f" on average ({min(savings):+.1%} to {max(savings):+.1%})" if n > 1 else ""
    out += [f"- Specialised vs generic program (draw + read-back): saving "
            f"{statistics.mean(savings):+.1%}{spread}.", ""]
    return out


MODEL_LABELS = {"blinn-phong": "Blinn-Phong", "phong": "Phong", "pbr": "PBR"}


SHORT = {"fresnel": "F", "ndf": "D", "visibility": "V", "diffuse": "diff."}


def short_label(c: Config) -> str:
    if c.model != "PBR":
        return c.label.replace(", energy-normalised", " norm.")
    if c.principled:
        return "PBR Principled"
    if c.auto_bound:
        return f"Auto {c.auto_bound:g}"
    if c.multiscatter:
        return "PBR multiscatter"
    if c.terms:
        family, choice = c.terms[0]
        return f"{SHORT[family]} {cli._flag(choice)}"
    return "PBR default"


def pareto_front(points: list[tuple]) -> list[tuple]:
    """Points no other point beats in both time (index 1) and error (index 2)."""
    front, best = [], math.inf
    for point in sorted(points, key=lambda q: (q[1], q[2])):
        if point[2] < best:
            front.append(point)
            best = point[2]
    return front


def _labels(ax, points, fontsize=6) -> None:
    """Annotate points, nudging labels apart vertically where they would overlap."""
    placed = []  # display coordinates of labels already placed
    to_disp = ax.transData.transform
    for label, x, y, _kind in sorted(points, key=lambda q: q[2]):
        px, py = to_disp((x, y))
        dy = 0.0
        while any(abs(px - qx) < 70 and abs(py + dy - qy) < 8 for qx, qy in placed):
            dy += 8
        placed.append((px, py + dy))
        ax.annotate(label, (x, y), fontsize=fontsize, xytext=(5, dy - 2), textcoords="offset points",
                    arrowprops={"arrowstyle": "-", "lw": 0.3, "color": "0.5"} if dy else None)


def pareto_plot(path: Path, args, results, configs, peers) -> None:
    plt = plots.pyplot()
    ref = args.ref_size
    points = []  # (label, ms, flip, kind)
    for c in configs:
        points.append((short_label(c), statistics.mean(r["times"][ref][c.key]["wall_ms"] for r in results),
                       statistics.mean(r["errors"][c.key].flip for r in results), c.group))
    for p in peers:
        if p in engines.PEERS:
            points.append((engines.label(p), statistics.mean(r["peer_times"][p]["wall_ms"] for r in results),
                           statistics.mean(r["peer_errors"][p].flip for r in results), "peer"))
    front = pareto_front(points)
    colours = {"Blinn-Phong": "tab:blue", "Phong": "tab:green", "PBR": "tab:red", "peer": "tab:gray"}
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.2), dpi=80, gridspec_kw={"width_ratios": [1, 1.15]})
    ours = [q for q in points if q[3] != "peer"]
    for ax, sel_points, log in ((axes[0], points, True), (axes[1], ours, False)):
        for kind, colour in colours.items():
            sel = [q for q in sel_points if q[3] == kind]
            if sel:
                ax.scatter([q[1] for q in sel], [q[2] for q in sel], c=colour, s=24, zorder=3,
                           label="Shading Lab " + kind if kind != "peer" else "EEVEE / Workbench")
        f = [q for q in front if q in sel_points]
        ax.plot([q[1] for q in f], [q[2] for q in f], "k--", lw=1, zorder=2, label="Pareto front")
        ax.scatter([q[1] for q in f], [q[2] for q in f], s=100, facecolors="none", edgecolors="k", zorder=4)
        if log:
            ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.set_xlabel(f"median frame time, ms (wall, {ref[0]}×{ref[1]}, mean over presets)")
        ax.set_ylabel("mean HDR-FLIP vs Cycles (mean over presets, log)")
        fig.canvas.draw()
        _labels(ax, sel_points if not log else [q for q in sel_points if q[3] == "peer" or q in f])
    axes[0].set_title("every model, variant and peer (log time; labels: peers and the front)", fontsize=9)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=7, loc="lower center", ncol=len(labels), frameon=False)
    axes[1].set_title("Shading Lab only (linear time; front over all points)", fontsize=9)
    fig.suptitle(f"Time vs error — {len(results)} preset(s): {', '.join(r['name'] for r in results)}; "
                 "Mesa llvmpipe, compare ratios", fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    plots.save(fig, path)


def scaling_plot(path: Path, args, lights, tris, results) -> None:
    plt = plots.pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(13, 4), dpi=80)
    ax = axes[0]
    if lights:
        counts = sorted({n for n, _ in lights["rows"]})
        for k in ("blinn-phong", "phong", "pbr"):
            if (counts[0], k) in lights["rows"]:
                ax.plot(counts, [lights["rows"][(n, k)]["total_ms"] for n in counts], "o-",
                        label=MODEL_LABELS[k])
        ax.set_xticks(counts[-4:] if len(counts) > 5 else counts)
    ax.set_xlabel(f"point lights ({lights['preset'] if lights else '-'})")
    ax.set_ylabel("median total ms")
    ax.set_title("frame time vs lights", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    ax = axes[1]
    if tris:
        targets = sorted(tris["triangles"])
        xs = [tris["triangles"][t] for t in targets]
        for k in ("blinn-phong", "pbr"):
            ax.plot(xs, [tris["rows"][(t, k)]["total_ms"] for t in targets], "o-",
                    label=f"{MODEL_LABELS[k]} total")
        ax.plot(xs, [tris["rows"][(t, "pbr")]["extract_ms"] for t in targets], "s--", label="PBR extraction")
        ax.plot(xs, [tris["rows"][(t, "pbr")]["draw_ms"] for t in targets], "^--",
                label="PBR draw (+upload, read-back)")
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlabel("triangles (subdivided grid)")
    ax.set_ylabel("median ms")
    ax.set_title("frame and extraction time vs triangles", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    ax = axes[2]
    names = [r["name"] for r in results]
    xs = range(len(names))
    ax.bar([x - 0.2 for x in xs], [r["generic"]["specialised"] for r in results], 0.4, label="specialised")
    ax.bar([x + 0.2 for x in xs], [r["generic"]["generic"] for r in results], 0.4,
           label=f"generic (4 kinds, {GENERIC_MAX_LIGHTS} slots)")
    ax.set_xticks(list(xs), names, rotation=30, ha="right", fontsize=7)
    ax.set_ylabel("median draw + read-back ms")
    ax.set_title("specialised vs generic program (PBR)", fontsize=9)
    ax.legend(fontsize=7)
    fig.suptitle(f"Scaling at {args.size[0]}×{args.size[1]} (Mesa llvmpipe: compare ratios)", fontsize=9)
    fig.tight_layout()
    plots.save(fig, path)


# --- command line -----------------------------------------------------------------------------


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=5, presets="all", reference_samples=128,
             peers=",".join(engines.PEERS))
    parser.add_argument("--reference-resolution", type=size, default=None, metavar="WxH",
                        help="resolution of the error comparisons and the peers' timing (default: half "
                             "of --resolution; with --quick or from 640 px down, --resolution)")
    parser.add_argument("--peer-frames", type=int, default=3, help="timed frames per peer (default 3)")


def resolve(args) -> None:
    if args.peer_frames < 1:
        raise cli.CliError("--peer-frames must be at least 1")
    args.preset_list = args.presets[:1] if args.quick else args.presets
    args.size = args.resolution
    if args.reference_resolution:
        args.ref_size = args.reference_resolution
    elif args.quick or args.size[0] <= 640:
        args.ref_size = args.size
    else:
        args.ref_size = (args.size[0] // 2, args.size[1] // 2)
    args.sizes = [args.size] + ([args.ref_size] if args.ref_size != args.size else [])
    args.light_counts = (1, 4, 16, 64) if args.quick else LIGHT_COUNTS
    args.triangle_counts = TRIANGLE_COUNTS[:2] if args.quick else TRIANGLE_COUNTS
    args.scaling_preset = (SCALING_PRESET if SCALING_PRESET in shipped_presets() and not args.quick
                           else args.preset_list[0])


def run(ctx) -> None:
    args = ctx.args
    resolve(args)
    configs = all_configs(args.quick)
    peers = ["sl-blinn-phong", "sl-pbr", *args.peers]
    print(f"bench: {len(args.preset_list)} preset(s) x {len(configs)} configurations, {page.res(args.size)} "
          f"(errors and peers at {page.res(args.ref_size)}), {args.frames} frames")
    with tempfile.TemporaryDirectory() as tmp:
        results = [bench_preset(name, args, configs, peers, ctx.progress, Path(tmp))
                   for name in args.preset_list]
    lights = bench_lights(args, ctx.progress)
    tris = bench_triangles(args, ctx.progress)
    ctx.page("Shading Lab benchmark", report(args, results, lights, tris, configs, peers))
    pareto_plot(args.out / "pareto.png", args, results, configs, peers)
    scaling_plot(args.out / "scaling.png", args, lights, tris, results)
