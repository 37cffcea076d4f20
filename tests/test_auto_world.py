"""The Auto term set where a scene samples an image world's specular (World Specular: Sampled):
the world joins the candidates, each term set also with the split sum, the Principled set
sampled the reference. Checked against renders: random scenes (tests/auto_scenes.py) under
Blender's bundled worlds, Auto against the Principled set, per material."""

from __future__ import annotations

import math

import auto_scenes
import bpy
import numpy as np
import pytest
import scenes
from test_world_light import _hdri, _world

from addon import auto_terms, engine, extract

#: Seeds apart from test_auto_terms.py's (0-49) and from the margin's calibration (1000-1029).
SEEDS = range(2000, 2012)
WORLDS = ("forest", "city", "studio", "sunset")
SAMPLES = 16
#: The default bound, and a loose one under which more materials take the split sum.
BOUNDS = (auto_terms.DEFAULT_BOUND, 4.0)


def _world_scene(seed: int):
    scene, camera, names = auto_scenes.random_scene(seed)
    rng = np.random.default_rng(seed + 7)
    _world(scene, image=_hdri(WORLDS[seed % len(WORLDS)]), strength=float(rng.uniform(0.3, 1.5)))
    mapping = scene.world.node_tree.nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value[2] = float(rng.uniform(0.0, 2.0 * math.pi))
    coords = scene.world.node_tree.nodes.new("ShaderNodeTexCoord")
    environment = scene.world.node_tree.nodes["Environment Texture"]
    scene.world.node_tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    scene.world.node_tree.links.new(mapping.outputs["Vector"], environment.inputs["Vector"])
    props = scene.shading_lab
    props.world_specular, props.world_samples = "SAMPLED", SAMPLES
    bpy.context.view_layer.update()
    return scene, camera, names


@pytest.fixture(scope="module")
def world_results(tmp_path_factory):
    """{bound: [(seed, material, Choice, measured error)]} over the random scenes: each rendered
    with the Principled set once and with Auto at each of BOUNDS."""
    tmp = tmp_path_factory.mktemp("auto_world")
    rows = {bound: [] for bound in BOUNDS}
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(auto_terms, "PAYBACK_FRAMES", 1e12)  # every saving counts (96 px views)
        for seed in SEEDS:
            scene, camera, names = _world_scene(seed)
            props = scene.shading_lab
            props.term_set = "PRINCIPLED"
            reference = scenes.render(scene, tmp / f"{seed}_principled.exr")
            masks = auto_scenes.material_masks(camera, names)
            for bound in BOUNDS:
                props.term_set, props.auto_error_bound = "AUTO", bound
                auto = scenes.render(scene, tmp / f"{seed}_auto_{bound}.exr")
                choices = dict(engine.last_term_choices)
                measured = auto_scenes.measured_errors(auto, reference, masks, props.auto_quantile / 100.0)
                rows[bound] += [(seed, name, choices[name], measured[name])
                                for name in names if name in measured]
    return rows


#: Of the materials, at least this share takes the split sum (measured 2026-12-03: 8 of 60 at
#: 0.5, 18 of 60 at 4).
SPLIT_SHARE = {auto_terms.DEFAULT_BOUND: 0.08, 4.0: 0.2}


@pytest.mark.parametrize("bound", BOUNDS)
def test_auto_takes_the_split_sum_where_it_is_within_the_bound(world_results, bound):
    """Under sampled image worlds (16 samples a pixel), Auto's materials stay within the bound
    measured against the Principled set sampled (>= 95 %), and some take the split sum. Few do at
    the default bound: the split sum's error against the sampled lobe is large on metals (Delta
    E_ITP 5-30 at the 99th percentile, measured and predicted alike); rough dielectrics and dark
    materials take it."""
    rows = world_results[bound]
    measured = np.array([m for *_, m in rows])
    within = float(np.mean(measured <= bound))
    chosen: dict[str, int] = {}
    for *_, c, _m in rows:
        chosen[c.name] = chosen.get(c.name, 0) + 1
    split = sum(n for name, n in chosen.items() if name.endswith(auto_terms.SPLIT_SUM))
    over = [(seed, name, c.name, round(c.predicted, 2), round(m, 2))
            for seed, name, c, m in rows if m > bound]
    print(f"bound {bound}: within {within:.1%} of {len(measured)}; chosen {chosen}; over: {over}")
    assert len(rows) >= 50, len(rows)
    assert within >= 0.95, f"{within:.1%} within {bound}; over: {over}"
    assert split >= SPLIT_SHARE[bound] * len(rows), f"the split sum by {split} of {len(rows)}: {chosen}"


def test_the_split_sums_predicted_error_against_the_measured(world_results):
    """Where a material took the split sum and either error is noticeable (>= 0.1): measured /
    predicted within a factor 2 for most (measured 2026-12-03: 72 % of 18, the largest ratio 3.4;
    11.6 before the levels' borders led to the poles' values: a rough metal floor)."""
    pairs = [(c.predicted, m) for bound in BOUNDS for *_, c, m in world_results[bound]
             if c.name.endswith(auto_terms.SPLIT_SUM) and max(c.predicted, m) >= 0.1]
    ratios = np.array([m / max(p, 1e-6) for p, m in pairs])
    inside = float(np.mean((ratios >= 0.5) & (ratios <= 2.0))) if len(ratios) else 0.0
    percentiles = np.round(np.percentile(ratios, [5, 25, 50, 75, 95, 100]), 3) if len(ratios) else []
    print(f"measured/predicted: {inside:.0%} of {len(ratios)} within a factor 2; percentiles "
          f"5/25/50/75/95/100 {percentiles}")
    assert len(ratios) >= 10, f"only {len(ratios)} materials to compare"
    assert inside >= 0.6, f"within a factor 2 for {inside:.0%}: {percentiles}"


def test_a_material_with_its_own_world_specular_keeps_it(tmp_path):
    scene, _camera, names = _world_scene(SEEDS[0])
    scene.shading_lab.term_set = "AUTO"
    bpy.data.materials[names[0]].shading_lab.world_specular = "SAMPLED"
    snap = extract.snapshot(bpy.context.evaluated_depsgraph_get(), auto_choice=True)
    assert names[0] not in snap.term_choices
    own = bpy.data.materials[names[0]].shading_lab.world_samples
    assert snap.materials[names[0]].environment_samples == own
    assert snap.term_choices and all(c.name.endswith(auto_terms.SPLIT_SUM) or c.name == "PRINCIPLED"
                                     for c in snap.term_choices.values()), snap.term_choices
