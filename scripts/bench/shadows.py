"""Shadows: the cost of each shadowed light kind, map size against error, soft against hard, and
EEVEE (shadows on) beside us, all against Cycles.

Scene: the shadow tests' sphere and torus over a white Lambert ground (tests/test_shadows.py),
one light casting: point, spot or sun, hard (radius 0) or soft (point 0.3 m, spot 0.3 m, sun 4
degrees). Error: the image's mean absolute luminance error over Cycles' mean (direct light only,
shadows on, ``--reference-samples`` spp); *state* the fraction of pixels whose lit/shadowed state
(radiance with shadows over without > 0.5) differs from Cycles', a one-pixel band around Cycles'
shadow edges left out. Per case, ours without shadows, with each map size, and EEVEE at 1 and 16
samples are rendered round-robin in one process after a warm-up round (the warm-up's images are
compared; a render after another configuration's is preceded by an untimed one of its own, so
that maps are not reallocated in a timed render nor EEVEE's programs displace ours); ours: the
engine's own time (``engine.last_timings``: extraction, shadow maps, draw, read-back), EEVEE's
whole-render wall time; medians of ``--frames``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from .harness import choices, engines, page, standard, timing

PAGE = "shadows.md"
QUICK = dict(resolution="160x90", frames=1, reference_samples=16, kinds="SUN", map_sizes="512,1024",
             peers="eevee-1")
CASES = (("POINT", 0.0), ("POINT", 0.3), ("SPOT", 0.0), ("SPOT", 0.3), ("SUN", 0.0), ("SUN", 4.0))
MAP_SIZES = ("512", "1024", "2048", "4096")
EEVEE = ("eevee-1", "eevee-16")


def options(parser) -> None:
    standard(parser, resolution="640x360", frames=5, reference_samples=256, peers=",".join(EEVEE))
    parser.add_argument("--kinds", type=choices(("POINT", "SPOT", "SUN")), default="POINT,SPOT,SUN",
                        help="the light kinds (default: all)")
    parser.add_argument("--map-sizes", type=choices(MAP_SIZES), default=",".join(MAP_SIZES),
                        help="shadow map sizes; 1024 is the first table's (default: all)")


def _luminance(image):
    return image[..., :3].mean(-1)


def _error(ours, ref) -> float:
    import numpy as np

    return float(np.abs(_luminance(ours) - _luminance(ref)).mean() / _luminance(ref).mean())


def _state_error(ours_on, ours_off, ref_on, ref_off) -> float:
    import numpy as np
    from test_shadows import _edge_band

    def visible(on, off):
        lum_on, lum_off = _luminance(on), _luminance(off)
        return np.where(lum_off > 1e-3 * lum_off.max(), lum_on / np.maximum(lum_off, 1e-30), 1.0) > 0.5

    state_ours, state_ref = visible(ours_on, ours_off), visible(ref_on, ref_off)
    seen = _luminance(ref_off) > 0.02 * _luminance(ref_off).max()
    considered = seen & ~_edge_band(state_ref)
    return float((state_ours != state_ref)[considered].mean())


def measure(kind: str, size: float, args, tmp: Path, progress) -> dict:
    """One light: ours without shadows and with each map size, EEVEE, Cycles with and without."""
    import bpy
    from test_shadows import _scene

    scene, light = _scene(kind, size, resolution=args.resolution[0])
    scene.render.resolution_y = args.resolution[1]
    light.data.use_shadow = False
    ref_off = engines.cycles(scene, args.reference_samples)[0]
    light.data.use_shadow = True
    ref = engines.cycles(scene, args.reference_samples)[0]
    images = {}

    def render(item):
        light.data.use_shadow = item != "off"
        scene.render.engine = engines.OURS
        if item in MAP_SIZES:
            scene.shading_lab.shadow_map_size = item
        elif item in args.peers:
            engines.use(scene, item)
        if item not in images:  # the warm-up round: the image compared
            images[item] = engines.image(scene, tmp / f"{kind}_{size}_{item}.exr")[0]
            return {}
        return timing.render_timed(scene)

    items = ["off", *args.map_sizes, *args.peers]
    times = dict(zip(items, timing.round_robin(items, args.frames, render, progress, f"{kind} {size}",
                                               state_of=lambda item: item)))
    scene.shading_lab.shadow_map_size = "1024"
    off = images["off"]
    row = dict(kind=kind, size=size, ms_off=times["off"]["total_ms"], error_unshadowed=_error(off, ref),
               sizes={m: dict(ms=times[m]["total_ms"], error=_error(images[m], ref),
                              state=_state_error(images[m], off, ref, ref_off)) for m in args.map_sizes},
               **{peer: dict(ms=times[peer]["wall_ms"], error=_error(images[peer], ref))
                  for peer in args.peers})
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return row


def label(row) -> str:
    return f"{row['kind'].lower()} {'hard' if row['size'] == 0 else row['size']}"


def run(ctx) -> None:
    args = ctx.args
    args.map_sizes = sorted({*args.map_sizes, "1024"}, key=int)
    with tempfile.TemporaryDirectory() as tmp:
        rows = [measure(kind, size, args, Path(tmp), ctx.progress)
                for kind, size in CASES if kind in args.kinds]
    per_kind = []
    for r in rows:
        s = r["sizes"]["1024"]
        per_kind.append([label(r), f"{r['ms_off']:.1f}", f"{s['ms']:.1f}", f"{s['ms'] - r['ms_off']:.1f}",
                         f"{r['error_unshadowed']:.2%}", f"{s['error']:.2%}", f"{s['state']:.3%}",
                         *(f"{r[peer]['ms']:.0f} / {r[peer]['error']:.2%}" for peer in args.peers)])
    ctx.page("Shadows", [
        f"{page.res(args.resolution)}, Cycles {args.reference_samples} spp, medians of {args.frames} frames. "
        "The shadow tests' sphere and torus over a white Lambert ground, one light casting (soft: point "
        "and spot radius 0.3 m, sun 4°). Error: mean |luminance − Cycles'| / Cycles' mean (direct light "
        "only, shadows on); *state*: pixels whose lit/shadowed state differs from Cycles' outside a "
        "one-pixel band around its shadow edges. Ours: the engine's own time (shadow maps drawn every "
        "frame here: a final render); EEVEE: whole-render wall time.", "",
        "## Cost and error per light kind (map 1024)", "",
        *page.table(["light", "no shadows ms", "shadows ms", "shadow cost ms", "error without", "error with",
                     "state", *(f"{engines.label(peer)} ms / error" for peer in args.peers)], per_kind), "",
        "## Map size against error", "",
        *page.table(["light", *(f"{m} ms / error / state" for m in args.map_sizes)],
                    [[label(r), *(f"{r['sizes'][m]['ms']:.1f} / {r['sizes'][m]['error']:.2%} / "
                                  f"{r['sizes'][m]['state']:.3%}" for m in args.map_sizes)] for r in rows])])
