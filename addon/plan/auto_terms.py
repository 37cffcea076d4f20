"""The Auto term set: per material, the cheapest physically based terms whose predicted error
against the Principled set stays within the artist's bound.

The prediction looks at what each material really shows: points on its surfaces, drawn where they
cover pixels (area x n.v / d^2, inside the view), with their normals, the view and the scene's
lights, its textures' texel values and what its procedural textures give there (the graph's
nodes evaluated in numpy, ``materials.evaluate``). At those points the numpy twin (``shading.py``, itself
checked against the GLSL, Mitsuba and Cycles) shades every candidate term set and the Principled
set; the error is Delta E_ITP (ITU-R BT.2124) between the two, on the radiance as a display of
100 cd/m^2 white and 0.1 cd/m^2 black shows it after the exposure, and its ``quantile`` over the
points (the 99th percentile by default) is the material's predicted error. Candidates are tried
cheap -> accurate (``term_costs.json``, measured by ``scripts/bench/term_costs.py``); the first whose
predicted error, times a calibrated margin, is within the bound wins, else the Principled set.
Shadows are left out of the prediction where the world is black (they darken candidate and
reference alike); with the world occluded, a share of the points lies in creases
(``CREASE_SHARE``): there the world's light is occluded and the lights' blocked, so what remains is
the candidates' world terms alone, which differ most there and are seen near black, where Delta
E_ITP is steepest.

Where the scene samples an image world's specular, the world joins the candidates: each term set
also with the split sum (``SPLIT_SUM``), lit by the image world's twin (``environment.world_maps``)
against the reference sampled as the GPU samples it.

The choice is made when the scene is read (``extract.snapshot``), once per material, and fixed
into the material's program by defines: on this machine's rasteriser both sides of every branch
run, so only a separate program saves a term's cost. Pure numpy: no ``bpy``, no ``gpu``.
"""

from __future__ import annotations

import json
import math
import zlib
from collections import OrderedDict
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path
from typing import Callable

import numpy as np

from ..materials import evaluate
from ..materials.convert import LUMA
from ..reference import environment, shading
from ..reference.brdf import half_vector
from ..scene.snapshot import (
    CLOSURE_LOBES,
    LOBES,
    ImageData,
    MaterialParams,
    Snapshot,
    Terms,
    World,
)
from . import programs

#: The reference every candidate's error is measured against.
REFERENCE = Terms(principled=True)
#: Candidate term sets, by name: each a step from the default terms towards the Principled set
#: (what Cycles' Principled BSDF adds: exact Fresnel, multiple scattering, the base layered under
#: the specular's albedo, and its dielectric lobe's own compensation and world reflection). Their
#: order and costs come from ``term_costs.json``.
CANDIDATE_TERMS = {
    "DEFAULT": Terms(),
    "MULTISCATTER": Terms(multiscatter=True),
    "EXACT_FRESNEL": Terms(fresnel="EXACT"),
    "EXACT_MULTISCATTER": Terms(fresnel="EXACT", multiscatter=True),
    "LAYERED_MULTISCATTER": Terms(diffuse="LAYERED", multiscatter=True),
    "LAYERED_EXACT_MULTISCATTER": Terms(fresnel="EXACT", diffuse="LAYERED", multiscatter=True),
    "PRINCIPLED": REFERENCE,
}
LABELS = {
    "DEFAULT": "Schlick, GGX, Smith, Lambert",
    "MULTISCATTER": "default + multiple scattering",
    "EXACT_FRESNEL": "default with exact Fresnel",
    "EXACT_MULTISCATTER": "exact Fresnel + multiple scattering",
    "LAYERED_MULTISCATTER": "layered diffuse + multiple scattering",
    "LAYERED_EXACT_MULTISCATTER": "layered diffuse, exact Fresnel, multiple scattering",
    "PRINCIPLED": "Principled set",
}
#: What each candidate leaves out of the Principled set (for "why" in the panel), in the order
#: they are named.
TERMS_OF_PRINCIPLED = ("multiple scattering", "layered diffuse", "exact Fresnel",
                       "Principled dielectric lobe")
MISSING = {
    "DEFAULT": TERMS_OF_PRINCIPLED,
    "MULTISCATTER": ("layered diffuse", "exact Fresnel", "Principled dielectric lobe"),
    "EXACT_FRESNEL": ("multiple scattering", "layered diffuse", "Principled dielectric lobe"),
    "EXACT_MULTISCATTER": ("layered diffuse", "Principled dielectric lobe"),
    "LAYERED_MULTISCATTER": ("exact Fresnel", "Principled dielectric lobe"),
    "LAYERED_EXACT_MULTISCATTER": ("Principled dielectric lobe",),
    "PRINCIPLED": (),
}
#: The Principled BSDF's lobes (``snapshot.LOBES``), which the Principled set alone draws, named for
#: "why".
LOBE_LABELS = {"SPECULAR_TINT": "specular tint", "COAT": "coat", "SHEEN": "sheen", "THIN_FILM": "thin film",
               "ANISOTROPY": "anisotropy", "TRANSLUCENT": "translucent",
               "SUBSURFACE": "subsurface", "TRANSMISSION": "transmission",
               "DIFFUSE_ROUGHNESS": "Oren-Nayar diffuse", "VELVET": "velvet sheen", "TOON": "toon",
               "GLOSSY": "Glossy BSDF"}
#: The lobes the prediction's twin does not draw: a material with one takes the Principled set, which
#: alone draws it, unpredicted (its why names the lobe).
UNPREDICTED_LOBES = ("ANISOTROPY",)


def unpredicted_lobes(material: MaterialParams) -> tuple[str, ...]:
    """The labels of ``material``'s lobes in ``UNPREDICTED_LOBES``."""
    return tuple(LOBE_LABELS[lobe] for lobe in UNPREDICTED_LOBES if lobe in material.lobes)
COSTS_FILE = Path(__file__).with_name("term_costs.json")
#: Where a scene samples an image world's specular (World Specular: Sampled), the world joins the
#: candidates: each term set with the split sum instead, named with this suffix, cheaper than
#: any sampled one; the reference (and the last resort) stays the Principled set sampled. The
#: other sets sampled are left out: the sampling, not the terms, is most of their cost.
SPLIT_SUM = "+SPLIT_SUM"
#: The prediction's twin of the world (``environment.world_maps``): baked no wider than this, each
#: prefiltered level from this many lobe samples a point (the GPU: 1024 wide, 64-2048 samples);
#: the split sum's error against the sampled lobe is what it predicts, at 1024 points a material.
PREDICTION_WORLD_WIDTH = 512
PREDICTION_PREFILTER_SAMPLES = 128
#: Where the scene is on the split sum, every candidate and the reference read the same
#: prefiltered light, whose precision then matters little: 32 lobe samples a level gave the same
#: predictions as 128 (scripts/bench/auto_calibration.py --worlds split-sum, 63 materials: measured /
#: predicted 95th percentile 1.11 against 1.09, at most 1.38 against 1.39) in a quarter of the
#: time (a material's prediction ~140 -> ~40 ms).
SPLIT_SUM_PREFILTER_SAMPLES = 32


