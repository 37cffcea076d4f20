"""The Principled BSDF's lobes: what each costs against the Principled set without it, and how
close it comes to Cycles, ours and EEVEE's side by side.

The lobes are those the scene presets can turn on (``presets.PRINCIPLED_INPUTS``); each is shown
by the one shipped preset that names it (``[scene] lobe``), and turned off by setting its
switches to Blender's defaults (``presets.lobe_off``) on every Principled BSDF of the scene.
(1) Cost, per lobe: its preset's library material on a plane filling the view under 2 and 8
point lights (shadows off, the Principled term set), and the preset scene itself, each with the
lobe on and off, rendered round-robin in one process after a warm-up (draw + read-back ms,
medians); the ratio on / off. "Every lobe drawn" is one material with each drawn lobe's inputs.
(2) Error, per lobe preset at ``--error-resolution``: ours and EEVEE (16 samples) against Cycles
with the lobe's transport (direct light; a refraction's bounces for Transmission), mean relative
error of the lit pixels' luminance and mean HDR-FLIP (``scripts/metrics.py``); beside them how far
Cycles' own image moves when the lobe is turned off (what the lobe shows). A lobe the engine does
not draw yet (not in ``snapshot.LOBES``) is drawn as its base: its ratio is about 1 and its
error is what it misses.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from pathlib import Path

from .harness import engines, page, plots, scenes, size, standard, timing

PAGE = "lobes.md"
FIGURE = "lobes.png"
QUICK = dict(resolution="160x90", frames=1, error_resolution="96x54", reference_samples=8, lights="2")
#: The point-light counts of the plane's cost (session 22's measurement: 2 and 8).
LIGHT_COUNTS = "2,8"
#: EEVEE's samples per pixel in the error comparison (``engines.PEERS``).
EEVEE = "eevee-16"
#: Cycles' bounces for the lobes whose light is more than direct (the rest: direct light only,
#: ``reference.render_reference``): a refraction reaches what lies behind through the surface
#: and its far side, then takes the lights there directly.
TRANSPORT = {"TRANSMISSION": dict(max_bounces=8, transmission_bounces=8, transparent_max_bounces=8,
                                  diffuse_bounces=0, glossy_bounces=0, volume_bounces=0)}


def options(parser) -> None:
    standard(parser, resolution="1280x720", frames=5, reference_samples=256)
    parser.add_argument("--error-resolution", type=size, default="480x270", metavar="WxH",
                        help="size of the images compared with Cycles (default 480x270)")
    parser.add_argument("--lights", default=LIGHT_COUNTS,
                        help=f"point-light counts of the plane's cost, comma-separated "
                             f"(default {LIGHT_COUNTS})")


# --- the lobes and their presets ------------------------------------------------------------------


def lobe_presets() -> dict:
    """{lobe: the shipped scene preset that names it}, in ``presets.LOBE_NAMES``' order."""
    from addon.scene import presets

    named = {}
    for name in presets.scene_preset_names():
        lobe = presets.load_scene_preset(name).lobe
        if lobe is not None:
            named.setdefault(lobe, name)
    return {lobe: named[lobe] for lobe in presets.LOBE_NAMES if lobe in named}


def drawn(lobe: str) -> bool:
    from addon.scene import snapshot

    return lobe in snapshot.LOBES


def _label(lobe: str) -> str:
    return lobe.replace("_", " ").title()


def _library_material(preset_name: str, lobe: str):
    """The preset's first material with ``lobe`` on (a ``presets.MaterialPreset``)."""
    from addon.scene import presets

    preset = presets.load_scene_preset(preset_name)
    return next(o.material for o in preset.objects if o.material is not None and lobe in o.material.lobes)


def _principled_nodes(scene):
    materials = {slot.material for obj in scene.objects for slot in obj.material_slots if slot.material}
    return [node for mat in materials if mat.node_tree is not None for node in mat.node_tree.nodes
            if node.bl_idname == "ShaderNodeBsdfPrincipled"]


