"""The Auto term set: the error metric against an independent implementation, the cost table
against the script that writes it, the choice on materials whose answer is known, and the choice
checked against renders on random scenes (Auto against the Principled set, per material)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import auto_scenes
import numpy as np
import pytest
import scenes

from addon.blender import engine, extract
from addon.plan import auto_terms
from addon.reference import shading
from addon.scene import snapshot as S

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))

#: Seeds of the test scenes; scripts/bench/auto_calibration.py calibrates the margin on others (1000+).
SEEDS = range(50)


# --- the error metric --------------------------------------------------------------------------

def test_delta_e_itp_matches_colour_science():
    """BT.2124's Delta E_ITP of linear BT.709 colours against colour-science's ICtCp (BT.2100 PQ)
    and delta_E_ITP, from black to 100x display white."""
    import colour

    rng = np.random.default_rng(7)
    a = rng.uniform(0.0, 1.0, (200, 3)) * np.exp(rng.uniform(-6, 4.6, (200, 1)))
    b = a * rng.uniform(0.9, 1.1, (200, 3))
    nits = 100.0

    def theirs(rgb):
        rgb2020 = colour.RGB_to_RGB(rgb, "ITU-R BT.709", "ITU-R BT.2020")
        return colour.RGB_to_ICtCp(rgb2020 * nits, method="ITU-R BT.2100-2 PQ")

    expected = colour.difference.delta_E_ITP(theirs(a), theirs(b))
    ours = auto_terms.delta_e_itp(a, b, nits, black_nits=0.0)
    worst = float(np.max(np.abs(ours - expected) / np.maximum(expected, 1e-3)))
    assert worst < 2e-3, f"Delta E_ITP differs from colour-science's by up to {worst:.2e} (relative)"
    ictcp = auto_terms.ictcp(np.array([1.0, 1.0, 1.0]), nits, black_nits=0.0)
    assert abs(ictcp[0] - theirs(np.array([1.0, 1.0, 1.0]))[0]) < 1e-4, f"I of white {ictcp[0]:.5f}"
    assert abs(ictcp[1]) < 1e-3 and abs(ictcp[2]) < 1e-3, f"white's chroma {ictcp[1:]}"


# --- the cost table ----------------------------------------------------------------------------

def test_shipped_cost_table_is_what_the_script_derives():
    """``addon/plan/term_costs.json`` holds the script's measured draw times and exactly the ratios its
    ``derive`` computes from them; the order puts the Principled set last and drops candidates
    that cost more than it."""
    from bench import term_costs

    data = json.loads(auto_terms.COSTS_FILE.read_text())
    assert data["generated_by"] == "scripts/bench/term_costs.py"
    assert set(data["draw_ms"]) == set(auto_terms.CANDIDATE_TERMS)
    assert data["relative"] == term_costs.derive(data["draw_ms"])
    for lights in (1, 2, 8, 32, 64):
        order = auto_terms.candidate_order(lights, data)
        costs = auto_terms.relative_costs(lights, data)
        assert order[-1] == "PRINCIPLED"
        assert all(costs[n] < costs["PRINCIPLED"] for n in order[:-1]), (lights, costs)
        assert [costs[n] for n in order[:-1]] == sorted(costs[n] for n in order[:-1]), (lights, costs)


# --- the choice on materials whose answer is known ---------------------------------------------

def _sphere_snapshot(material: S.MaterialParams, elevation_deg: float, light_kind: str = "SUN"):
    """A unit sphere (a 32 x 64 UV mesh) seen by an orthographic camera from ``elevation_deg``
    above the horizon, lit by one light from behind and above the camera."""
    n = 32
    theta, phi = np.meshgrid(np.linspace(0, np.pi, n + 1), np.linspace(0, 2 * np.pi, 2 * n + 1),
                             indexing="ij")
    points = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)],
                      -1).reshape(-1, 3)
    w = 2 * n + 1
    quads = [(i * w + j, (i + 1) * w + j, i * w + j + 1, (i + 1) * w + j + 1)
             for i in range(n) for j in range(2 * n)]
    rows = np.array([c for a, b, c2, d in quads for c in (a, b, c2, c2, b, d)], np.int32)
    positions = points[rows].astype(np.float32)
    geometry = S.MeshGeometry("sphere", positions, positions.copy(), [(0, 0, len(rows))])
    e = math.radians(elevation_deg)
    forward = np.array([0.0, math.cos(e), -math.sin(e)])
    right = np.array([1.0, 0.0, 0.0])
    up = np.cross(right, forward)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = right, up, -forward
    eye = -5.0 * forward
    view[:3, 3] = -view[:3, :3] @ eye
    projection = np.diag([1 / 1.2, 1 / 1.2, -2 / 20.0, 1.0])
    projection[2, 3] = -1.0
    camera = S.Camera.from_matrices(view, projection, False)
    snap = S.Snapshot(camera=camera, width=64, height=64)
    snap.geometries["sphere"] = geometry
    snap.materials["m"] = material
    snap.items.append(S.DrawItem("sphere", np.eye(4, dtype=np.float32), ["m"]))
    to_light = -forward + np.array([0.3, 0.0, 0.8])
    to_light /= np.linalg.norm(to_light)
    if light_kind == "SUN":
        snap.lights.append(S.Light("SUN", (0.0, 0.0, 0.0), tuple(-to_light), (3.0, 3.0, 3.0)))
    else:
        snap.lights.append(S.Light("POINT", tuple(4.0 * to_light), tuple(-to_light), (40.0, 40.0, 40.0)))
    return snap


def test_rough_metal_at_grazing_needs_every_term():
    """A rough metal (roughness 0.9) seen at a grazing angle: multiple scattering alone leaves it
    far outside the bound, so Auto takes the Principled set."""
    metal = S.MaterialParams(base_color=(0.95, 0.64, 0.54), metalness=1.0, roughness=0.9)
    choice = auto_terms.choose(_sphere_snapshot(metal, 8.0), bound=1.0, payback_frames=NEVER_MERGE)["m"]
    errors = dict(choice.errors)
    assert choice.name == "PRINCIPLED", f"chose {choice.name}: predicted {errors}"
    assert errors["MULTISCATTER"] > 3.0 and errors["DEFAULT"] > 20.0, errors


def test_smooth_metal_needs_only_multiple_scattering():
    """A smooth metal (roughness 0.2): Schlick from the base colour is the Principled set's metal
    Fresnel, and its diffuse is zero; what remains is the lobe's multiple scattering (~1 % at this
    roughness: Delta E_ITP ~0.8 at the 99th percentile without it, ~0.02 with it), so under a
    bound of 0.5 Auto takes the multiscatter candidate, not the Principled set."""
    metal = S.MaterialParams(base_color=(0.95, 0.64, 0.54), metalness=1.0, roughness=0.2)
    choice = auto_terms.choose(_sphere_snapshot(metal, 45.0, "POINT"), bound=0.5,
                               payback_frames=NEVER_MERGE)["m"]
    errors = dict(choice.errors)
    assert choice.name in ("MULTISCATTER", "EXACT_MULTISCATTER"), f"chose {choice.name}: {errors}"
    assert errors[choice.name] < 0.05 and 0.5 < errors["DEFAULT"] < 1.6, errors
    assert choice.limiting == "multiple scattering", choice


def test_materials_with_their_own_terms_or_unseen_keep_theirs():
    material = S.MaterialParams(roughness=0.5, ndf="BECKMANN")
    snap = _sphere_snapshot(material, 45.0)
    assert auto_terms.choose(snap) == {}
    snap.materials["hidden"] = S.MaterialParams(roughness=0.9, metalness=1.0)
    far = np.eye(4, dtype=np.float32)
    far[:3, 3] = (0.0, 0.0, 100.0)  # out of the view
    snap.items[0] = S.DrawItem("sphere", far, ["hidden"])
    choice = auto_terms.choose(snap)["hidden"]
    assert choice.samples == 0 and choice.name == auto_terms.candidate_order(1)[0], choice


def test_a_materials_share_of_the_view_is_its_projected_area():
    """The unit sphere (a 32 x 64 UV mesh) in an orthographic view 2.4 m square covers its
    projected outline's area over the view's 5.76 m^2 (the back half hidden behind the front,
    not counted twice); the estimate is a sum over 8,192 random points (measured: 1.1 % over)."""
    metal = S.MaterialParams(base_color=(0.9, 0.9, 0.9), metalness=1.0, roughness=0.5)
    snap = _sphere_snapshot(metal, 45.0)
    samples = auto_terms.material_samples(snap, "m")
    # the mesh's outline seen along the view: the convex hull of its vertices projected
    from scipy.spatial import ConvexHull

    view = np.asarray(snap.camera.view, np.float64)
    xy = (snap.geometries["sphere"].positions.astype(np.float64) @ view[:3, :3].T)[:, :2]
    expected = ConvexHull(xy).volume / 5.76
    assert abs(samples.share / expected - 1.0) < 0.03, f"share {samples.share:.4f}, outline {expected:.4f}"


def test_candidates_sharing_the_lights_geometry_shade_as_alone():
    """predict shades one material's points with every candidate, sharing the lights' irradiance
    and the area and sphere lights' lobe geometry between them (``shading.shade``'s
    ``irradiance`` and ``memo``): each candidate's radiance must equal what it gives alone."""
    rng = np.random.default_rng(7)
    n = rng.normal(size=(400, 3))
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    v = n + rng.normal(scale=0.5, size=(400, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    p = rng.uniform(-1.0, 1.0, size=(400, 3))
    lights = [S.Light("AREA", (0.0, 0.0, 3.0), (0.0, 0.0, -1.0), (50.0, 50.0, 50.0), half_size=(0.8, 0.5)),
              S.Light("POINT", (2.0, 1.0, 2.0), (0.0, 0.0, -1.0), (80.0, 60.0, 40.0), radius=0.3)]
    material = S.MaterialParams(base_color=(0.8, 0.5, 0.3), metalness=0.3, roughness=0.25)
    irradiance = [shading.light_irradiance(light, p) for light in lights]
    memo: dict = {}
    for terms in (auto_terms.REFERENCE, *auto_terms.CANDIDATE_TERMS.values()):
        s = shading.Surface(p, n, v, material)
        shared = shading.shade("PBR", s, lights, terms=terms, irradiance=irradiance, memo=memo)
        alone = shading.shade("PBR", shading.Surface(p, n, v, material), lights, terms=terms)
        assert np.array_equal(shared, alone), terms
    assert memo  # the geometry was shared


def test_programs_that_save_too_little_are_merged():
    """A program of its own must repay its first use within PAYBACK_FRAMES frames: a material
    covering 1 % of the view saves 0.01 x (140 - 110) = 0.3 ms a frame on multiple scattering
    against the Principled set (30 ms over 100 frames, less than a 70 ms first use: merged into
    the Principled program another material uses); covering 5 % it saves 1.5 ms (150 ms: kept).
    A material moves only to a set within its bound whose program is drawn anyway."""
    frame_ms = {"DEFAULT": 100.0, "MULTISCATTER": 110.0, "PRINCIPLED": 140.0}

    def merged(chosen, allowed, shares, fixed=()):
        return auto_terms.merge_small_savings(chosen, allowed, shares, lambda key, name: name, set(fixed),
                                              frame_ms, 70.0, 100)

    allowed = {"a": ["MULTISCATTER", "PRINCIPLED"], "b": ["PRINCIPLED"]}
    on_ms = {"a": "MULTISCATTER", "b": "PRINCIPLED"}
    assert merged(on_ms, allowed, {"a": 0.01, "b": 0.9}) == {"a": "PRINCIPLED", "b": "PRINCIPLED"}
    assert merged(on_ms, allowed, {"a": 0.05, "b": 0.9}) == on_ms
    # no program within a's bound is drawn but its own (multiple scattering is not): kept
    on_default = {"a": "DEFAULT", "b": "PRINCIPLED"}
    assert merged(on_default, {"a": ["DEFAULT", "MULTISCATTER"], "b": ["PRINCIPLED"]},
                  {"a": 0.001, "b": 0.9}) == on_default
    # a cheap program merges into a dearer one in use (0.01 x 10 ms x 100 < 70 ms) ...
    assert merged({"a": "DEFAULT", "b": "MULTISCATTER"},
                  {"a": ["DEFAULT", "MULTISCATTER", "PRINCIPLED"], "b": ["MULTISCATTER", "PRINCIPLED"]},
                  {"a": 0.01, "b": 0.9}) == {"a": "MULTISCATTER", "b": "MULTISCATTER"}
    # ... or into one that a material with its own terms draws with (``fixed``), which is never
    # merged away itself
    assert merged({"a": "MULTISCATTER"}, {"a": ["MULTISCATTER", "PRINCIPLED"]}, {"a": 0.01},
                  fixed={"PRINCIPLED"}) == {"a": "PRINCIPLED"}
    assert merged({"a": "DEFAULT"}, {"a": ["DEFAULT", "PRINCIPLED"]}, {"a": 0.001}, fixed={"DEFAULT"}) \
        == {"a": "DEFAULT"}


def test_the_hdr_presets_small_metal_stays_on_the_principled_program(tmp_path):
    """The hdr preset at 1280 x 720: its silver sphere covers about 2.5 % of the view, so no
    cheaper set could save it more than share x (Principled - cheapest) of the measured full-view
    shading time a frame -- over PAYBACK_FRAMES frames less than a program's first use -- and no
    cheaper program is drawn for the big floor: it takes the Principled set without a
    prediction. Auto then draws exactly what the Principled set draws (the same image), with no
    program more to compile. Where a program need repay its first use only over many more
    frames, the silver is predicted and takes a cheaper set of its own, which it keeps in the
    next choice under the usual payback: its program is compiled by then."""
    import bpy

    from addon.blender import extract, scene_builder
    from addon.scene import presets

    scene = scenes.reset()
    scene_builder.build_scene(presets.load_scene_preset("hdr"), scene)
    scene.render.resolution_x, scene.render.resolution_y = 1280, 720
    scene.shading_lab.term_set = "AUTO"
    bpy.context.view_layer.update()
    snap = extract.snapshot(bpy.context.evaluated_depsgraph_get(), auto_choice=False)
    choices = auto_terms.choose(snap, auto_terms.DEFAULT_BOUND)
    key = next(k for k in choices if "ilver" in k)
    silver = choices[key]
    frame_ms = auto_terms.shading_ms(len(snap.lights), snap.width * snap.height * snap.settings.samples ** 2)
    first_use = auto_terms.cost_table()["first_use_ms"]
    assert {c.name for c in choices.values()} == {"PRINCIPLED"}, {k: (c.name, c.alone)
                                                                  for k, c in choices.items()}
    share = auto_terms.material_samples(snap, key).share
    reach = share * (frame_ms["PRINCIPLED"] - min(frame_ms.values()))
    assert not silver.errors and silver.samples > 0, silver  # not predicted
    assert silver.costs_ms == pytest.approx(reach, rel=1e-6), (silver.costs_ms, reach)
    assert 0.0 < reach * auto_terms.PAYBACK_FRAMES < first_use, (reach, first_use)
    alone = auto_terms.choose(snap, auto_terms.DEFAULT_BOUND, payback_frames=4.0 * first_use / reach)
    kept = alone[key]
    assert kept.errors and kept.name not in ("PRINCIPLED", "") and not kept.alone, kept
    # once drawn, that program is compiled: the next choice keeps it (nothing left to repay)
    again = auto_terms.choose(snap, auto_terms.DEFAULT_BOUND, previous=alone)[key]
    assert again.name == kept.name and again.errors, (again, kept)
    print(f"hdr silver: share {share:.4f}, at most {reach:.3f} ms a frame against a {first_use:.1f} ms "
          f"first use; predicted alone: {kept.name}")
    # the same programs draw the same image
    scene.render.resolution_x, scene.render.resolution_y = 96, 54
    scene.shading_lab.term_set = "PRINCIPLED"
    principled = scenes.render(scene, tmp_path / "principled.exr")
    scene.shading_lab.term_set = "AUTO"
    auto = scenes.render(scene, tmp_path / "auto.exr")
    assert {c.name for c in engine.last_term_choices.values()} == {"PRINCIPLED"}, engine.last_term_choices
    worst = float(np.max(np.abs(auto - principled)))
    assert worst <= 1e-5 * float(np.max(principled)), f"Auto differs from the Principled set by {worst:.3g}"


def test_hysteresis_keeps_a_set_through_small_changes():
    order = ["DEFAULT", "MULTISCATTER", "PRINCIPLED"]
    errors = {"DEFAULT": 0.79, "MULTISCATTER": 0.5, "PRINCIPLED": 0.0}
    bound, margin = 1.0, 1.25
    assert auto_terms.decide(errors, order, bound, None, margin) == "DEFAULT"  # 0.99 <= 1
    # having been on MULTISCATTER, DEFAULT only just fits (0.99 > 1 / 1.25): stay
    assert auto_terms.decide(errors, order, bound, "MULTISCATTER", margin) == "MULTISCATTER"
    # clearly within: move
    assert auto_terms.decide({**errors, "DEFAULT": 0.5}, order, bound, "MULTISCATTER", margin) == "DEFAULT"
    # on DEFAULT, a small rise past the bound (1.1 <= 1.25) keeps it; a large one does not
    assert auto_terms.decide({**errors, "DEFAULT": 0.88}, order, bound, "DEFAULT", margin) == "DEFAULT"
    assert auto_terms.decide({**errors, "DEFAULT": 1.2}, order, bound, "DEFAULT", margin) == "MULTISCATTER"


# --- the choice against renders ----------------------------------------------------------------

#: Bounds the random scenes are rendered at: the default, and a loose one under which more
#: materials take cheaper sets (more pairs of predicted and measured error to compare).
BOUNDS = (auto_terms.DEFAULT_BOUND, 4.0)


#: Programs never merged (``auto_terms.PAYBACK_FRAMES``): at these 96 px no cheaper set saves a
#: program's first use, so every material would join the Principled set's program and the
#: prediction would go untested. The merge has tests of its own.
NEVER_MERGE = 1e12


@pytest.fixture(scope="module")
def random_results(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("auto")
    rows = {bound: [] for bound in BOUNDS}
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(auto_terms, "PAYBACK_FRAMES", NEVER_MERGE)
        for seed in SEEDS:
            scene, camera, names = auto_scenes.random_scene(seed)
            for bound, found in auto_scenes.render_pairs(scene, camera, names, seed, BOUNDS, tmp).items():
                rows[bound] += found
    return rows


#: Per bound: how many of the 250 materials may be measured over it (measured 2026-12-03: none at
#: 0.5, one at 4: a rough dielectric at 4.59), and the least share that takes a set cheaper than
#: the Principled one (measured: 59 of 250 at 0.5, 148 at 4): each within about 2-3x.
MAX_OVER = {auto_terms.DEFAULT_BOUND: 2, 4.0: 3}
MIN_CHEAPER = {auto_terms.DEFAULT_BOUND: 0.12, 4.0: 0.3}


@pytest.mark.parametrize("bound", BOUNDS)
def test_auto_keeps_random_materials_within_the_bound(random_results, bound):
    """On 50 random scenes (5 materials each, 1-8 lights of every kind, frontal and grazing views,
    shadows on, black or uniform worlds, 96 px): the measured error of Auto against the Principled
    set, per material on all its pixels, is within the bound for all but MAX_OVER materials, and
    Auto does not simply take the Principled set (at least MIN_CHEAPER take cheaper terms)."""
    rows = random_results[bound]
    within, chosen, over = auto_scenes.tally(rows, bound)
    cheaper = 1.0 - chosen.get("PRINCIPLED", 0) / len(rows)
    print(f"bound {bound}: within {within:.1%} of {len(rows)}; cheaper terms {cheaper:.1%}; chosen {chosen}; "
          f"over: {over}")
    assert len(rows) >= 200, len(rows)
    assert len(over) <= MAX_OVER[bound], (f"{len(over)} of {len(rows)} materials over {bound} (at most "
                                          f"{MAX_OVER[bound]}): {over}; chosen {chosen}")
    least = MIN_CHEAPER[bound]
    assert cheaper >= least, f"cheaper terms for {cheaper:.1%} (at least {least:.0%})"


def test_measured_error_is_within_a_factor_two_of_the_prediction(random_results):
    """Where Auto chose a set other than the Principled one (whose error is 0 by construction)
    and either error is noticeable: measured / predicted within [1/2, 2] for most (81 % of 150
    with either >= 0.1; the rest mostly over-predicted: smooth metals, whose 99th percentile lies
    at n.v < 0.1, a rim 0.04 px wide on these 8.5-px spheres that two or three pixel centres
    sample), and never above twice the prediction where either is at least half a just-noticeable
    difference (measured at most 1.72x of 100, 79 % within a factor 2; below that 2.3x: 0.19
    predicted, 0.44 measured)."""
    rows = [row for bound in BOUNDS for row in random_results[bound]]

    def compared(floor):
        pairs = [(c.predicted, m) for *_, c, m in rows
                 if c.name != "PRINCIPLED" and max(c.predicted, m) >= floor]
        ratios = np.array([m / max(p, 1e-6) for p, m in pairs])
        inside = float(np.mean((ratios >= 0.5) & (ratios <= 2.0))) if len(ratios) else 0.0
        percentiles = np.round(np.percentile(ratios, [5, 25, 50, 75, 95, 100]), 3) if len(ratios) else []
        return ratios, inside, percentiles

    ratios, inside, percentiles = compared(0.1)
    assert len(ratios) >= 40, f"only {len(ratios)} materials to compare"
    assert inside >= 0.75, (f"measured/predicted within a factor 2 for {inside:.0%} of {len(ratios)}; "
                            f"percentiles 5/25/50/75/95/100: {percentiles}")
    noticeable, inside_noticeable, noticeable_percentiles = compared(0.5)
    assert len(noticeable) >= 30, f"only {len(noticeable)} materials with errors >= 0.5"
    assert float(np.max(noticeable)) <= 2.0, (f"measured up to {np.max(noticeable):.2f}x the prediction "
                                              f"where either is >= 0.5: {noticeable_percentiles}")
    assert inside_noticeable >= 0.75, (f"within a factor 2 for {inside_noticeable:.0%} of {len(noticeable)} "
                                       f"(>= 0.5): {noticeable_percentiles}")
    print(f"measured/predicted: {inside:.0%} of {len(ratios)} within a factor 2 (either >= 0.1), "
          f"percentiles 5/25/50/75/95/100 {percentiles}; either >= 0.5: {inside_noticeable:.0%} of "
          f"{len(noticeable)}, {noticeable_percentiles}")


def test_verify_measures_what_the_analytic_masks_measure(tmp_path, monkeypatch):
    """The Verify operator's per-material errors (its own material-id render) agree with the same
    error measured on the pixels found by intersecting rays with the analytic spheres and plane
    (less those whose centres lie within a twentieth of a pixel of a sphere's outline)."""
    import bpy

    monkeypatch.setattr(auto_terms, "PAYBACK_FRAMES", NEVER_MERGE)
    scene, camera, names = auto_scenes.random_scene(7)
    props = scene.shading_lab
    props.term_set = "PRINCIPLED"
    reference = scenes.render(scene, tmp_path / "principled.exr")
    props.term_set, props.auto_error_bound = "AUTO", 4.0
    auto = scenes.render(scene, tmp_path / "auto.exr")
    assert bpy.ops.shading_lab.verify_auto_terms() == {"FINISHED"}
    verified = dict(engine.last_verification)
    masks = auto_scenes.material_masks(camera, names)
    analytic = auto_scenes.measured_errors(auto, reference, masks, props.auto_quantile / 100.0)
    cheaper = [n for n in names if engine.last_term_choices[n].name != "PRINCIPLED"]
    assert cheaper, f"seed 7 chose the Principled set everywhere: {engine.last_term_choices}"
    report = {n: (round(verified[n].measured, 3), round(analytic[n], 3), verified[n].pixels,
                  int(masks[n].sum())) for n in cheaper}
    for name in cheaper:  # measured: the same errors to 3 decimals, 0-20 more pixels (the outlines)
        v = verified[name]
        assert masks[name].sum() <= v.pixels <= 1.005 * masks[name].sum() + 4, report
        assert abs(v.measured - analytic[name]) <= 0.03 * max(analytic[name], 0.2), report
    assert set(verified) == {n for n in names if n in engine.last_term_choices}, (verified, report)
    print(f"verify vs analytic (measured, analytic, pixels, analytic pixels): {report}")


@pytest.mark.parametrize("name", ["DEFAULT", "MULTISCATTER", "LAYERED_MULTISCATTER", "PRINCIPLED"])
def test_the_uniform_world_twin_is_the_programs_world_term(name, tmp_path):
    """shading.shade_uniform_environment (the prediction's world term) against the GPU: a sphere
    under a uniform world, nothing occluding it, no lights, for a rough metal and a dielectric, on
    the pixels whose 3x3 neighbourhood is on the sphere (normals from the analytic sphere)."""
    import bpy

    from addon.reference import shading

    worst = {}
    for metal, roughness in ((1.0, 0.6), (0.0, 0.35)):
        scene = scenes.reset(size=48)
        scene.shading_lab.model = "PBR"
        scene.shading_lab.world_occlusion = False
        terms = auto_terms.CANDIDATE_TERMS[name]
        props = scene.shading_lab
        props.term_set = "PRINCIPLED" if terms.principled else "CUSTOM"
        props.diffuse, props.multiscatter = terms.diffuse, terms.multiscatter
        camera = scenes.ortho_camera(scene, location=(0.0, 0.0, 5.0), scale=2.4)
        base = (0.9, 0.55, 0.3)
        mat = scenes.material("M", base_color=base, roughness=roughness, metalness=metal, f0=0.05)
        bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=128, ring_count=64)
        sphere = bpy.context.object
        for poly in sphere.data.polygons:
            poly.use_smooth = True
        sphere.data.materials.append(mat)
        background = next(n for n in scenes.node_tree(scene.world).nodes
                          if n.bl_idname == "ShaderNodeBackground")
        background.inputs["Color"].default_value = (0.6, 0.8, 1.0, 1.0)
        background.inputs["Strength"].default_value = 0.5
        image = scenes.render(scene, tmp_path / f"{name}_{metal}.exr")[..., :3]
        origins, direction = scenes.ortho_pixel_rays(48, 2.4, np.array(camera.matrix_world))
        t = auto_scenes.sphere_hits(origins, direction, (0.0, 0.0, 0.0), 1.0)
        hit = np.isfinite(t)
        inner = hit & auto_scenes.interior(hit.astype(int))
        p = origins + np.where(hit, t, 0.0)[..., None] * direction
        s = shading.Surface(p[inner], p[inner], np.broadcast_to(-direction, p[inner].shape),
                            S.MaterialParams(base_color=base, roughness=roughness, metalness=metal, f0=0.05))
        expected = shading.shade_uniform_environment(s, np.array([0.3, 0.4, 0.5]), terms)
        worst[metal] = float(np.max(np.abs(image[inner] - expected) / np.maximum(expected, 1e-3)))
    # float32 and the mesh's interpolated normals: measured up to 1.1e-3
    assert max(worst.values()) < 3e-3, f"{name}: worst relative difference {worst}"
    print(f"{name}: worst relative difference GPU vs twin {worst}")


def test_predictions_are_kept_for_an_unchanged_scene_and_redone_on_a_change(monkeypatch):
    metal = S.MaterialParams(base_color=(0.95, 0.64, 0.54), metalness=1.0, roughness=0.45)
    snap = _sphere_snapshot(metal, 30.0, "POINT")
    calls = []
    original = auto_terms.predict
    monkeypatch.setattr(auto_terms, "predict", lambda *a, **k: calls.append(1) or original(*a, **k))
    monkeypatch.setattr(auto_terms, "PAYBACK_FRAMES", NEVER_MERGE)  # 64 px: else too small to predict
    first = auto_terms.choose(snap)["m"]
    again = auto_terms.choose(_sphere_snapshot(metal, 30.0, "POINT"))["m"]
    assert len(calls) == 1 and again == first, (len(calls), first, again)
    auto_terms.choose(_sphere_snapshot(metal, 31.0, "POINT"))  # the view moved
    auto_terms.choose(_sphere_snapshot(S.MaterialParams(metalness=1.0, roughness=0.5), 30.0, "POINT"))
    assert len(calls) == 3, len(calls)


def test_the_calibration_script_end_to_end(tmp_path):
    """The calibration (scripts/bench/auto_calibration.py) on one scene under its own world and one
    under an image world on the split sum: a row per world and bound, each material's row in the
    CSV with the set Auto chose and the measured error; a world it does not know and an unwritable
    page are one clear error each (exit 2), nothing written."""
    import csv
    import subprocess

    def run(*options):
        return subprocess.run([sys.executable, str(ROOT / "scripts" / "bench"), "run", "auto_calibration",
                               "--seeds", "1000", "--bounds", "4", *options],
                              capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)

    table, rows = tmp_path / "auto_calibration.md", tmp_path / "rows.csv"
    proc = run("--worlds", "uniform,split-sum", "--out", str(tmp_path), "--rows", str(rows))
    assert proc.returncode == 0, proc.stderr[-2000:]
    text = table.read_text()
    assert "| uniform | 4 | 5 |" in text and "| split-sum | 4 | 5 |" in text, text
    found = list(csv.DictReader(rows.open()))
    assert len(found) == 10 and {r["world"] for r in found} == {"uniform", "split-sum"}, found
    assert all(r["set"] in auto_terms.CANDIDATE_TERMS and float(r["measured"]) >= 0.0 for r in found), found
    bad = run("--worlds", "uniform,cloudy", "--out", str(tmp_path / "bad"))
    assert bad.returncode == 2 and "unknown cloudy" in bad.stderr, bad.stderr[-500:]
    assert not (tmp_path / "bad").exists()
    (tmp_path / "a file").write_text("")
    unwritable = run("--worlds", "uniform", "--out", str(tmp_path / "a file"))
    assert unwritable.returncode == 2 and "cannot write" in unwritable.stderr, unwritable.stderr[-500:]


def _on_a_random_sphere(seed: int, make_material, tmp_path):
    """The material ``make_material()`` makes on the first sphere of random scene ``seed``,
    rendered with the Principled set, the default terms (Custom) and Auto: (the snapshot, the
    material, Auto's choice for it, its measured errors {"CUSTOM", "AUTO"} against the Principled
    set's image, the scene's settings)."""
    import bpy

    scene, camera, names = auto_scenes.random_scene(seed)
    mat = make_material()
    sphere = next(o for o in scene.objects if o.type == "MESH" and o.data.materials[0].name == names[0])
    sphere.data.materials[0] = mat
    names[0] = mat.name
    bpy.context.view_layer.update()
    snap = extract.snapshot(bpy.context.evaluated_depsgraph_get())
    props = scene.shading_lab
    mask = {mat.name: auto_scenes.material_masks(camera, names)[mat.name]}
    images = {}
    for term_set in ("PRINCIPLED", "CUSTOM", "AUTO"):  # Custom: the default terms
        props.term_set = term_set
        images[term_set] = scenes.render(scene, tmp_path / f"{term_set}.exr")
    measured = {name: auto_scenes.measured_errors(images[name], images["PRINCIPLED"], mask,
                                                  props.auto_quantile / 100.0)[mat.name]
                for name in ("CUSTOM", "AUTO")}
    return snap, mat, engine.last_term_choices[mat.name], measured, props


def _assert_predicted(choice, measured, props) -> None:
    """The default terms' measured error within a factor 2 of their prediction, Auto's within the
    bound."""
    predicted = dict(choice.errors)
    assert choice.samples > 0 and predicted, choice  # predicted, not passed over
    ratio = measured["CUSTOM"] / predicted["DEFAULT"]
    assert 0.5 <= ratio <= 2.0, (f"default terms: measured {measured['CUSTOM']:.2f}, "
                                 f"predicted {predicted['DEFAULT']:.2f}")
    assert measured["AUTO"] <= props.auto_error_bound, f"Auto ({choice.name}) measured {measured['AUTO']:.3f}"


def test_textured_materials_are_predicted_from_their_texels(tmp_path, monkeypatch):
    """A material whose base colour and roughness come from images is predicted from random
    texels of them, one for every point (the highlight points once had none: the prediction failed
    on every textured material, and the render with it). Checked against renders: the default
    terms' measured error within a factor 2 of their predicted one (measured 2026-12-03: 34.8
    against 19.7 predicted: random texels at each point, not the texture's layout), and Auto's
    choice within the bound."""
    import bpy
    import scenes

    monkeypatch.setattr(auto_terms, "PAYBACK_FRAMES", NEVER_MERGE)
    seed = 11

    def textured():
        mat = bpy.data.materials.new("Textured")
        tree = scenes.node_tree(mat)
        bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        rng = np.random.default_rng(seed)
        for socket, non_color in (("Base Color", False), ("Roughness", True)):
            image = bpy.data.images.new(socket, 16, 16, alpha=False)
            image.pixels.foreach_set(np.c_[rng.random((256, 3)), np.ones(256)].astype(np.float32).ravel())
            if non_color:
                image.colorspace_settings.name = "Non-Color"
            node = tree.nodes.new("ShaderNodeTexImage")
            node.image = image
            tree.links.new(node.outputs["Color"], bsdf.inputs[socket])
        return mat

    snap, mat, choice, measured, props = _on_a_random_sphere(seed, textured, tmp_path)
    assert set(snap.materials[mat.name].graph.textured) == {"base_color", "roughness"}
    print(f"{choice.name}: predicted {dict(choice.errors)}; measured {measured}")
    _assert_predicted(choice, measured, props)


def _procedural_material(name: str):
    """Base Color from a Voronoi Texture's cell colours, Roughness from a Noise Texture mapped to
    [0.6, 1] (rough: where single scattering loses most), Metallic from a Checker Texture (half
    the surface a metal), at Generated; the sockets' own values (0.8 grey, 0.5, 0) say otherwise."""
    import bpy

    mat = bpy.data.materials.new(name)
    tree = scenes.node_tree(mat)
    bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    cells = tree.nodes.new("ShaderNodeTexVoronoi")
    cells.inputs["Scale"].default_value = 3.0
    tree.links.new(cells.outputs["Color"], bsdf.inputs["Base Color"])
    noise = tree.nodes.new("ShaderNodeTexNoise")
    ranged = tree.nodes.new("ShaderNodeMapRange")
    ranged.inputs["To Min"].default_value, ranged.inputs["To Max"].default_value = 0.6, 1.0
    tree.links.new(noise.outputs["Fac"], ranged.inputs["Value"])
    tree.links.new(ranged.outputs["Result"], bsdf.inputs["Roughness"])
    checker = tree.nodes.new("ShaderNodeTexChecker")
    checker.inputs["Scale"].default_value = 2.0
    tree.links.new(checker.outputs["Fac"], bsdf.inputs["Metallic"])
    return mat


#: Random scenes the procedural material is tried in. Its default terms' error (Delta E_ITP, 99th
#: percentile), measured 2026-12-07: seed 11 predicted 35.1, measured 33.3 (by socket values 7.3);
#: seed 23 predicted 32.4, measured 29.6 (by socket values 8.2).
PROCEDURAL_SEEDS = (11, 23)


@pytest.mark.parametrize("seed", PROCEDURAL_SEEDS)
def test_procedural_materials_are_predicted_from_their_values(tmp_path, monkeypatch, seed):
    """A material whose base colour, roughness and metalness come from procedural textures is
    predicted from the values its graph gives at each point (``materials.evaluate``), not from its
    inputs' socket values: the default terms' measured error within a factor 2 of the prediction
    (by socket values, as before, it is under-predicted 3.6-4.5x), and Auto's choice within the
    bound."""
    monkeypatch.setattr(auto_terms, "PAYBACK_FRAMES", NEVER_MERGE)
    snap, mat, choice, measured, props = _on_a_random_sphere(seed, lambda: _procedural_material("Procedural"),
                                                             tmp_path)
    assert {entry[0] for entry in snap.materials[mat.name].graph.procedural} == \
        {"base_color", "roughness", "metalness"}
    # the prediction by socket values (the graph not evaluated), for the record
    with monkeypatch.context() as patch:
        patch.setattr(auto_terms.evaluate, "evaluate", lambda *args: None)
        samples = auto_terms.material_samples(snap, mat.name)
    by_socket = auto_terms.predict(samples, snap.lights, auto_terms.world_radiance(snap.world), ["DEFAULT"],
                                   float(snap.settings.exposure), props.auto_quantile / 100.0,
                                   snap.settings.world_occlusion)
    print(f"seed {seed}: {choice.name}: predicted {dict(choice.errors)}; by socket values {by_socket}; "
          f"measured {measured}")
    _assert_predicted(choice, measured, props)
    assert measured["CUSTOM"] / by_socket["DEFAULT"] > 2.0, by_socket  # (the case tells the two apart)