def base_name(name: str) -> str:
    """The term set of candidate ``name`` (without the world's split-sum suffix)."""
    return name[:-len(SPLIT_SUM)] if name.endswith(SPLIT_SUM) else name


def candidate_terms(name: str) -> Terms:
    return CANDIDATE_TERMS[base_name(name)]


def label(name: str) -> str:
    return LABELS[base_name(name)] + (", split-sum world" if name.endswith(SPLIT_SUM) else "")


def missing(name: str) -> tuple[str, ...]:
    """What candidate ``name`` leaves out of the reference."""
    return MISSING[base_name(name)] + (("sampled world specular",) if name.endswith(SPLIT_SUM) else ())

#: Default error bound. Delta E_ITP 1 is about one just-noticeable difference (BT.2124), but at 1
#: the benchmark's material_grid moved its mean FLIP against Cycles from 0.032 (Principled set)
#: to 0.039 (its floor on the multiple-scattering set); at 0.5 every preset's FLIP equalled the
#: Principled set's to four decimals (docs/bench/bench.md, 2026-12-02).
DEFAULT_BOUND = 0.5
DEFAULT_QUANTILE = 0.99
#: Points per material the prediction shades (~10 of them beyond the 99th percentile; with 512
#: the prediction moved by up to +-15 % with the points drawn).
SAMPLES = 1024
#: Points added where the lights' highlights are (a share of SAMPLES; ``_highlight_points``).
HIGHLIGHT_SHARE = 1.0 / 32.0
#: The predicted error is multiplied by this before it is held to the bound. Calibrated by
#: scripts/bench/auto_calibration.py (docs/bench/auto_calibration.md) on the random scenes of
#: tests/auto_scenes.py with seeds 1000-1029 (apart from the tests'), at bounds 0.5 and 4, measured
#: on every pixel of each material: where either error is >= 0.1, measured / predicted has its
#: 95th percentile at 1.14 under black or uniform worlds (93 pairs), 1.11 under image worlds on
#: the split sum (63), 1.42 sampled 16 a pixel (52); its maximum at 1.89, 1.38 and 2.17 (measured
#: 1.35 against 0.72 predicted, and 0.21 against 0.10: far within their bounds); all 900
#: materials within their bound (2026-12-03). First calibrated 2026-12-02 on the uniform worlds
#: alone: 95th percentile 1.14, maximum 1.64.
MARGIN = 1.25
#: A material keeps its set while that set's predicted error stays within this many times the
#: bound, and moves to a cheaper one only when that one is within the bound / HYSTERESIS: small
#: edits do not flip programs back and forth.
HYSTERESIS = 1.25
#: Lights the prediction shades per material (the brightest at its points; the rest add little).
MAX_LIGHTS = 16
#: The display the error is measured on: its white (cd/m^2 for radiance 1 after exposure) and its
#: black (a 1000:1 display; without one, PQ's steep foot makes 0.05 cd/m^2 against 0 a difference
#: of ~20 that no display shows).
WHITE_NITS = 100.0
BLACK_NITS = 0.1


@dataclass(frozen=True)
class Choice:
    """What Auto chose for one material: the candidate's name, its terms, its predicted error
    (Delta E_ITP at the quantile, before the margin), the term limiting it (the first one the
    cheaper candidates lacked) and why, and every candidate's predicted error."""

    name: str
    terms: Terms
    predicted: float
    limiting: str = ""
    reason: str = ""
    errors: tuple[tuple[str, float], ...] = ()
    samples: int = 0
    alone: str = ""  # the candidate it would have taken on its own, where merged into another's program
    #: what that merge costs a frame (ms on the cost table's machine); unpredicted (no ``errors``):
    #: the most any cheaper set could save it
    costs_ms: float = 0.0

    @property
    def label(self) -> str:
        return label(self.name)

    @property
    def environment_samples(self) -> int | None:
        """The material's World Specular with this choice: 0 (the split sum) for a split-sum
        candidate, else None (as it was)."""
        return 0 if self.name.endswith(SPLIT_SUM) else None


# --- the cost table ----------------------------------------------------------------------------

@lru_cache(maxsize=1)
def cost_table() -> dict:
    """``term_costs.json`` as shipped (candidates' frame times relative to the default terms, per
    light count); without it, every candidate costs as the order of ``CANDIDATE_TERMS`` says."""
    try:
        return json.loads(COSTS_FILE.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}


def relative_costs(lights: int, table: dict | None = None) -> dict[str, float]:
    """Each candidate's frame time over the default terms' at ``lights`` lights, interpolated in
    log light count between the measured counts (held beyond them)."""
    table = cost_table() if table is None else table
    counts = table.get("lights", [])
    out = {}
    for i, name in enumerate(CANDIDATE_TERMS):
        ratios = table.get("relative", {}).get(name)
        if not counts or not ratios:
            out[name] = 1.0 + 0.01 * i
            continue
        x = math.log(max(lights, 1))
        out[name] = float(np.interp(x, np.log(counts), ratios))
    return out


def candidate_order(lights: int, table: dict | None = None) -> list[str]:
    """Candidates cheap -> accurate at ``lights`` lights: those cheaper than the Principled set, by
    cost, then the Principled set (always the last resort: its error is 0)."""
    costs = relative_costs(lights, table)
    cheaper = [n for n in CANDIDATE_TERMS if n != "PRINCIPLED" and costs[n] < costs["PRINCIPLED"]]
    return sorted(cheaper, key=lambda n: (costs[n], list(CANDIDATE_TERMS).index(n))) + ["PRINCIPLED"]


#: A term set gets a shading program of its own only where the materials on it save that
#: program's first use (its compile and first draw: ``first_use_ms`` in term_costs.json) within
#: this many frames: about a second of viewport navigation here, or a short animation; a still
#: render pays the compile for one frame. On this machine a program's first use took 27 ms with
#: the driver's shader cache warm (~600 ms cold: the hdr preset's first render with Auto 2.0-2.2 s
#: against the Principled set's 1.3 s, one program more) while that preset's one metal on
#: multiple scattering saved ~0.3 ms a frame; no per-frame cost of a second program could be
#: measured (+-5 % noise), so only the compile counts (2026-12-02; 11 ms warm on 2026-12-05).
PAYBACK_FRAMES = 10


def shading_ms(lights: int, pixels: int, table: dict | None = None) -> dict[str, float]:
    """Each candidate's time to shade ``pixels`` pixels under ``lights`` lights (ms, as
    term_costs.py measured the default terms over its whole view, scaled by the pixel count);
    empty without a measured table."""
    table = cost_table() if table is None else table
    counts, base = table.get("lights"), table.get("draw_ms", {}).get("DEFAULT")
    if not counts or not base or not table.get("pixels"):
        return {}
    default = float(np.interp(math.log(max(lights, 1)), np.log(counts), base)) * pixels / table["pixels"]
    return {name: default * ratio for name, ratio in relative_costs(lights, table).items()}


