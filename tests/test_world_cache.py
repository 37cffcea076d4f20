"""The world's maps kept on disk between sessions (addon/plan/world_cache.py): a later session reads
them instead of computing them, and renders exactly what it would have computed; a changed world
computes again; a broken file or a folder that cannot be written loses nothing."""

from __future__ import annotations

import os
import time

import bpy
import numpy as np
import pytest
import scenes
from test_world_light import _diffuse, _glossy, _sphere, _world

from addon.frame import gpu_environment, gpu_library
from addon.plan import world_cache


def _image(folder, seed: int = 0, bright: float = 500.0) -> bpy.types.Image:
    """A 64 x 32 float world with noise and one texel far above the sun threshold (so the maps
    include the clamped chain), saved to ``folder`` as an artist's file is (an unsaved image is
    read again for every render, and its maps looked up again)."""
    h, w = 32, 64
    pixels = np.ones((h, w, 4), np.float32)
    pixels[..., :3] = np.random.default_rng(seed).uniform(0.05, 2.0, (h, w, 3))
    pixels[24, 40, :3] = bright
    return scenes.saved_float_image(f"World {seed}", pixels, folder)


def _scene(folder):
    scene = scenes.reset(size=48)
    scene.render.resolution_x, scene.render.resolution_y = 96, 48
    scene.shading_lab.model = "PBR"
    scene.shading_lab.world_occlusion = False
    scenes.ortho_camera(scene, location=(0.0, 0.0, 10.0), scale=4.0)
    _sphere((-1.0, 0.0, 0.0), _glossy("smooth metal", 0.05), radius=0.9)
    _sphere((1.0, 0.0, 0.0), _diffuse("white"), radius=0.9)
    _sphere((0.0, 0.8, -1.0), _glossy("rough metal", 0.6), radius=0.6)
    _world(scene, image=_image(folder))
    return scene


def _renders(scene, tmp_path, name: str) -> list[np.ndarray]:
    """The scene with the split sum and with sampled world specular (which reads the chains)."""
    out = []
    for mode in ("SPLIT_SUM", "SAMPLED"):
        scene.shading_lab.world_specular = mode
        out.append(scenes.render(scene, tmp_path / f"{name}_{mode}.exr"))
        world_cache.wait()
    return out


def _files(folder) -> list:
    return sorted(folder.glob("*.maps"))


@pytest.fixture
def cache(monkeypatch, tmp_path):
    folder = tmp_path / "cache"
    monkeypatch.setenv("SHADING_LAB_CACHE", str(folder))
    monkeypatch.delenv("SHADING_LAB_CACHE_MB", raising=False)
    gpu_library.LIBRARY.clear()  # nothing held in memory: every world is new to this "session"
    yield folder
    world_cache.wait()
    gpu_library.LIBRARY.clear()


def test_a_later_session_reads_the_maps_and_renders_exactly_the_same(cache, tmp_path):
    scene = _scene(tmp_path)
    builds, loads, saves = gpu_environment.BUILDS, gpu_environment.LOADS, world_cache.SAVES
    built = _renders(scene, tmp_path, "built")
    assert gpu_environment.BUILDS == builds + 1 and world_cache.SAVES == saves + 1
    assert len(_files(cache)) == 1
    gpu_library.LIBRARY.clear()  # a new session: the maps only on disk
    loaded = _renders(scene, tmp_path, "loaded")
    assert gpu_environment.BUILDS == builds + 1, "the maps were computed again, not read"
    assert gpu_environment.LOADS == loads + 1
    for mode, a, b in zip(("split sum", "sampled"), built, loaded):
        assert a[..., :3].max() > 0.1, f"{mode}: an unlit render proves nothing"
        diff = float(np.abs(a - b).max())
        assert diff == 0.0, f"{mode}: the render from the kept maps differs by up to {diff:g}"