class Switch:
    """Turns a lobe off and on again on every Principled BSDF of a scene: its switches at Blender's
    defaults, then back at the values the scene had."""

    def __init__(self, scene, lobe: str):
        from addon.scene import presets

        self.off = presets.lobe_off(lobe)
        self.nodes = _principled_nodes(scene)
        self.on = [self._values(node) for node in self.nodes]

    def _values(self, node) -> dict:
        from addon.scene import presets

        sockets = {s.identifier: s for s in node.inputs}
        out = {}
        for key in self.off:
            value = sockets[presets.PRINCIPLED_INPUTS[key].socket].default_value
            out[key] = tuple(value)[:3] if presets.PRINCIPLED_INPUTS[key].color else float(value)
        return out

    def __call__(self, on: bool) -> None:
        from addon.blender import scene_builder

        for node, values in zip(self.nodes, self.on):
            scene_builder.set_principled_inputs(node, values if on else self.off)


# --- (1) cost -------------------------------------------------------------------------------------


def _plane_scene(args, lights: int):
    """A plane filling the view (orthographic, from above) under ``lights`` point lights in a ring
    1.5 m above it, shadows off; the Principled term set."""
    scene, plane = scenes.filled_plane(args.resolution)
    for i in range(lights):
        a = 2.0 * math.pi * (i + 0.5) / lights
        scenes.light(scene, f"Point {i}", "POINT", location=(1.2 * math.cos(a), 1.2 * math.sin(a), 1.5),
                     energy=60.0, shadow_soft_size=0.0, use_shadow=False)
    return scene, plane


def _plane_materials(lobes: dict) -> dict:
    """{(row label, on): Blender material}: each lobe's library material with the lobe on and off,
    and one material with every drawn lobe's inputs (over the first drawn lobe's base)."""
    import bpy

    from addon.blender import scene_builder
    from addon.scene import presets

    specs = {_label(lobe): (_library_material(name, lobe), (lobe,)) for lobe, name in lobes.items()}
    every = [lobe for lobe in lobes if drawn(lobe)]
    if len(every) > 1:
        merged = {k: v for lobe in every for k, v in _library_material(lobes[lobe], lobe).principled}
        base = _library_material(lobes[every[0]], every[0])
        every_on = dataclasses.replace(base, principled=tuple(merged.items()))
        specs["Every lobe drawn"] = (every_on, tuple(every))
    out = {}
    for label, (spec, off_lobes) in specs.items():
        off = {k: v for lobe in off_lobes for k, v in presets.lobe_off(lobe).items()}
        for on, values in ((True, spec.principled), (False, (*spec.principled, *off.items()))):
            material = dataclasses.replace(spec, principled=tuple(dict(values).items()))
            out[label, on] = scene_builder.apply_material_preset(
                bpy.data.materials.new(f"{label} {'on' if on else 'off'}"), material)
    return out