def world_ms(samples: int, pixels: int, table: dict | None = None) -> tuple[float, float] | None:
    """(split sum, sampled ``samples`` per pixel): what an image world's light adds to the
    frame time at ``pixels`` pixels (term_costs.py's ``world_ms``: the Principled set under the
    forest world less under the black one, in one run; linear in the samples between and beyond
    the measured counts, never below the split sum); None without a measured table."""
    table = cost_table() if table is None else table
    world = table.get("world_ms")
    if not world or "black" not in world or not table.get("pixels"):
        return None
    counts = sorted(int(n) for n in world["sampled"])
    times = [world["sampled"][str(n)] for n in counts]
    slope = (times[-1] - times[0]) / (counts[-1] - counts[0]) if len(counts) > 1 else 0.0
    sampled = max(times[0] + slope * (samples - counts[0]), world["split_sum"])
    scale = pixels / table["pixels"]
    return (world["split_sum"] - world["black"]) * scale, (sampled - world["black"]) * scale


def merge_small_savings(chosen: dict[str, str], allowed: dict[str, list[str]], shares: dict[str, float],
                        program: Callable[[str, str], object], fixed: set, frame_ms: dict[str, float],
                        first_use_ms: float, payback_frames: float = PAYBACK_FRAMES) -> dict[str, str]:
    """Auto's choices with the programs that do not pay for themselves merged away.

    ``chosen``: material -> candidate; ``allowed``: material -> the candidates within its bound;
    ``shares``: of the view each covers; ``program(material, candidate)``: the program it would
    draw with; ``fixed``: the programs other materials draw with anyway; ``frame_ms``: each
    candidate's full-view shading time. Greedily, the program whose materials save the least
    against their cheapest allowed candidate among the other programs in use is dropped while
    that saving, over ``payback_frames`` frames, is less than a program's ``first_use_ms``."""
    chosen = dict(chosen)
    if not frame_ms or first_use_ms <= 0.0:
        return chosen
    while True:
        in_use: dict = {}
        for key, name in chosen.items():
            in_use.setdefault(program(key, name), []).append(key)
        best = None
        for prog, members in in_use.items():
            if prog in fixed:
                continue
            moves, loss = {}, 0.0
            for key in members:
                targets = [n for n in allowed[key] if n != chosen[key] and
                           (program(key, n) in fixed or program(key, n) in in_use)]
                if not targets:
                    break
                target = min(targets, key=lambda n: frame_ms[n])
                moves[key] = target
                loss += shares[key] * (frame_ms[target] - frame_ms[chosen[key]])
            else:
                if loss * payback_frames < first_use_ms and (best is None or loss < best[0]):
                    best = (loss, moves)
        if best is None:
            return chosen
        chosen.update(best[1])


# --- Delta E_ITP (ITU-R BT.2124) ---------------------------------------------------------------

#: BT.709 -> BT.2020 primaries (ITU-R BT.2087), then BT.2100's RGB -> LMS.
_REC709_TO_2020 = np.array([[0.6274, 0.3293, 0.0433],
                            [0.0691, 0.9195, 0.0114],
                            [0.0164, 0.0880, 0.8956]])
_RGB2020_TO_LMS = np.array([[1688.0, 2146.0, 262.0],
                            [683.0, 2951.0, 462.0],
                            [99.0, 309.0, 3688.0]]) / 4096.0
_LMS_TO_ICTCP = np.array([[2048.0, 2048.0, 0.0],
                          [6610.0, -13613.0, 7003.0],
                          [17933.0, -17390.0, -543.0]]) / 4096.0


def pq_encode(nits):
    """SMPTE ST 2084's inverse EOTF: absolute luminance (cd/m^2, clipped to [0, 10000]) -> [0, 1]."""
    m1, m2 = 2610.0 / 16384.0, 2523.0 / 4096.0 * 128.0
    c1, c2, c3 = 3424.0 / 4096.0, 2413.0 / 4096.0 * 32.0, 2392.0 / 4096.0 * 32.0
    y = np.clip(np.asarray(nits, np.float64) / 10000.0, 0.0, 1.0) ** m1
    return ((c1 + c2 * y) / (1.0 + c3 * y)) ** m2


def ictcp(rgb, white_nits: float = WHITE_NITS, black_nits: float = BLACK_NITS):
    """ICtCp (BT.2100, PQ) of scene-linear BT.709 ``rgb`` shown with 1.0 at ``white_nits`` on a
    display whose black is ``black_nits``."""
    rgb = np.maximum(np.asarray(rgb, np.float64), 0.0) * white_nits + black_nits
    lms = rgb @ (_RGB2020_TO_LMS @ _REC709_TO_2020).T
    return pq_encode(lms) @ _LMS_TO_ICTCP.T


def delta_e_itp(a, b, white_nits: float = WHITE_NITS, black_nits: float = BLACK_NITS):
    """BT.2124's Delta E_ITP = 720 sqrt(dI^2 + (dCt / 2)^2 + dCp^2) per pixel (1: about one
    just-noticeable difference)."""
    d = ictcp(a, white_nits, black_nits) - ictcp(b, white_nits, black_nits)
    return 720.0 * np.sqrt(d[..., 0] ** 2 + 0.25 * d[..., 1] ** 2 + d[..., 2] ** 2)


# --- what a material shows ---------------------------------------------------------------------

@dataclass
class Samples:
    """Points on one material's surfaces, distributed as its pixels are: world positions,
    normals (facing the camera), view directions, and the material with per-point arrays where
    textures vary it."""

    p: np.ndarray
    n: np.ndarray
    v: np.ndarray
    material: MaterialParams
    share: float = 0.0  # of the view's pixels it covers (what other objects hide counted too)

    def __len__(self) -> int:
        return len(self.p)


def _rng(name: str) -> np.random.Generator:
    return np.random.default_rng(zlib.crc32(name.encode("utf-8")))


def material_users(snapshot: Snapshot) -> dict[str, list]:
    """Material key -> the items drawing it (in any slot), in an order of the geometry itself, not
    of its listing (the depsgraph lists instances, and a mesh its triangles, in no fixed order;
    geometry keys hold addresses): the same scene, the same points."""
    def order(item):
        return item.geometry.rsplit(":", 1)[0], np.asarray(item.matrix, np.float32).tobytes()

    users: dict[str, list] = {}
    for item in sorted(snapshot.items, key=order):
        for key in dict.fromkeys(item.materials):
            users.setdefault(key, []).append(item)
    return users