def test_the_chains_are_made_only_for_surfaces_that_sample_the_world(cache, tmp_path):
    """The downsampled chains (two textures the size of the mirror level and its halvings) are what
    per-pixel sampling reads; split-sum renders keep only the atlas, and the file only the atlas
    and the SH. A surface that samples later gets them drawn then, and renders exactly as if the
    maps had been built with them."""
    scene = _scene(tmp_path)
    scene.shading_lab.world_specular = "SPLIT_SUM"
    scenes.render(scene, tmp_path / "split.exr")
    world_cache.wait()
    (held,) = gpu_library.LIBRARY._environments.values()
    assert held.chain is None and held.clamped_chain is None
    (path,) = _files(cache)
    arrays = world_cache.load(path.stem, {})
    assert sorted(arrays) == ["atlas", "sh"], sorted(arrays)
    scene.shading_lab.world_specular = "SAMPLED"
    added = scenes.render(scene, tmp_path / "added.exr")
    assert held.chain is not None and held.clamped_chain is not None
    gpu_library.LIBRARY.clear()
    world_cache.clear()
    builds = gpu_environment.BUILDS
    built = scenes.render(scene, tmp_path / "built.exr")  # built with the chains from the start
    assert gpu_environment.BUILDS == builds + 1
    assert added[..., :3].max() > 0.1
    diff = float(np.abs(added - built).max())
    assert diff == 0.0, f"chains drawn later render {diff:g} off"


def test_a_changed_world_is_computed_again(cache, tmp_path):
    scene = _scene(tmp_path)
    scenes.render(scene, tmp_path / "a.exr")
    world_cache.wait()
    builds = gpu_environment.BUILDS
    scene.world.node_tree.nodes["Environment Texture"].image = _image(tmp_path, seed=1)  # other pixels
    scenes.render(scene, tmp_path / "b.exr")
    world_cache.wait()
    assert gpu_environment.BUILDS == builds + 1
    scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.5
    scenes.render(scene, tmp_path / "c.exr")
    assert gpu_environment.BUILDS == builds + 2
    world_cache.wait()
    assert len(_files(cache)) == 3


def test_a_broken_file_is_replaced_and_the_render_is_unchanged(cache, tmp_path, capsys):
    scene = _scene(tmp_path)
    want = scenes.render(scene, tmp_path / "built.exr")
    world_cache.wait()
    (path,) = _files(cache)
    path.write_bytes(path.read_bytes()[:100_000])  # truncated, as by a full disk
    gpu_library.LIBRARY.clear()
    builds = gpu_environment.BUILDS
    got = scenes.render(scene, tmp_path / "again.exr")
    world_cache.wait()
    assert gpu_environment.BUILDS == builds + 1
    assert "could not be read" in capsys.readouterr().out
    assert float(np.abs(got - want).max()) == 0.0
    gpu_library.LIBRARY.clear()
    loads = gpu_environment.LOADS
    scenes.render(scene, tmp_path / "loaded.exr")  # the file written again reads back
    assert gpu_environment.LOADS == loads + 1


def test_a_folder_that_cannot_be_written_costs_nothing_but_the_cache(monkeypatch, tmp_path, capsys):
    blocker = tmp_path / "a file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("SHADING_LAB_CACHE", str(blocker / "cache"))
    gpu_library.LIBRARY.clear()
    scene = _scene(tmp_path)
    image = scenes.render(scene, tmp_path / "r.exr")
    world_cache.wait()
    gpu_library.LIBRARY.clear()
    assert image[..., :3].max() > 0.1
    assert "cannot keep the world's lighting" in capsys.readouterr().out


def test_the_cache_off_reads_and_writes_nothing(monkeypatch, tmp_path):
    monkeypatch.setenv("SHADING_LAB_CACHE", "off")
    assert world_cache.folder() is None
    gpu_library.LIBRARY.clear()
    saves = world_cache.SAVES
    scenes.render(_scene(tmp_path), tmp_path / "r.exr")
    world_cache.wait()
    gpu_library.LIBRARY.clear()
    assert world_cache.SAVES == saves


