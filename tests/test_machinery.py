"""The comparison machinery (scripts/metrics.py, reference.py, compare.py): metrics on known
images, the multi-layer EXR round trip, and the reference cache."""

from __future__ import annotations

import sys
import types
from pathlib import Path

import bpy
import numpy as np
import OpenEXR
import pytest
import scenes

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))

import compare  # noqa: E402
import metrics  # noqa: E402
import reference  # noqa: E402


def _image(value, shape=(16, 24)):
    return np.full(shape + (3,), value, np.float32)


def test_metrics_on_known_images():
    ref = np.random.default_rng(0).uniform(0.1, 4.0, (32, 48, 3)).astype(np.float32)
    same = metrics.errors(ref, ref)
    assert same.flip == pytest.approx(0.0, abs=1e-6) and same.mean_relative == 0.0 and same.max_abs == 0.0
    scaled = metrics.errors(ref, ref * 1.1)
    assert scaled.mean_relative == pytest.approx(0.1, rel=1e-5)  # luminance scales linearly
    assert scaled.max_abs == pytest.approx(float((ref * 0.1).max()), rel=1e-5)
    assert 0.0 < scaled.flip < metrics.errors(ref, ref * 2.0).flip  # FLIP grows with the error
    dark = ref.copy()
    dark[:8] = 0.0  # unlit rows: excluded from the relative error
    assert metrics.errors(dark, dark * 1.5).lit_pixels == 24 * 48
    with pytest.raises(ValueError, match="sizes differ"):
        metrics.errors(ref, ref[:8])


def test_multilayer_exr_round_trip(tmp_path):
    layers = {"reference": np.random.default_rng(1).uniform(0, 50, (9, 7, 3)).astype(np.float32),
              "pbr": _image(0.25, (9, 7)), "error_pbr": _image(1e-6, (9, 7))}
    path = tmp_path / "layers.exr"
    compare.write_multilayer(path, layers)
    with OpenEXR.File(str(path), separate_channels=True) as f:  # the file's own channel names
        channels = f.channels()  # valid while the file is open
        for name, image in layers.items():
            got = np.stack([np.asarray(channels[f"{name}.{c}"].pixels) for c in "RGB"], axis=-1)
            np.testing.assert_array_equal(got, image)  # float32 stored exactly
    assert not list(tmp_path.glob(".*partial*"))


def test_reference_cache_and_fingerprint(tmp_path):
    scene = scenes.reset(size=8)
    scenes.ortho_camera(scene)
    scenes.plane(scene, size=4.0)
    light = scenes.light(scene, "SUN", energy=2.0)
    light.data.use_shadow = True  # the reference must turn shadows off and restore them
    first, cached = reference.render_reference(scene, samples=4, cache_dir=tmp_path)
    assert not cached and first[..., 0].max() > 0
    assert light.data.use_shadow and scene.render.engine == "SHADING_LAB"
    again, cached = reference.render_reference(scene, samples=4, cache_dir=tmp_path)
    assert cached
    np.testing.assert_array_equal(again, first)
    key = reference.scene_fingerprint(scene)
    light.data.energy = 3.0
    assert reference.scene_fingerprint(scene) != key
    brighter, cached = reference.render_reference(scene, samples=4, cache_dir=tmp_path)
    assert not cached
    np.testing.assert_allclose(brighter[..., :3], first[..., :3] * 1.5, rtol=1e-5)  # Cycles, linear in power