def _triangles(snapshot: Snapshot, key: str, items, rng, per_item: int = 20000, coordinates: bool = False):
    """(corners (T, 3, 3) world positions, corner normals (T, 3, 3), weight per triangle) of the
    triangles drawn with material ``key`` by ``items`` (``material_users``'); a mesh with more
    than ``per_item`` of them contributes a uniform random subset, weighted up. ``coordinates``:
    and a fourth, the corners' coordinates a graph reads ({"generated", "object", "uv"}: (T, 3, 3)
    each: the object's texture space, object space, the active UV map or 0)."""
    corners, normals, weights = [], [], []
    coords = {"generated": [], "object": [], "uv": []}
    for item in items:
        geometry = snapshot.geometries.get(item.geometry)
        if geometry is None:
            continue
        for slot, first, count in geometry.ranges:
            mkey = item.materials[slot] if slot < len(item.materials) else item.materials[-1]
            if mkey != key or count < 3:
                continue
            tri = np.arange(first // 3, (first + count) // 3)
            scale = 1.0
            if len(tri) > per_item:
                scale = len(tri) / per_item
                tri = rng.choice(tri, per_item, replace=False)
            rows = geometry.indices[(tri[:, None] * 3 + np.arange(3)).ravel()]
            m = np.asarray(item.matrix, np.float64)
            pos = geometry.positions[rows].astype(np.float64) @ m[:3, :3].T + m[:3, 3]
            nm = np.asarray(item.normal_matrix, np.float64)[:3, :3]
            nrm = geometry.normals[rows].astype(np.float64) @ nm.T
            pos, nrm = pos.reshape(-1, 3, 3), nrm.reshape(-1, 3, 3)
            by_place = slice(None)
            if scale == 1.0:  # all of them: sorted by centroid
                centroid = pos.mean(axis=1)
                by_place = np.lexsort(centroid.T[::-1])
                pos, nrm = pos[by_place], nrm[by_place]
            if coordinates:
                local = geometry.positions[rows].astype(np.float64).reshape(-1, 3, 3)[by_place]
                location, size = (np.asarray(v, np.float64) for v in item.texspace)
                # glsl/graph_surface.glsl's graph_generated (a zero size: guarded by 1, as no texture space)
                coords["generated"].append((local - location) / np.where(size != 0.0, size, 1.0) * 0.5 + 0.5)
                coords["object"].append(local)
                uv = np.zeros((len(rows), 3))
                if geometry.uvs is not None:
                    uv[:, :2] = geometry.uvs[rows]
                coords["uv"].append(uv.reshape(-1, 3, 3)[by_place])
            corners.append(pos)
            normals.append(nrm)
            weights.append(np.full(len(tri), scale))
    if not corners:
        return None
    found = np.concatenate(corners), np.concatenate(normals), np.concatenate(weights)
    return found + ({k: np.concatenate(v) for k, v in coords.items()},) if coordinates else found


def _texels(image: ImageData, count: int, rng) -> np.ndarray:
    """``count`` random texels of ``image`` (linear, rgba) and its extremes by luminance."""
    pixels = environment.linear_pixels(image).reshape(-1, 4)
    picks = pixels[rng.integers(0, len(pixels), count)]
    luminance = pixels[:, :3] @ np.array([0.2126, 0.7152, 0.0722])
    picks[:2] = pixels[[int(np.argmin(luminance)), int(np.argmax(luminance))]]
    return picks


def material_samples(snapshot: Snapshot, key: str, count: int = SAMPLES, camera=None,
                     users: dict[str, list] | None = None) -> Samples | None:
    """Points where material ``key`` covers pixels (None: it covers none): area-sampled on its
    triangles, then resampled by how many pixels each covers (n.v, and 1 / d^2 in perspective),
    inside the view (``camera``'s, else the snapshot's); textured inputs take random texels of
    their images, inputs a procedural texture gives its value at each point (the compiled graph's
    nodes in numpy: ``materials.evaluate``). ``users``: ``material_users(snapshot)``, when the
    caller has it."""
    rng = _rng(key)
    users = material_users(snapshot) if users is None else users
    material = snapshot.materials[key]
    procedural = [entry for entry in (material.graph.procedural if material.graph is not None else ())
                  if entry[0] not in material.graph_keep]
    found = _triangles(snapshot, key, users.get(key, ()), rng, coordinates=bool(procedural))
    if found is None:
        return None
    corners, normals, tri_weight = found[:3]
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = 0.5 * np.linalg.norm(np.cross(e1, e2), axis=-1) * tri_weight
    if not np.any(area > 0.0):
        return None
    pool = 8 * count
    tri = rng.choice(len(area), pool, p=area / area.sum())
    r1, r2 = rng.random(pool), rng.random(pool)
    flip = r1 + r2 > 1.0
    r1, r2 = np.where(flip, 1.0 - r1, r1), np.where(flip, 1.0 - r2, r2)
    bary = np.stack([1.0 - r1 - r2, r1, r2], -1)
    p = np.einsum("ij,ijk->ik", bary, corners[tri])
    n = np.einsum("ij,ijk->ik", bary, normals[tri])
    face = np.cross(e1[tri], e2[tri])
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    n = np.where(length > 1e-12, n / np.maximum(length, 1e-30),
                 face / np.maximum(np.linalg.norm(face, axis=-1, keepdims=True), 1e-30))
    camera = camera or snapshot.camera
    if camera.is_perspective:
        to_eye = np.asarray(camera.position, np.float64) - p
        d2 = np.maximum(np.sum(to_eye * to_eye, axis=-1), 1e-12)
        v = to_eye / np.sqrt(d2)[:, None]
    else:
        d2 = np.ones(pool)
        v = np.broadcast_to(-np.asarray(camera.forward, np.float64), p.shape).copy()
    NoV = np.sum(n * v, axis=-1)
    n = np.where((NoV < 0.0)[:, None], -n, n)  # back faces shade with the normal flipped (as Cycles)
    clip = np.c_[p, np.ones(pool)] @ camera.view_projection.astype(np.float64).T
    w = clip[:, 3]
    inside = (w > 0.0) if camera.is_perspective else np.ones(pool, bool)
    inside &= np.all(np.abs(clip[:, :3]) <= np.abs(w)[:, None] * (1.0 + 1e-6), axis=-1)
    weight = np.where(inside, np.abs(NoV) / d2, 0.0)
    if not np.any(weight > 0.0):
        return None
    share = _view_share(camera, p, weight, NoV > 0.0, area.sum() / pool)
    pick = rng.choice(pool, count, p=weight / weight.sum())
    highlights = _highlight_points(snapshot, p, n, v, weight, int(HIGHLIGHT_SHARE * count))
    pick = np.concatenate([pick, highlights])
    changes = {}
    textured = material.graph.textured if material.graph is not None else {}
    for field, (image_key, channel) in sorted(textured.items()):
        image = snapshot.images.get(image_key)
        if image is None or field in material.graph_keep:
            continue
        texels = _texels(image, len(pick), rng)  # a texel for every point
        if channel is None:
            values = texels[:, :3]
        elif channel == "luma":
            values = texels[:, :3] @ np.array(LUMA)
        else:
            values = texels[:, channel]
        changes[field] = np.clip(values, 0.0, None if field == "base_color" else 1.0)
    if procedural:  # the procedurals' values where the points are (the compiled graph's, in numpy)
        at = {k: np.einsum("ij,ijk->ik", bary[pick], corners_of[tri[pick]]).astype(np.float32)
              for k, corners_of in found[3].items()}
        points = evaluate.Points(at["generated"], at["object"], at["uv"])
        for field, flat, source in procedural:
            values = evaluate.evaluate(flat, source, points)
            if values is not None:
                values = values[:, :3] if field == "base_color" else values
                changes[field] = np.clip(np.nan_to_num(values.astype(np.float64)), 0.0,
                                         None if field == "base_color" else 1.0)
    if changes:
        material = replace(material, **changes)
    return Samples(p[pick], n[pick], v[pick], material, share)


def _view_share(camera, p, weight, front, area_per_point: float) -> float:
    """The share of the view's pixels the pool points ``p`` cover, each standing for
    ``area_per_point`` m^2 and weighted by |n.v| / d^2 (0 outside the view): its projected area
    on the image plane at distance 1 (a solid angle over cos^3 of the angle off the axis, in
    perspective) over the plane's 4 / (P00 P11), of its front faces (``front``) or of its back
    faces, whichever cover more (a closed surface's back faces are hidden behind its front; an
    open one seen from behind shows its back). Other objects in front are not known here."""
    projection = np.asarray(camera.projection, np.float64)
    plane = 4.0 / max(abs(projection[0, 0] * projection[1, 1]), 1e-12)
    if camera.is_perspective:
        to_point = p - np.asarray(camera.position, np.float64)
        d = np.maximum(np.linalg.norm(to_point, axis=-1), 1e-12)
        cos_axis = np.clip(to_point @ np.asarray(camera.forward, np.float64) / d, 1e-3, 1.0)
        weight = weight / cos_axis ** 3
    covered = max(np.sum(weight[front]), np.sum(weight[~front]))
    return float(min(covered * area_per_point / plane, 1.0))


def _highlight_points(snapshot: Snapshot, p, n, v, weight, count: int) -> np.ndarray:
    """Indices of the ``count`` visible pool points nearest a light's mirror direction (largest
    n.h over the lights): a sharp highlight covers few pixels, and few random points, but decides
    the high quantiles; adding them errs on the side of accuracy."""
    if count <= 0 or not snapshot.lights:
        return np.zeros(0, int)
    best = np.full(len(p), -np.inf)
    for light in snapshot.lights[:MAX_LIGHTS]:
        if light.kind == "SUN":
            l = -np.broadcast_to(np.asarray(light.direction, np.float64), p.shape)
        else:
            l = np.asarray(light.position, np.float64) - p
        l = l / np.maximum(np.linalg.norm(l, axis=-1, keepdims=True), 1e-30)
        best = np.maximum(best, np.sum(n * half_vector(l, v, n), axis=-1))
    best = np.where(weight > 0.0, best, -np.inf)
    return np.argsort(best)[::-1][:count]


def world_radiance(world: World) -> np.ndarray:
    """The mean radiance (rgb) of the world's lighting field over the sphere (its suns excluded:
    they are lights): the uniform world the prediction lights materials with where the world has
    no images (``image_world``)."""
    if not world.lights:
        return np.zeros(3)
    directions = _sphere_directions(256)
    threshold = world.threshold if world.suns else 0.0
    return environment.world_radiance(world.lighting, directions, threshold).mean(0)


@lru_cache(maxsize=4)
def _sphere_directions(count: int) -> np.ndarray:
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    phi = math.pi * (3.0 - math.sqrt(5.0)) * i
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], -1)


