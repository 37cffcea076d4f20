"""Resources over a long session: GPU objects and memory across a thousand renders and a hundred
add-on register/unregister cycles, the program cache, and Blender's leak report at exit.

GPU objects are counted by a census (tests/gpu_census.py) of every texture, framebuffer, uniform
buffer, vertex/index buffer, batch and shader the add-on makes: after each render none it made may
still be alive, after each unregister none at all, and after each cycle's renders exactly the
programs and tables its caches hold. Memory is the process's current resident set (VmRSS from
/proc/self/status), measured after a warm-up (programs compiled, Blender's and Mesa's caches
filled) and again after the loop, with garbage collected both times; margins (printed with the
numbers by ``-s``):

* 1,000 final renders at 16 x 16: growth below RENDER_MARGIN_MB (8 MB, 8 kB per render);
* 100 unregister/register cycles, each followed by renders that compile every program again:
  growth below CYCLE_MARGIN_MB (10 MB).
"""

from __future__ import annotations

import collections
import gc
import subprocess
import sys
import textwrap
import weakref
from pathlib import Path

import bpy
import gpu
import numpy as np
import scenes
from gpu_census import Census
from gpu_harness import run_on_gpu

import addon
from addon.blender import engine
from addon.frame import gpu_library, renderer

ROOT = Path(__file__).resolve().parent.parent
RENDER_MARGIN_MB = 8.0
CYCLE_MARGIN_MB = 10.0
RENDERS = 1000
CYCLES = 100
LAMBERT = scenes.LAMBERT

#: Cycled through so that every kind of GPU object is made and dropped: three shading programs,
#: supersampling and a tone mapper (post-pass programs, a second target), the multiscatter table,
#: depth peeling with 4 and 2 layers.
CONFIGS = (
    dict(model="PBR", tone_mapper="BLENDER", samples=1, multiscatter=False, transparency_layers=4),
    dict(model="BLINN_PHONG", tone_mapper="BLENDER", samples=1, multiscatter=False),
    dict(model="PHONG", tone_mapper="BLENDER", samples=1, multiscatter=False),
    dict(model="PBR", tone_mapper="REINHARD", samples=2, multiscatter=True, transparency_layers=2),
)


def _rss_mb() -> float:
    gc.collect()
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS in /proc/self/status")



def _scene(size: int = 16):
    """The Lambert scene under a fully transparent plane: the peeling passes, their textures and
    framebuffers run on every render, and the image stays the closed form (0 x L + 1 x behind)."""
    from addon.blender.scene_builder import principled_material

    scene = scenes.lambert_scene(size)
    cover = principled_material("Invisible", (1.0, 1.0, 1.0))
    scenes.node_tree(cover).nodes["Principled BSDF"].inputs["Alpha"].default_value = 0.0
    scenes.plane(scene, size=4.0, location=(0.0, 0.0, 0.5), material=cover)
    return scene


def _configure(scene, config: dict) -> None:
    props = scene.shading_lab
    for key, value in config.items():
        setattr(props, key, value)


def _check_closed_form(scene, path: Path) -> None:
    _configure(scene, CONFIGS[0])
    image = scenes.render(scene, path)
    np.testing.assert_allclose(image[..., :3], LAMBERT, rtol=1e-4)


class _TrackedRenderer(renderer.Renderer):
    """The engine's renderer, remembered weakly: alive after a render means its GPU batches are
    still referenced."""

    live: weakref.WeakSet = weakref.WeakSet()
    made = 0

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        type(self).live.add(self)
        type(self).made += 1


def test_1000_renders_free_every_gpu_object_they_make_and_keep_memory_flat(tmp_path, monkeypatch):
    from addon.frame import passes

    original_gbuffer = passes.GBuffer
    monkeypatch.setattr(engine, "Renderer", _TrackedRenderer)
    # every other render shades deferred (its G-buffer and material table made and freed too)
    monkeypatch.setattr(passes, "deferred_pays", lambda features, *_counts:
                        deferred[0] and not features.peel and features.graph is None)
    deferred = [False]
    gbuffers = []
    monkeypatch.setattr(passes, "GBuffer", lambda *args: gbuffers.append(1) or original_gbuffer(*args))
    scene = _scene()
    for i in range(5 * len(CONFIGS)):  # warm-up: every program compiled, every cache filled
        _configure(scene, CONFIGS[i % len(CONFIGS)])
        deferred[0] = i % 2 == 0
        bpy.ops.render.render()
    programs_before = gpu_library.LIBRARY.program_count()
    made_before = _TrackedRenderer.made
    rss_before = _rss_mb()
    census = Census()
    with census.active():
        for i in range(RENDERS):
            _configure(scene, CONFIGS[i % len(CONFIGS)])
            deferred[0] = i % 2 == 0
            bpy.ops.render.render()
            alive = census.settle()
            assert not alive, f"render {i} ({CONFIGS[i % len(CONFIGS)]}) left alive {dict(alive)}"
    rss_after = _rss_mb()
    programs_after = gpu_library.LIBRARY.program_count()
    print(f"\n{RENDERS} renders (16x16): made {dict(census.made)} GPU objects, all freed; RSS "
          f"{rss_before:.1f} -> {rss_after:.1f} MB ({rss_after - rss_before:+.2f} MB, margin "
          f"{RENDER_MARGIN_MB} MB); programs {programs_before} -> {programs_after}")
    # each render makes textures, uniform blocks (its lights among them) and framebuffers
    assert min(census.made[kind] for kind in ("GPUTexture", "GPUUniformBuf", "GPUFrameBuffer")) >= RENDERS, (
        f"the census did not see the renders' targets: {dict(census.made)}")
    assert _TrackedRenderer.made - made_before == RENDERS, "every render must go through the engine"
    assert len(gbuffers) >= RENDERS // 2, f"{len(gbuffers)} G-buffers made: deferred every other render"
    assert len(_TrackedRenderer.live) == 0, "a renderer (and its GPU batches) outlived its render"
    assert programs_after == programs_before, "re-rendering the same scenes compiled new programs"
    assert rss_after - rss_before < RENDER_MARGIN_MB, f"RSS grew {rss_after - rss_before:.2f} MB"
    _check_closed_form(scene, tmp_path / "after.exr")