def test_reference_fingerprint_follows_node_graphs(tmp_path):
    """What decides a Cycles render and is not a socket value changes the cache key too: a world
    image swapped for another, a node linked, a packed image's pixels."""
    scene = scenes.reset()
    scenes.ortho_camera(scene)
    mat = bpy.data.materials.new("Surface")
    scenes.plane(scene, size=4.0, material=mat)
    tree = scenes.node_tree(scene.world)
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    keys = [reference.scene_fingerprint(scene)]
    tree.links.new(env.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    keys.append(reference.scene_fingerprint(scene))
    image = bpy.data.images.new("sky", 8, 4, float_buffer=True)
    env.image = image
    keys.append(reference.scene_fingerprint(scene))
    image.pixels.foreach_set(np.full(8 * 4 * 4, 0.5, np.float32))
    keys.append(reference.scene_fingerprint(scene))
    env.image = bpy.data.images.new("sky", 8, 4, float_buffer=True)  # same pixels, another name
    keys.append(reference.scene_fingerprint(scene))
    mtree = scenes.node_tree(mat)
    principled = next(n for n in mtree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    value = mtree.nodes.new("ShaderNodeValue")
    keys.append(reference.scene_fingerprint(scene))  # an unlinked node: also a change (kept simple)
    mtree.links.new(value.outputs[0], principled.inputs["Roughness"])
    keys.append(reference.scene_fingerprint(scene))
    assert len(set(keys)) == len(keys), keys
    assert reference.scene_fingerprint(scene) == keys[-1]  # and stable


def test_compare_command_on_a_preset(tmp_path):
    """compare.py end to end: the files, and the physically based model closer to Cycles than
    Blinn-Phong on the long-tail scene (measured with FLIP)."""
    import subprocess

    script = Path(__file__).resolve().parent.parent / "scripts" / "compare.py"
    proc = subprocess.run([sys.executable, str(script), "long_tail", "--resolution", "96x54",
                           "--reference-samples", "16", "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stderr[-2000:]
    for suffix in ("_compare.exr", "_compare.png", "_metrics.md"):
        assert (tmp_path / f"long_tail{suffix}").stat().st_size > 0
    rows = {line.split("|")[1].strip(): line.split("|")[2:] for line in
            (tmp_path / "long_tail_metrics.md").read_text().splitlines() if line.startswith("| ")}
    flip = {name: float(cols[0]) for name, cols in rows.items() if name in
            ("Blinn-Phong", "Phong", "Physically Based")}
    assert flip["Physically Based"] < 0.5 * flip["Blinn-Phong"]


def test_results_script_drives_compare(tmp_path, monkeypatch):
    """scripts/results.py hands compare.py every option it reads (a missing one once broke the
    whole document): one scene with a term override, the startup file, end to end, tiny."""
    import results

    monkeypatch.setattr(results, "OUT", tmp_path)
    args = types.SimpleNamespace(resolution="32x18", reference_samples=4)
    result = results.run("long_tail", args, tag="_beckmann", ndf="beckmann")
    assert result["png"].is_file() and result["png"].parent == tmp_path
    assert result["stem"] == "long_tail_beckmann"
    startup = results.run("startup", args)
    assert 0.0 <= results._flip(startup, "Physically Based") < results._flip(startup, "Blinn-Phong")


def test_round_robin_settles_an_engine_after_another_engines_render():
    """The benchmarks' round robin (scripts/bench/harness/timing.py) times each item in rotated
    rounds; a timed render that follows another engine's render comes after an untimed one of its
    own (that render's time is discarded)."""
    from bench.harness import timing

    calls = []
    items = [("ours-a", "ours"), ("ours-b", "ours"), ("peer", "peer")]

    def run(item):
        calls.append(item[0])
        # the first render after an engine switch is slow, as ours is after an EEVEE render
        switched = len(calls) > 1 and dict(items)[calls[-2]] != item[1]
        return {"ms": 100.0 if switched else 1.0}

    steps = []
    progress = types.SimpleNamespace(step=steps.append, expect=lambda n: steps.append(n))
    times = timing.round_robin(items, 3, run, progress, "test", state_of=lambda item: item[1])
    assert [t["ms"] for t in times] == [1.0, 1.0, 1.0], (times, calls)
    a, b, peer = (item[0] for item in items)
    assert calls == [a, b, peer,  # the warm-up round, then rounds rotated by one each
                     b, b, peer, peer, a, a,  # each switch of engine: an untimed render first
                     peer, peer, a, a, b,
                     a, b, peer, peer], calls
    assert steps[0] == 4 * len(items) and len(steps) == 1 + 4 * len(items), steps  # announced, then each
    calls.clear()
    plain = timing.round_robin(items, 3, run)  # without state_of: no settling
    assert max(t["ms"] for t in plain) == 100.0, plain