# --- prediction and choice ---------------------------------------------------------------------

#: With the world occluded, this share of the samples is taken to lie in a crease (diffuse
#: visibility CREASE_AO, the reflection direction blocked, the lights shadowed): candidates whose
#: world term treats occlusion differently from the Principled set's (multiple scattering lit by
#: the occluded irradiance, not by the occluded reflection) differ most there. With the lights
#: left on at those points, a metal's crease pixels facing the ground (the Principled set 0, the
#: multiple-scattering set 0.001: Delta E_ITP 12.8 on a display with a 0.1 cd/m^2 black) were
#: predicted at 2.2 (random scene 42, 2026-12-02).
CREASE_SHARE = 0.1
CREASE_AO = 0.5
#: Under an image world (``SPLIT_SUM`` candidates), a further share of the samples is taken to lie
#: in the lights' shadows, the world unoccluded: the split sum's error against the sampled lobe is
#: seen there against the world's light alone, darker than in the light. Without it, a ground in
#: the shadow of spheres under the sunset world's sun was predicted at 0.44 and measured at 5.1
#: (random scene 2011, bound 4, 2026-12-03).
SHADOW_SHARE = 0.1


def radiance(samples: Samples, lights, terms: Terms, world: np.ndarray | None = None,
             occlusion: bool = False, irradiance: list | None = None, memo: dict | None = None,
             image: tuple | None = None, prefilter_samples: int = PREDICTION_PREFILTER_SAMPLES) -> np.ndarray:
    """(N, 3) radiance at the samples with ``terms``: the lights (no shadows), the uniform world
    ``world`` or (``image``: the twin's maps, the world samples per pixel, 0 for the split sum,
    and the diffuse mode) the image world itself; when ``occlusion``, the first CREASE_SHARE of
    the samples lie in creases (the world occluded, the lights blocked); under an image world, the
    next SHADOW_SHARE in the lights' shadows; ``prefilter_samples``: the lobe samples of each
    prefiltered level the split sum reads. ``irradiance``,
    ``memo``: what ``shading.shade`` and the world's twin can share between the candidates
    shading the same samples."""
    s = shading.Surface(samples.p, samples.n, samples.v, samples.material)
    c = shading.shade("PBR", s, list(lights), terms=terms, irradiance=irradiance, memo=memo)
    lit = image is not None or (world is not None and np.any(world > 0.0))
    if lit:
        ao, specular_ao = np.ones(len(samples)), np.ones(len(samples))
        index = np.arange(len(samples))
        creases = CREASE_SHARE * len(samples) if occlusion else 0.0
        if occlusion:
            creased = index < creases
            ao, specular_ao = np.where(creased, CREASE_AO, 1.0), np.where(creased, 0.0, 1.0)
            c = np.where(creased[:, None], 0.0, c)  # the lights shadowed in creases
        if image is not None:
            shadowed = (index >= creases) & (index < creases + SHADOW_SHARE * len(samples))
            c = np.where(shadowed[:, None], 0.0, c)
            maps, count, diffuse = image
            world_memo = {} if memo is None else memo.setdefault(("world",), {})
            c = c + shading.shade_image_environment(s, maps, terms, count, diffuse, ao=ao,
                                                    specular_ao=specular_ao, memo=world_memo,
                                                    prefilter_samples=prefilter_samples)
        else:
            c = c + shading.shade_uniform_environment(s, world, terms, ao=ao, specular_ao=specular_ao)
    return c


