"""scripts/render.py as a user runs it: a separate process, a saved .blend, files on disk."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import bpy
import numpy as np
import pytest
import scenes

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = ROOT / "scripts" / "render.py"


def _run(*args, cwd=ROOT):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=300, stdin=subprocess.DEVNULL)


def test_renders_a_saved_blend_with_every_model(tmp_path):
    scene = scenes.reset(size=8)
    scenes.ortho_camera(scene)
    mat = scenes.material(base_color=(0.5, 0.5, 0.5), f0=0.0, metalness=0.0, shininess=10.0,
                          specular_color=(0.0, 0.0, 0.0))
    scenes.plane(scene, size=4.0, material=mat)
    scenes.light(scene, "SUN", energy=2.0, rotation=(math.radians(45.0), 0.0, 0.0))
    scene.shading_lab.ambient = 0.0
    blend = tmp_path / "plane scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))

    out = tmp_path / "out"
    proc = _run(blend, "--model", "all", "--resolution", "24x12", "--out", out)
    assert proc.returncode == 0, proc.stderr[-2000:]
    stem = "plane scene"
    for model in ("blinn-phong", "phong", "pbr"):
        exr = scenes.read_exr(out / f"{stem}_{model}.exr")
        assert exr.shape == (12, 24, 4)
        # pure Lambert in every model here: rho / pi * E * cos 45
        np.testing.assert_allclose(exr[..., :3], 0.5 / math.pi * 2.0 * math.cos(math.radians(45.0)),
                                   rtol=1e-4)
        assert (out / f"{stem}_{model}.png").stat().st_size > 0
    assert (out / f"{stem}_comparison.png").is_file()


def test_missing_blend_is_one_clear_line(tmp_path):
    proc = _run(tmp_path / "nope.blend", "--out", tmp_path / "out")
    assert proc.returncode == 2
    assert "no such .blend file" in proc.stderr
    assert not (tmp_path / "out" / "nope_pbr.exr").exists()


def test_unwritable_output_directory(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    proc = _run("demo", "--model", "pbr", "--resolution", "8x8", "--out", blocker / "sub")
    assert proc.returncode == 2
    assert "cannot create output directory" in proc.stderr


def test_bad_resolution(tmp_path):
    proc = _run("demo", "--resolution", "wide", "--out", tmp_path)
    assert proc.returncode == 2 and "--resolution must look like 1280x720" in proc.stderr


def test_demo_frames_and_lights_every_sphere(tmp_path):
    """``./run demo``: the ten spheres whole inside the frame, and each lit in the physically
    based render (the world and the key sun reach the gold too)."""
    w, h = 96, 54
    out = tmp_path / "out"
    proc = _run("demo", "--model", "all", "--resolution", f"{w}x{h}", "--out", out)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (out / "demo_comparison.png").is_file()
    images = {model: scenes.read_exr(out / f"demo_{model}.exr") for model in ("blinn-phong", "phong", "pbr")}
    for image in images.values():
        assert image.shape == (h, w, 4) and np.isfinite(image).all() and image.min() >= 0.0

    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    sys.path.insert(0, str(ROOT / "scripts"))
    import demo_scene

    scene = scenes.reset(size=8)
    demo_scene.build(scene)
    scene.render.resolution_x, scene.render.resolution_y = w, h
    bpy.context.view_layer.update()
    spheres = [ob for ob in scene.objects if ob.name.startswith("Sphere")]
    assert len(spheres) == 10
    luminance = images["pbr"][..., :3] @ np.array([0.2126, 0.7152, 0.0722], np.float32)
    for ob in spheres:
        centre = Vector(ob.location)
        for d in ((1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 0, -1), (0, 1, 0), (0, -1, 0)):
            p = world_to_camera_view(scene, scene.camera, centre + demo_scene.RADIUS * Vector(d))
            assert 0.03 < p.x < 0.97 and 0.03 < p.y < 0.97 and p.z > 0.0, (ob.name, d, tuple(p))
        p = world_to_camera_view(scene, scene.camera, centre)
        edge = world_to_camera_view(scene, scene.camera, centre + Vector((demo_scene.RADIUS, 0.0, 0.0)))
        r = 0.6 * (edge.x - p.x) * w  # the inner part of the sphere's disc, in pixels
        ys, xs = np.mgrid[0:h, 0:w]
        inside = (xs + 0.5 - p.x * w) ** 2 + (ys + 0.5 - (1.0 - p.y) * h) ** 2 < r * r
        assert inside.sum() >= 4
        mean = float(luminance[inside].mean())
        assert mean > 0.05, (ob.data.materials[0].name, mean)


def test_usage_inside_blender_argv_convention(tmp_path):
    """``blender -b --python render.py -- ARGS``: everything before ``--`` belongs to Blender."""
    sys.path.insert(0, str(ROOT / "scripts"))
    import render

    args = render.parse_args(["blender", "-b", "--python", "render.py", "--", "demo", "--model", "pbr"])
    assert (args.scene, args.model) == ("demo", "pbr")
    assert os.fspath(args.out) == "out"


def test_preset_frames_and_term_options(tmp_path):
    out = tmp_path / "out"
    proc = _run("roughness_sweep", "--model", "pbr", "--resolution", "32x18", "--frames", "1-2",
                "--ndf", "beckmann", "--visibility", "smith-separable", "--diffuse", "oren-nayar",
                "--multiscatter", "--tone-mapper", "aces", "--out", out)
    assert proc.returncode == 0, proc.stderr[-2000:]
    for frame in (1, 2):
        exr = scenes.read_exr(out / f"roughness_sweep_pbr_{frame:04d}.exr")
        assert exr.shape == (18, 32, 4) and np.isfinite(exr).all()
        assert exr[..., :3].max() <= 1.0  # ACES fills Combined with display values in [0, 1]
    assert not list(out.glob(".*partial*")), "no partial files left behind"
    assert "2/2" in proc.stderr  # the progress bar reached the end


def test_a_preset_renders_to_the_same_bits_in_every_process(tmp_path):
    """Two processes (each its own hash seed and memory layout) render a preset of UV spheres, whose
    seams bmesh welds through a hash of addresses, to the same bits: each primitive's faces are
    put in one order (scene_builder._sort_faces; without it the images differed by up to 1.5e-3)."""
    images = []
    for run in ("a", "b"):
        out = tmp_path / run
        proc = _run("furnace", "--model", "pbr", "--resolution", "64x27", "--out", out)
        assert proc.returncode == 0, proc.stderr[-2000:]
        images.append(scenes.read_exr(out / "furnace_pbr.exr"))
    assert images[0][..., :3].max() > 0.1
    differ = float(np.abs(images[0] - images[1]).max())
    assert differ == 0.0, f"{differ} largest difference between the two processes"


def test_unknown_preset_and_bad_options(tmp_path):
    proc = _run("fresnell", "--out", tmp_path)
    assert proc.returncode == 2 and 'did you mean "fresnel"' in proc.stderr
    proc = _run("fresnel", "--frames", "5-2", "--out", tmp_path)
    assert proc.returncode == 2 and "comes before" in proc.stderr
    proc = _run("portability", "--variant", "moonlight", "--out", tmp_path)
    assert proc.returncode == 2 and "no lighting variant" in proc.stderr
    proc = _run("fresnel", "--transparency-layers", "0", "--out", tmp_path)
    assert proc.returncode == 2 and "--transparency-layers must be between 1 and 16, got 0" in proc.stderr
    assert not any(tmp_path.glob("*.exr"))


def test_shadow_options_reach_the_scene():
    sys.path.insert(0, str(ROOT / "scripts"))
    import render as cli

    scene = scenes.reset(size=8)
    cli.configure(scene, cli.parse_args(["x"]))
    props = scene.shading_lab
    assert (props.shadows, props.shadow_map_size, props.soft_shadows) == (True, "1024", True)
    assert not scene.render.use_persistent_data
    args = cli.parse_args(["x", "--no-shadows", "--shadow-map-size", "2048", "--no-soft-shadows",
                           "--persistent-data"])
    cli.configure(scene, args)
    assert (props.shadows, props.shadow_map_size, props.soft_shadows) == (False, "2048", False)
    assert scene.render.use_persistent_data
    cli.configure(scene, cli.parse_args(["x", "--no-persistent-data"]))
    assert not scene.render.use_persistent_data
    with pytest.raises(SystemExit):
        cli.parse_args(["x", "--shadow-map-size", "300"])


def test_world_options_reach_the_scene():
    sys.path.insert(0, str(ROOT / "scripts"))
    import render as cli

    scene = scenes.reset(size=8)
    props = scene.shading_lab
    cli.configure(scene, cli.parse_args(["x"]))
    assert (props.world_specular, props.world_diffuse, props.world_occlusion) == ("SPLIT_SUM", "MAP", True)
    cli.configure(scene, cli.parse_args(["x", "--world-specular", "sampled", "--world-samples", "16",
                                         "--world-diffuse", "sh9", "--no-world-occlusion"]))
    assert (props.world_specular, props.world_samples, props.world_diffuse, props.world_occlusion) == (
        "SAMPLED", 16, "SH9", False)
    for bad, message in ((["--world-samples", "0"], "between 1 and 1024, got 0"),
                         (["--world-specular", "split-sum", "--world-samples", "8"],
                          "needs --world-specular")):
        with pytest.raises(cli.CliError, match=message):
            cli.configure(scene, cli.parse_args(["x", *bad]))


def test_warnings_are_listed_once_per_run(tmp_path):
    """What the engine could not read is listed by the CLI once, whatever the number of models."""
    scene = scenes.reset(size=8)
    scenes.ortho_camera(scene)
    mat = scenes.unread_material()
    scenes.plane(scene, size=4.0, material=mat)
    scenes.light(scene, "SUN", energy=2.0)
    blend = tmp_path / "mixed.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    proc = _run(blend, "--model", "all", "--resolution", "8x8", "--out", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr[-2000:]
    listed = [line for line in proc.stderr.splitlines() if line.startswith("warning: ")]
    assert listed == ["warning: Material 'Mixed': its surface shader (Mix Shader) is not read; it is drawn "
                      "with its viewport display values"], proc.stderr[-2000:]