def test_the_folder_keeps_within_its_budget_dropping_the_least_recently_used(tmp_path):
    now = time.time()
    for k, age in enumerate((50, 10, 30, 40)):  # seconds since last use
        path = tmp_path / f"{k}.maps"
        path.write_bytes(b"x" * 1000)
        os.utime(path, (now - age, now - age))
    stale, fresh = tmp_path / "old.tmp", tmp_path / "new.tmp"  # writers that stopped half-way
    for path, age in ((stale, 7200), (fresh, 60)):
        path.write_bytes(b"x")
        os.utime(path, (now - age, now - age))
    world_cache._keep_within_budget(tmp_path, 2500)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["1.maps", "2.maps", "new.tmp"]


def test_the_key_is_the_content(tmp_path):
    """Same content, same key (whatever the image is called); any change in what the maps depend
    on, another key."""
    from addon.scene.snapshot import EnvironmentTerm, ImageData

    pixels = np.random.default_rng(2).uniform(0.0, 1.0, (8, 16, 4)).astype(np.float32)

    def key(pixels=pixels, weight=(1.0, 1.0, 1.0), lookup=None, threshold=10.0, suns=True,
            constant=(0.0, 0.0, 0.0), device="gpu", name="a"):
        lookup = np.eye(4) if lookup is None else lookup
        terms = (EnvironmentTerm(weight, ImageData(name, pixels), lookup=np.asarray(lookup, np.float32)),
                 EnvironmentTerm(constant))
        return world_cache.content_key(terms, threshold, suns, device)

    other = pixels.copy()
    other[3, 4, 1] += 1e-6
    turned = np.eye(4)
    turned[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
    base = key()
    assert key(name="b") == base
    changed = [key(pixels=other), key(weight=(1.0, 1.0, 0.5)), key(lookup=turned), key(threshold=20.0),
               key(suns=False), key(constant=(0.1, 0.0, 0.0)), key(device="another gpu"),
               key(pixels=pixels.astype(np.float16))]
    assert base not in changed and len(set(changed)) == len(changed)


def test_the_world_panel_shows_what_is_kept_and_the_operator_clears_it(cache, tmp_path, monkeypatch):
    from types import SimpleNamespace

    from test_ui import _draw

    from addon.blender import ui

    scene = _scene(tmp_path)
    scenes.render(scene, tmp_path / "r.exr")
    world_cache.wait()
    (path,) = _files(cache)
    megabytes = path.stat().st_size / 2 ** 20
    labels = _draw(ui.SHADINGLAB_PT_world, SimpleNamespace(world=scene.world, scene=scene)).log
    assert ("label", f"1 world, {megabytes:.0f} MB on disk", True) in labels, labels
    assert ("operator", "shading_lab.clear_world_cache", True) in labels
    assert bpy.ops.shading_lab.clear_world_cache() == {"FINISHED"}
    assert not _files(cache) and world_cache.usage() == (0, 0)
    monkeypatch.setenv("SHADING_LAB_CACHE", "off")
    labels = _draw(ui.SHADINGLAB_PT_world, SimpleNamespace(world=scene.world, scene=scene)).labels()
    assert "Off (SHADING_LAB_CACHE=off)" in labels
    assert bpy.ops.shading_lab.clear_world_cache() == {"CANCELLED"}


def test_an_image_being_edited_is_not_kept(cache, tmp_path):
    """An unsaved image (painted, generated) is read again for every render: each edit would
    write a file. Its world is computed as without the cache."""
    scene = _scene(tmp_path)
    image = scene.world.node_tree.nodes["Environment Texture"].image
    pixels = np.empty(len(image.pixels), np.float32)
    image.pixels.foreach_get(pixels)
    image.pixels.foreach_set(pixels * 1.5)  # an edit, not saved
    assert image.is_dirty
    builds, loads, saves = gpu_environment.BUILDS, gpu_environment.LOADS, world_cache.SAVES
    scenes.render(scene, tmp_path / "a.exr")
    scenes.render(scene, tmp_path / "b.exr")
    world_cache.wait()
    assert (gpu_environment.BUILDS, gpu_environment.LOADS, world_cache.SAVES) == (builds + 2, loads, saves)
    assert not _files(cache)
    image.save()  # saved: kept from the next render on
    scenes.render(scene, tmp_path / "c.exr")
    world_cache.wait()
    assert world_cache.SAVES == saves + 1 and len(_files(cache)) == 1