def _cost(args, ctx, lobes) -> tuple[list[str], dict]:
    counts = [int(n) for n in str(args.lights).split(",")]
    ratios: dict = {}
    for n in counts:
        scene, plane = _plane_scene(args, n)
        materials = _plane_materials(lobes)

        def apply(config, plane=plane, materials=materials):
            plane.data.materials.clear()
            plane.data.materials.append(materials[config])

        med = timing.median_ms(list(materials), apply, args.frames, ctx.progress, f"plane, {n} lights")
        for label, on in materials:
            if on:
                ratios.setdefault(label, {})[n] = (med[label, True], med[label, False])
    for lobe, name in lobes.items():
        scene = scenes.preset(name, args.resolution)
        scene.shading_lab.term_set = "PRINCIPLED"
        switch = Switch(scene, lobe)
        med = timing.median_ms([True, False], switch, args.frames, ctx.progress, name)
        switch(True)
        ratios.setdefault(_label(lobe), {})["scene"] = (med[True], med[False])
    rows = []
    for label, by in ratios.items():
        lobe = label.upper().replace(" ", "_")
        row = [label, ("yes" if drawn(lobe) else "not yet") if lobe in lobes else "yes"]
        for key in (*counts, "scene"):
            on, off = by.get(key, (math.nan, math.nan))
            row += ["", ""] if math.isnan(off) else [f"{on:.1f} / {off:.1f}", f"**{on / off:.2f}×**"]
        rows.append(row)
    header = ["lobe", "drawn"]
    for n in counts:
        header += [f"{n} lights: ms on / off", "ratio"]
    header += ["preset scene: ms on / off", "ratio"]
    lines = ["## What each lobe costs", "",
             f"{page.res(args.resolution)}, the Principled term set, {args.frames} frames per configuration "
             "after a warm-up, round-robin in one process; draw + read-back ms, medians. *N lights*: the "
             "lobe's library material on a plane filling the view under N point lights in a ring 1.5 m above "
             "it (shadows off), against the same material with the lobe off. *Preset scene*: the lobe's "
             "preset as shipped (its lights cast shadows), the lobe on against off on every material. A "
             "material without a lobe pays nothing for it: its program holds none of the lobe's code.", "",
             *page.table(header, rows), ""]
    return lines, ratios


# --- (2) error against Cycles ---------------------------------------------------------------------


def _cycles(scene, lobe: str, samples: int, folder: Path):
    """Cycles' image of ``scene`` with ``lobe``'s transport (direct light, else ``TRANSPORT``)."""
    import reference

    if lobe not in TRANSPORT:
        return engines.cycles(scene, samples)[0]
    engine = scene.render.engine
    try:
        scene.render.engine = "CYCLES"
        c = scene.cycles
        c.device, c.samples, c.use_adaptive_sampling, c.use_denoising = "CPU", samples, False, False
        c.pixel_filter_type, c.filter_width, c.seed = "GAUSSIAN", 0.01, 0
        for key, value in TRANSPORT[lobe].items():
            setattr(c, key, value)
        return reference.render_to_array(scene, folder / "cycles.exr")
    finally:
        scene.render.engine = engine


def _errors(args, ctx, lobes) -> tuple[list[str], dict]:
    import metrics

    rows, found = [], {}
    ctx.progress.expect(5 * len(lobes))
    for lobe, name in lobes.items():
        scene = scenes.preset(name, args.error_resolution)
        scene.shading_lab.term_set = "PRINCIPLED"
        switch = Switch(scene, lobe)
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            ref = _cycles(scene, lobe, args.reference_samples, folder)
            ctx.progress.step(f"{name}: Cycles")
            ours = engines.image(scene, folder / "ours.exr")[0]
            ctx.progress.step(f"{name}: ours")
            eevee = engines.image(scene, folder / "eevee.exr", EEVEE)[0]
            ctx.progress.step(f"{name}: EEVEE")
            switch(False)
            ref_off = _cycles(scene, lobe, args.reference_samples, folder)
            ours_off = engines.image(scene, folder / "ours_off.exr")[0]
            switch(True)
            ctx.progress.step(f"{name}: lobe off")
        e_ours, e_eevee = metrics.errors(ref, ours), metrics.errors(ref, eevee)
        effect = metrics.errors(ref, ref_off)
        e_off = metrics.errors(ref, ours_off)
        found[_label(lobe)] = dict(ours=e_ours, eevee=e_eevee, effect=effect, off=e_off)
        rows.append([_label(lobe), f"`{name}`", "yes" if drawn(lobe) else "not yet",
                     f"{e_ours.mean_relative:.2%}", f"{e_ours.flip:.4f}", f"{e_eevee.mean_relative:.2%}",
                     f"{e_eevee.flip:.4f}", f"{e_off.mean_relative:.2%} / {e_off.flip:.4f}",
                     f"{effect.mean_relative:.2%} / {effect.flip:.4f}",
                     "direct + refraction" if lobe in TRANSPORT else "direct"])
        ctx.progress.step(f"{name}: compared")
    lines = ["## Error against Cycles", "",
             f"Each lobe's preset at {page.res(args.error_resolution)}, the Principled term set, against "
             f"Cycles ({args.reference_samples} samples per pixel, pixel centres; *transport*: direct light "
             "only, or with the bounces a refraction needs: 8 transmission bounces, none diffuse or glossy) "
             "as the preset is shipped: its lights cast shadows, the world lights it. *Mean rel.*: the mean "
             "relative error of the lit pixels' luminance; *FLIP*: mean HDR-FLIP (0: the same, 1: as "
             "different as can be). EEVEE at 16 samples per pixel. *Ours, lobe off*: our image with the lobe "
             "off against Cycles' with it (what drawing the lobe gains); *the lobe in Cycles*: Cycles' image "
             "with the lobe off against with it (how much the lobe shows in the scene).", "",
             *page.table(["lobe", "preset", "drawn", "ours: mean rel.", "ours: FLIP", "EEVEE: mean rel.",
                          "EEVEE: FLIP", "ours, lobe off: rel. / FLIP", "the lobe in Cycles: rel. / FLIP",
                          "transport"], rows), ""]
    return lines, found