def test_same_scene_compiles_no_new_program():
    _scene()
    bpy.ops.render.render()
    count = gpu_library.LIBRARY.program_count()
    for _ in range(10):
        bpy.ops.render.render()
        assert gpu_library.LIBRARY.program_count() == count


def test_100_unregister_register_cycles_free_every_gpu_object(tmp_path):
    """Each cycle unregisters the add-on (after which nothing it made may be alive), registers it
    and renders every configuration, which compiles every program and table again."""
    census = Census()

    def cycle(scene) -> collections.Counter:
        addon.unregister()
        try:
            assert gpu_library.LIBRARY.program_count() == 0 and gpu_library.LIBRARY.table_count() == 0
            assert not hasattr(bpy.types.Scene, "shading_lab")
            left = census.settle()
            assert not left, f"unregister left GPU objects alive: {dict(left)}"
        finally:
            addon.register()
        scene.render.engine = "SHADING_LAB"
        for config in CONFIGS:
            _configure(scene, config)
            bpy.ops.render.render()
        return census.settle()

    scene = _scene()
    with census.active():
        for _ in range(5):  # warm-up
            cycle(scene)
        programs = gpu_library.LIBRARY.program_count()
        cached = cycle(scene)  # the programs and tables the caches hold after the renders
        rss_before = _rss_mb()
        for k in range(CYCLES):
            alive = cycle(scene)
            assert alive == cached, f"cycle {k}: {dict(alive)} alive after the renders, not {dict(cached)}"
            assert gpu_library.LIBRARY.program_count() == programs
        rss_after = _rss_mb()
    print(f"\n{CYCLES} unregister/register cycles ({len(CONFIGS)} renders each): made {dict(census.made)}; "
          f"alive after each cycle's renders {dict(cached)}, none after unregister; RSS {rss_before:.1f} -> "
          f"{rss_after:.1f} MB ({rss_after - rss_before:+.2f} MB, margin {CYCLE_MARGIN_MB} MB)")
    assert cached["GPUShader"] == programs, (dict(cached), programs)
    assert rss_after - rss_before < CYCLE_MARGIN_MB, f"RSS grew {rss_after - rss_before:.2f} MB"
    _check_closed_form(scene, tmp_path / "after.exr")


SUBPROCESS = textwrap.dedent("""
    import math, sys
    sys.path[:0] = [{root!r}, {tests!r}]
    import bpy
    import addon
    addon.register()
    import scenes
    from test_resources import CONFIGS, _configure, _scene

    scene = _scene()
    for i in range(5):
        _configure(scene, CONFIGS[i % len(CONFIGS)])
        bpy.ops.render.render()
    print("rendered 5 times")
""")


def _no_leak_report(proc) -> None:
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Not freed memory blocks" not in proc.stderr + proc.stdout, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]


def test_no_leaked_blocks_at_exit_after_5_renders(tmp_path):
    script = tmp_path / "five_renders.py"
    script.write_text(SUBPROCESS.format(root=str(ROOT), tests=str(ROOT / "tests")))
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120,
                          stdin=subprocess.DEVNULL, cwd=tmp_path)
    _no_leak_report(proc)
    assert "rendered 5 times" in proc.stdout


def test_no_leaked_blocks_at_exit_of_the_cli(tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "scripts" / "render.py"), "fresnel", "--model", "all",
                           "--resolution", "16x8", "--tone-mapper", "reinhard", "--samples", "2",
                           "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL, cwd=tmp_path)
    _no_leak_report(proc)
    assert (tmp_path / "out" / "fresnel_comparison.png").is_file()


def test_the_census_sees_an_object_kept_alive():
    """The census itself can fail: a texture and a batch someone keeps are counted, and counted no
    more once let go (with the vertex buffer only the batch held)."""
    census = Census()
    kept = []

    def job(_depsgraph):
        kept.append(gpu.types.GPUTexture((4, 4), format="RGBA32F"))
        fmt = gpu.types.GPUVertFormat()
        fmt.attr_add(id="pos", comp_type="F32", len=2, fetch_mode="FLOAT")
        vbo = gpu.types.GPUVertBuf(fmt, 3)
        vbo.attr_fill("pos", ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0)))
        kept.append(gpu.types.GPUBatch(type="TRIS", buf=vbo))
        gpu.types.GPUTexture((4, 4), format="RGBA32F")  # dropped at once

    with census.active():
        run_on_gpu(job)
        alive = census.settle()
        assert alive == {"GPUTexture": 1, "GPUBatch": 1, "GPUVertBuf": 1}, dict(alive)
        kept.clear()
        assert not census.settle(), dict(census.settle())
    assert census.made == {"GPUTexture": 2, "GPUBatch": 1, "GPUVertBuf": 1}, dict(census.made)
