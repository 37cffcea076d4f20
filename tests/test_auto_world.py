"""The Auto term set under image worlds. Where a scene samples the world's specular (World
Specular: Sampled) the world joins the candidates: each term set also with the split sum, the
Principled set sampled the reference. On the split sum (the default) every candidate is predicted
lit by the image world itself. Checked against renders: random scenes (tests/auto_scenes.py)
under Blender's bundled worlds, Auto against the Principled set, per material."""

from __future__ import annotations

import auto_scenes
import bpy
import numpy as np
import pytest

from addon.blender import extract
from addon.plan import auto_terms

#: Seeds apart from test_auto_terms.py's (0-49) and from the margin's calibration (1000-1029).
SEEDS = range(2000, 2012)
SAMPLES = 16
#: The default bound, and a loose one under which more materials take the split sum.
BOUNDS = (auto_terms.DEFAULT_BOUND, 4.0)


def _results(tmp_path_factory, specular: str) -> dict[float, list]:
    """{bound: [(seed, material, Choice, measured error)]} over the random scenes under World
    Specular ``specular``: each rendered with the Principled set once and with Auto at each of
    BOUNDS."""
    tmp = tmp_path_factory.mktemp(f"auto_world_{specular.lower()}")
    rows = {bound: [] for bound in BOUNDS}
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(auto_terms, "PAYBACK_FRAMES", 1e12)  # every saving counts (96 px views)
        for seed in SEEDS:
            scene, camera, names = auto_scenes.world_scene(seed, specular, SAMPLES)
            for bound, found in auto_scenes.render_pairs(scene, camera, names, seed, BOUNDS, tmp).items():
                rows[bound] += found
    return rows


@pytest.fixture(scope="module")
def world_results(tmp_path_factory):
    return _results(tmp_path_factory, "SAMPLED")


@pytest.fixture(scope="module")
def split_sum_results(tmp_path_factory):
    return _results(tmp_path_factory, "SPLIT_SUM")


def _ratios(rows, floor: float) -> tuple[np.ndarray, float, np.ndarray]:
    """(measured / predicted, the share within a factor 2, its percentiles 5/25/50/75/95/100) where
    Auto chose a set other than the Principled one and either error is at least ``floor``."""
    pairs = [(c.predicted, m) for *_, c, m in rows if c.name != "PRINCIPLED" and max(c.predicted, m) >= floor]
    ratios = np.array([m / max(p, 1e-6) for p, m in pairs])
    if not len(ratios):
        return ratios, 0.0, np.array([])
    inside = float(np.mean((ratios >= 0.5) & (ratios <= 2.0)))
    return ratios, inside, np.round(np.percentile(ratios, [5, 25, 50, 75, 95, 100]), 3)


#: Of the materials, at least this share takes the split sum (measured 2026-12-03: 8 of 60 at
#: 0.5, 18 of 60 at 4).
SPLIT_SHARE = {auto_terms.DEFAULT_BOUND: 0.08, 4.0: 0.2}


@pytest.mark.parametrize("bound", BOUNDS)
def test_auto_takes_the_split_sum_where_it_is_within_the_bound(world_results, bound):
    """Under sampled image worlds (16 samples a pixel), Auto's materials stay within the bound
    measured against the Principled set sampled (all but one at most), and some take the split sum. Few do at
    the default bound: the split sum's error against the sampled lobe is large on metals (Delta
    E_ITP 5-30 at the 99th percentile, measured and predicted alike); rough dielectrics and dark
    materials take it."""
    rows = world_results[bound]
    within, chosen, over = auto_scenes.tally(rows, bound)
    split = sum(n for name, n in chosen.items() if name.endswith(auto_terms.SPLIT_SUM))
    print(f"bound {bound}: within {within:.1%} of {len(rows)}; chosen {chosen}; over: {over}")
    assert len(rows) >= 50, len(rows)
    assert len(over) <= 1, f"{len(over)} of {len(rows)} over {bound} (at most 1; measured none): {over}"
    assert split >= SPLIT_SHARE[bound] * len(rows), f"the split sum by {split} of {len(rows)}: {chosen}"