# --- the figure -----------------------------------------------------------------------------------


def _figure(path: Path, ratios: dict, errors: dict, counts) -> Path:
    import numpy as np

    plt = plots.pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 3.8))
    labels = list(ratios)
    x = np.arange(len(labels))
    keys = [*counts, "scene"]
    width = 0.8 / len(keys)
    for k, key in enumerate(keys):
        values = [ratios[label].get(key, (math.nan, math.nan)) for label in labels]
        left.bar(x + (k - (len(keys) - 1) / 2) * width, [on / off for on, off in values], width,
                 label=f"{key} point lights" if key != "scene" else "preset scene")
    left.axhline(1.0, color="black", linewidth=0.6)
    left.set_xticks(x, labels, rotation=30, ha="right", fontsize=8)
    left.set_ylabel("frame time, lobe on / off")
    left.legend(fontsize=7)
    names = list(errors)
    x = np.arange(len(names))
    for k, (who, colour) in enumerate((("ours", "C0"), ("eevee", "C1"), ("off", "C7"))):
        right.bar(x + (k - 1) * 0.27, [errors[n][who].flip for n in names], 0.27, color=colour,
                  label={"ours": "Shading Lab", "eevee": "EEVEE 16 spp", "off": "Shading Lab, lobe off"}[who])
    right.set_xticks(x, names, rotation=30, ha="right", fontsize=8)
    right.set_ylabel("mean HDR-FLIP against Cycles")
    right.legend(fontsize=7)
    fig.tight_layout()
    return plots.save(fig, path, dpi=110)


def run(ctx) -> None:
    args = ctx.args
    lobes = lobe_presets()
    cost, ratios = _cost(args, ctx, lobes)
    errors, found = _errors(args, ctx, lobes)
    counts = [int(n) for n in str(args.lights).split(",")]
    _figure(ctx.out / FIGURE, ratios, found, counts)
    not_yet = [_label(lobe) for lobe in lobes if not drawn(lobe)]
    ctx.page("The Principled BSDF's lobes", [
        "What each of the Principled BSDF's lobes costs against the Principled set without it, and how "
        "close each comes to Cycles, ours and EEVEE's side by side, on the lobe's preset scene "
        "([Presets](../presets.md#lobes)).", "",
        *([f"Not drawn yet (their presets render as their base): {', '.join(not_yet)}.", ""]
          if not_yet else []),
        f"![Each lobe's frame-time ratio and its error against Cycles]({FIGURE})", "",
        *cost, *errors])