def brightest_lights(samples: Samples, lights, count: int = MAX_LIGHTS):
    """The ``count`` lights bringing the most irradiance to the samples."""
    lights = list(lights)
    if len(lights) <= count:
        return lights
    power = [float(shading.light_irradiance(light, samples.p)[0].max(axis=-1).sum()) for light in lights]
    keep = sorted(np.argsort(power)[::-1][:count])
    return [lights[i] for i in keep]


def display_error(image: np.ndarray, reference: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """Delta E_ITP per point of ``image`` against ``reference`` radiance (rgb), after ``exposure``
    EV: what the bound is held to."""
    scale = 2.0 ** exposure
    return delta_e_itp(image[..., :3] * scale, reference[..., :3] * scale)


def quantile_error(candidate: np.ndarray, reference: np.ndarray, exposure: float = 0.0,
                   quantile: float = DEFAULT_QUANTILE) -> float:
    """``display_error`` at ``quantile`` over the samples."""
    error = display_error(candidate, reference, exposure)
    return float(np.quantile(error, quantile)) if error.size else 0.0


def limiting_term(name: str, material: MaterialParams, errors: dict[str, float], bound: float,
                  margin: float = MARGIN) -> tuple[str, str]:
    """(terms, why) a material needed beyond the default terms, with its deciding values: ("", "")
    when the default terms were within the bound (``name`` then won on cost alone); for the
    Principled set, what the most accurate other candidate still lacked."""
    cheapest = "DEFAULT" + SPLIT_SUM if "DEFAULT" + SPLIT_SUM in errors else "DEFAULT"
    if errors.get(cheapest, math.inf) * margin <= bound:
        return "", ""
    if name == "PRINCIPLED":
        others = [n for n in errors if n != "PRINCIPLED"]
        best = min(others, key=lambda n: errors[n]) if others else cheapest
        # the Principled BSDF's lobes the material has: only the Principled set draws them
        needed = tuple(LOBE_LABELS[lobe] for lobe in LOBES if lobe in material.lobes) + missing(best)
    else:
        needed = tuple(t for t in missing(cheapest) if t not in missing(name))
    kind = "metal" if np.mean(material.metalness) > 0.5 else "dielectric"
    detail = f"{kind}, roughness {float(np.mean(material.roughness)):.2f}"
    if set(needed) - {"multiple scattering", "sampled world specular"}:
        detail += f", F0 {float(np.mean(material.f0)):.3f}"
    return ", ".join(needed), detail


def predict(samples: Samples, lights, world: np.ndarray | None, order, exposure: float = 0.0,
            quantile: float = DEFAULT_QUANTILE, occlusion: bool = False,
            image: tuple | None = None) -> dict[str, float]:
    """Each candidate's predicted error (before the margin), in ``order``. ``image``: (the twin's
    maps, world samples per pixel, diffuse mode) of a scene lit by an image world: the world
    lights every candidate as the scene does (samples 0: the split sum), but the ``SPLIT_SUM``
    candidates, which it lights with the split sum; else the uniform ``world``."""
    lights = brightest_lights(samples, lights)
    irradiance = [shading.light_irradiance(light, samples.p) for light in lights]  # the same for all
    memo: dict = {}  # the area and sphere lights' lobe geometry, the world's light: the same for all

    def world_of(name: str):
        if image is None:
            return None
        return (image[0], 0 if name.endswith(SPLIT_SUM) else image[1], image[2])

    sampled = image is not None and image[1] > 0
    prefilter = PREDICTION_PREFILTER_SAMPLES if sampled else SPLIT_SUM_PREFILTER_SAMPLES
    reference = radiance(samples, lights, REFERENCE, world, occlusion, irradiance, memo,
                         world_of("PRINCIPLED"), prefilter)
    out = {}
    for name in order:
        if name == "PRINCIPLED":
            out[name] = 0.0
            continue
        out[name] = quantile_error(radiance(samples, lights, candidate_terms(name), world, occlusion,
                                            irradiance, memo, world_of(name), prefilter),
                                   reference, exposure, quantile)
    return out


def decide(errors: dict[str, float], order, bound: float, previous: str | None = None,
           margin: float = MARGIN) -> str:
    """The cheapest candidate in ``order`` within ``bound`` (with ``margin``); ``previous`` is
    kept while within HYSTERESIS x bound unless a cheaper one is within bound / HYSTERESIS."""
    fits = [n for n in order if errors[n] * margin <= bound]
    best = fits[0] if fits else "PRINCIPLED"
    if previous in errors and errors[previous] * margin <= bound * HYSTERESIS:
        if order.index(best) >= order.index(previous):
            return previous  # the new choice is no cheaper: stay
        if errors[best] * margin > bound / HYSTERESIS:
            return previous  # cheaper, but only just within: stay until clearly so
    return best


#: Predictions kept (least recently used dropped first): a scene rendered again (a re-render, the
#: benchmark's rounds, a viewport edit elsewhere) predicts nothing anew.
PREDICTIONS_KEPT = 256
_PREDICTIONS: OrderedDict = OrderedDict()


def _geometry_fingerprint(geometry) -> tuple:
    if geometry is None:
        return ()
    step = max(1, len(geometry.positions) // 97)
    return (len(geometry.positions), len(geometry.indices), geometry.positions[::step].tobytes(),
            geometry.normals[::step].tobytes())


def _prediction_key(snapshot: Snapshot, key: str, items, camera, world: bytes | tuple, order, exposure: float,
                    quantile: float, occlusion: bool) -> tuple:
    """Everything a material's prediction depends on: its parameters and images, the geometry
    drawn with it and where, the view, the lights, the world, the candidates."""
    material = snapshot.materials[key]
    images = tuple(id(snapshot.images.get(ref[0])) for _, ref in
                   sorted(material.graph.textured.items() if material.graph is not None else ()))
    geometry = tuple(sorted((item.geometry.rsplit(":", 1)[0],
                             _geometry_fingerprint(snapshot.geometries.get(item.geometry)),
                             np.asarray(item.matrix, np.float32).tobytes(), tuple(map(tuple, item.texspace)))
                            for item in items))
    view = (np.asarray(camera.view).tobytes(), np.asarray(camera.projection).tobytes(), camera.is_perspective)
    return (key, replace(material, terms=None), images, geometry, view, tuple(snapshot.lights),
            world, tuple(order), exposure, quantile, occlusion)


#: The twin's maps of the last worlds a prediction sampled (by content, as the GPU keeps its own).
_WORLD_MAPS: OrderedDict = OrderedDict()
WORLD_MAPS_KEPT = 2


def image_world(snapshot: Snapshot) -> tuple | None:
    """(the twin's maps, world samples per pixel, diffuse mode) where the scene's world lights it
    with images: the prediction lights the materials with the image itself, on the split sum where
    the scene uses it (samples 0), else sampled, the split sum then joining the candidates
    (``SPLIT_SUM``). None for a world without images (``world_radiance`` is exact there)."""
    if programs.environment_kind(snapshot.world) != "MAP":
        return None
    samples = max(int(snapshot.settings.environment_samples), 0)
    key = environment.field_key(snapshot.world.lighting, snapshot.world.threshold)
    maps = _WORLD_MAPS.pop(key, None)
    if maps is None:
        maps = environment.world_maps(snapshot.world, PREDICTION_WORLD_WIDTH)
    _WORLD_MAPS[key] = maps
    while len(_WORLD_MAPS) > WORLD_MAPS_KEPT:
        del _WORLD_MAPS[next(iter(_WORLD_MAPS))]
    return maps, samples, snapshot.settings.environment_diffuse


@dataclass
class _Prediction:
    """One material's points and, once made, its prediction (kept in ``_PREDICTIONS``)."""

    count: int  # points (0: it covers no pixel)
    seen: MaterialParams  # the material as the points saw it (textures' values)
    share: float  # of the view
    samples: Samples | None  # the points, until predicted
    errors: dict[str, float] | None = None


def choose(snapshot: Snapshot, bound: float = DEFAULT_BOUND, quantile: float = DEFAULT_QUANTILE,
           previous: dict[str, Choice] | None = None, camera=None,
           payback_frames: float | None = None) -> dict[str, Choice]:
    """Auto's choice for every physically based material of ``snapshot`` that follows the scene's
    terms (a material with its own term or model choices keeps them), seen from ``camera`` (the
    snapshot's by default; the viewport passes the view it last drew); then the programs that
    would not pay for their first use within ``payback_frames`` frames merged into others
    (``merge_small_savings``; PAYBACK_FRAMES by default; the programs ``previous`` drew are
    compiled already and so repay nothing more). Materials covering too little of the
    view for any cheaper set to repay a program, alone or all of them together, are predicted only
    where a cheaper program they could join is drawn anyway; else they take the Principled set
    unpredicted."""
    if snapshot.settings.model != "PBR":
        return {}
    order = candidate_order(len(snapshot.lights))
    image = image_world(snapshot)
    sampled = image is not None and image[1] > 0
    if sampled:  # the split sum joins: every set with it, then the reference sampled
        order = [name + SPLIT_SUM for name in order] + ["PRINCIPLED"]
    world = world_radiance(snapshot.world) if image is None else None
    world_id = np.asarray(world).tobytes() if image is None else (
        environment.field_key(snapshot.world.lighting, snapshot.world.threshold), *image[1:])
    exposure = float(snapshot.settings.exposure)
    occlusion = snapshot.settings.world_occlusion
    users = material_users(snapshot)
    found: dict[str, _Prediction] = {}
    closure_only: dict[str, Choice] = {}  # the closure nodes only the Principled set draws
    for key, material in snapshot.materials.items():
        drawn_alone = sorted(material.lobes & CLOSURE_LOBES) if key in users else ()
        if drawn_alone and material.model in ("", "PBR") and not any(
                (material.fresnel, material.ndf, material.visibility, material.diffuse)):
            # a Toon, velvet or rough Diffuse BSDF: every other set would draw another closure
            # (glsl/node_closure_bsdfs.glsl's fallbacks), which the twin does not predict
            closure_only[key] = Choice("PRINCIPLED", candidate_terms("PRINCIPLED"), 0.0,
                                       ", ".join(LOBE_LABELS[lobe] for lobe in drawn_alone),
                                       "closure nodes only the Principled set draws")
            continue
        if material.model not in ("", "PBR") or any(
                (material.fresnel, material.ndf, material.visibility, material.diffuse)) \
                or material.environment_samples >= 0:  # its own terms or World Specular: kept
            continue
        if key not in users:
            continue
        cache_key = _prediction_key(snapshot, key, users[key], camera or snapshot.camera, world_id, order,
                                    exposure, quantile, occlusion)
        entry = _PREDICTIONS.pop(cache_key, None)
        if entry is None:
            samples = material_samples(snapshot, key, camera=camera, users=users)
            entry = (_Prediction(0, material, 0.0, None) if samples is None else
                     _Prediction(len(samples), samples.material, samples.share, samples))
        _PREDICTIONS[cache_key] = entry  # most recently used last
        while len(_PREDICTIONS) > PREDICTIONS_KEPT:
            del _PREDICTIONS[next(iter(_PREDICTIONS))]
        found[key] = entry

    def predicted(entry: _Prediction) -> dict[str, float]:
        if entry.errors is None:
            entry.errors = predict(entry.samples, snapshot.lights, world, order, exposure, quantile,
                                   occlusion, image)
            entry.samples = None
        return entry.errors

    pixels = snapshot.width * snapshot.height * snapshot.settings.samples ** 2
    frame_ms = shading_ms(len(snapshot.lights), pixels)
    if sampled and frame_ms:  # every set sampled (as the scene is) or on the split sum
        costs = world_ms(image[1], pixels)
        frame_ms = {} if costs is None else {
            **{name + SPLIT_SUM: ms + costs[0] for name, ms in frame_ms.items()},
            **{name: ms + costs[1] for name, ms in frame_ms.items()}}
    first_use = float(cost_table().get("first_use_ms", 0.0))
    payback = PAYBACK_FRAMES if payback_frames is None else payback_frames
    programs_of = _program_keys(snapshot)
    fixed = {programs_of(key, None) for key in users if key not in found}  # drawn with their own terms
    # the programs the previous choice drew are compiled: their first use is paid, so none is
    # merged away and joining one costs nothing (a material near the payback threshold does not
    # flip between a program of its own and a shared one on small edits)
    fixed |= {programs_of(key, choice.name) for key, choice in (previous or {}).items()
              if key in snapshot.materials and choice.name in order}
    cheapest = min(order, key=lambda n: frame_ms.get(n, 0.0))
    reach = {key: e.share * (frame_ms["PRINCIPLED"] - frame_ms[cheapest]) if frame_ms else math.inf
             for key, e in found.items()}

    def choices(keys) -> tuple[dict, dict, dict]:
        """(alone, allowed, merged) for ``keys``, the rest on the Principled set."""
        alone, allowed = {}, {}
        for key in found:
            entry = found[key]
            if entry.count == 0:  # covers no pixel: every set is as good, the cheapest first
                alone[key], allowed[key] = order[0], list(order)
            elif key not in keys:
                alone[key], allowed[key] = "PRINCIPLED", ["PRINCIPLED"]
            else:
                errors = predicted(entry)
                before = None  # what it took on its own last time (a merge moves it, not its need)
                if previous and key in previous:
                    before = previous[key].alone or previous[key].name
                alone[key] = decide(errors, order, bound, before)
                allowed[key] = [n for n in order
                                if errors[n] * MARGIN <= bound or n in ("PRINCIPLED", alone[key])]
        return alone, allowed, merge_small_savings(alone, allowed, {k: e.share for k, e in found.items()},
                                                   programs_of, fixed, frame_ms, first_use, payback)

    unpredicted = {key for key in found if unpredicted_lobes(snapshot.materials[key])}  # Principled, said
    predicted_keys = {key for key, e in found.items() if e.count and reach[key] * payback >= first_use
                      and key not in unpredicted}
    small = {key for key, e in found.items() if e.count and key not in predicted_keys | unpredicted}
    if sum(reach[key] for key in small) * payback >= first_use:
        predicted_keys |= small  # together they might repay a program
    alone, _allowed, chosen = choices(predicted_keys)
    in_use = fixed | {programs_of(key, name) for key, name in chosen.items() if found[key].count}
    joinable = {key for key, e in found.items() if e.count and key not in predicted_keys | unpredicted
                and any(programs_of(key, n) in in_use for n in order if n != "PRINCIPLED")}
    if joinable:
        predicted_keys |= joinable
        alone, _allowed, chosen = choices(predicted_keys)
    out = {}
    for key, entry in found.items():
        name = chosen[key]
        if entry.count == 0:
            out[key] = Choice(name, candidate_terms(name), 0.0, samples=0)
        elif key in unpredicted:  # a lobe the Principled set alone draws, beyond the twin's prediction
            lobes = ", ".join(unpredicted_lobes(snapshot.materials[key]))
            out[key] = Choice(name, candidate_terms(name), 0.0, lobes, "drawn by the Principled set alone",
                              samples=entry.count, costs_ms=reach[key])
        elif key not in predicted_keys:  # too small to be worth a program, none cheaper to join
            # (a prediction kept from an earlier choice, with another payback, decided nothing here)
            out[key] = Choice(name, candidate_terms(name), 0.0, samples=entry.count, costs_ms=reach[key])
        else:
            errors = entry.errors
            limiting, reason = limiting_term(name, entry.seen, errors, bound)
            was_merged = name != alone[key]
            saving = entry.share * (frame_ms[name] - frame_ms[alone[key]]) if was_merged else 0.0
            out[key] = Choice(name, candidate_terms(name), errors[name], limiting, reason,
                              tuple(errors.items()), entry.count, alone[key] if was_merged else "", saving)
    return {**out, **closure_only}


def _program_keys(snapshot: Snapshot) -> Callable[[str, str | None], tuple]:
    """(material, candidate) -> what tells its shading program from the others in this scene (its
    model, terms, maps); candidate None: the terms it has."""
    keys: dict = {}

    def key_of(key: str, name: str | None) -> tuple:
        if (key, name) not in keys:
            material = snapshot.materials[key]
            if name is not None:
                material = replace(material, terms=candidate_terms(name))
                if name.endswith(SPLIT_SUM):
                    material = replace(material, environment_samples=0)
            f = programs.Features.from_snapshot(snapshot, material=material, shadow_layers=0)
            keys[key, name] = (f.model, f.terms, f.graph, f.env_samples)
        return keys[key, name]

    return key_of


def apply(snapshot: Snapshot, choices: dict[str, Choice]) -> None:
    """Fix each chosen material's terms into ``snapshot.materials`` (its program follows) and
    keep the choices in ``snapshot.term_choices``."""
    for key, choice in choices.items():
        material = replace(snapshot.materials[key], terms=choice.terms)
        if choice.environment_samples is not None:
            material = replace(material, environment_samples=choice.environment_samples)
        snapshot.materials[key] = material
    snapshot.term_choices = choices


def summary(choices: dict[str, Choice]) -> str:
    """One line for the stats line: how many materials each set took, and the largest predicted
    error."""
    if not choices:
        return ""
    counts: dict[str, int] = {}
    for choice in choices.values():
        counts[choice.name] = counts.get(choice.name, 0) + 1
    worst = max(choice.predicted for choice in choices.values())
    names = sorted(counts, key=lambda n: (n.endswith(SPLIT_SUM), list(CANDIDATE_TERMS).index(base_name(n))))
    parts = ", ".join(f"{counts[n]} {label(n)}" for n in names)
    return f"Auto: {parts} (predicted dE_ITP <= {worst:.2f})"


# --- verification against renders --------------------------------------------------------------

@dataclass(frozen=True)
class Verification:
    """One material's measured error: Delta E_ITP of the Auto render against the Principled
    render at the quantile of the material's pixels, and how many pixels it covers."""

    measured: float
    pixels: int
    bound: float

    @property
    def over(self) -> bool:
        return self.measured > self.bound


def material_id_snapshot(snapshot: Snapshot) -> tuple[Snapshot, list[str]]:
    """``snapshot`` drawn as material ids: every material emits (its index + 1, 0, 0) and reflects
    nothing, no lights, a black world, no shadows or occlusion; with the keys in index order."""
    keys = list(snapshot.materials)
    black = (0.0, 0.0, 0.0)
    materials = {key: MaterialParams(name=key, base_color=black, diffuse_color=black, specular_color=black,
                                     ambient_color=black, emission=(float(i + 1), 0.0, 0.0), model="PBR")
                 for i, key in enumerate(keys)}
    settings = replace(snapshot.settings, shadows=False, world_occlusion=False, auto_error_bound=None,
                       ambient=0.0)
    ids = replace(snapshot, materials=materials, lights=[], world=World(), world_color=black,
                  settings=settings, term_choices={})
    return ids, keys


def principled_snapshot(snapshot: Snapshot) -> Snapshot:
    """``snapshot`` with every material Auto chose for on the Principled set, with the scene's
    World Specular (Auto chooses only for materials that follow it)."""
    materials = dict(snapshot.materials)
    for key in snapshot.term_choices:
        materials[key] = replace(materials[key], terms=REFERENCE, environment_samples=-1)
    return replace(snapshot, materials=materials)


def measure(auto: np.ndarray, reference: np.ndarray, ids: np.ndarray, keys: list[str], bound: float,
            exposure: float = 0.0, quantile: float = DEFAULT_QUANTILE) -> dict[str, Verification]:
    """Per material of ``keys`` covering pixels: the Auto image's error against the reference's
    on the pixels ``ids`` (the id image's red channel, index + 1) gives it."""
    index = np.rint(ids[..., 0]).astype(int) - 1
    error = display_error(auto, reference, exposure)
    out = {}
    for i, key in enumerate(keys):
        mask = index == i
        if mask.any():
            out[key] = Verification(float(np.quantile(error[mask], quantile)), int(mask.sum()), bound)
    return out