def test_the_split_sums_predicted_error_against_the_measured(world_results):
    """Where a material took the split sum and either error is noticeable (>= 0.1): measured /
    predicted within a factor 2 for most (measured 2026-12-03: 72 % of 18, the largest ratio 3.4;
    11.6 before the levels' borders led to the poles' values: a rough metal floor). The rest are
    over-predicted: the world's occlusion, which the prediction does not see but in its creases,
    hides much of the reflected world where the spheres stand in a row (calibration scene 1011, a
    near-mirror sphere reflecting a low sun past its neighbour: 2.24 predicted, 0.33 measured;
    with World Occlusion off 2.29 and 1.52)."""
    rows = [(seed, name, c, m) for bound in BOUNDS for seed, name, c, m in world_results[bound]
            if c.name.endswith(auto_terms.SPLIT_SUM)]
    ratios, inside, percentiles = _ratios(rows, 0.1)
    print(f"measured/predicted: {inside:.0%} of {len(ratios)} within a factor 2; percentiles "
          f"5/25/50/75/95/100 {percentiles}")
    assert len(ratios) >= 10, f"only {len(ratios)} materials to compare"
    assert inside >= 0.6, f"within a factor 2 for {inside:.0%}: {percentiles}"


@pytest.mark.parametrize("bound", BOUNDS)
def test_auto_on_the_split_sum_keeps_materials_within_the_bound(split_sum_results, bound):
    """Under image worlds on the split sum (the default World Specular), Auto's materials, predicted
    lit by the image itself, stay within the bound (all but one at most; measured 2026-12-03: all 60 at
    either bound) and do not all take the Principled set (measured: 10 of 60 at 0.5, 30 at 4)."""
    rows = split_sum_results[bound]
    within, chosen, over = auto_scenes.tally(rows, bound)
    print(f"bound {bound}: within {within:.1%} of {len(rows)}; chosen {chosen}; over: {over}")
    assert len(rows) >= 50, len(rows)
    assert len(over) <= 1, f"{len(over)} of {len(rows)} over {bound} (at most 1; measured none): {over}"
    assert chosen.get("PRINCIPLED", 0) <= CHEAPER_SHARE[bound] * len(rows), f"chosen {chosen}"


#: Of the materials at most this share stays on the Principled set (measured: 50 of 60 at 0.5,
#: 30 of 60 at 4).
CHEAPER_SHARE = {auto_terms.DEFAULT_BOUND: 0.9, 4.0: 0.6}


def test_split_sum_predictions_lit_by_the_image_follow_the_renders(split_sum_results):
    """Measured / predicted where Auto took a cheaper set and either error is at least half a
    just-noticeable difference: within a factor 2 for most and never far above the prediction
    (measured 2026-12-03: 83 % of 18, percentiles 5/25/50/75/95/100 0.31/0.73/0.81/0.97/1.16/1.59;
    with the world's mean radiance as a uniform world instead of the image: 76 % of 21, at most
    1.45)."""
    rows = [row for bound in BOUNDS for row in split_sum_results[bound]]
    ratios, inside, percentiles = _ratios(rows, 0.5)
    print(f"measured/predicted: {inside:.0%} of {len(ratios)} within a factor 2; percentiles "
          f"5/25/50/75/95/100 {percentiles}")
    assert len(ratios) >= 12, f"only {len(ratios)} materials to compare"
    assert inside >= 0.7, f"within a factor 2 for {inside:.0%}: {percentiles}"
    assert float(np.max(ratios)) <= 2.0, f"measured up to {np.max(ratios):.2f}x the prediction: {percentiles}"


def test_a_material_with_its_own_world_specular_keeps_it(tmp_path):
    scene, _camera, names = auto_scenes.world_scene(SEEDS[0])
    scene.shading_lab.term_set = "AUTO"
    bpy.data.materials[names[0]].shading_lab.world_specular = "SAMPLED"
    snap = extract.snapshot(bpy.context.evaluated_depsgraph_get(), auto_choice=True)
    assert names[0] not in snap.term_choices
    own = bpy.data.materials[names[0]].shading_lab.world_samples
    assert snap.materials[names[0]].environment_samples == own
    assert snap.term_choices and all(c.name.endswith(auto_terms.SPLIT_SUM) or c.name == "PRINCIPLED"
                                     for c in snap.term_choices.values()), snap.term_choices
