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
    assert listed == ["warning: Material 'Haired': 1 of 1 nodes not compiled (Hair BSDF "
                      "(ShaderNodeBsdfHair)); what they feed takes its socket's own value"], \
        proc.stderr[-2000:]


# --- every option reaches the scene, and the image changes as the option says -------------------


def _cli():
    sys.path.insert(0, str(ROOT / "scripts"))
    import render as cli

    return cli


def _configured(scene, *options):
    """``scene`` set up by render.py's options, as the CLI does before rendering."""
    cli = _cli()
    cli.configure(scene, cli.parse_args(["x", *options]))
    return scene


def _fresnel_exact(theta, n=1.5):
    """The unpolarised Fresnel reflectance of a dielectric of index n at incidence cos theta,
    from Fresnel's equations (s and p), not from the engine's formula."""
    c = math.cos(theta)
    s = math.sqrt(1.0 - (1.0 - c * c) / n ** 2)
    rs = (c - n * s) / (c + n * s)
    rp = (n * c - s) / (n * c + s)
    return 0.5 * (rs * rs + rp * rp)


def test_fresnel_option_takes_the_exact_dielectric_fresnel(tmp_path):
    """--fresnel exact: a black dielectric seen in its mirror direction (h = n, l.h = cos theta,
    D, V and the light cancel in the ratio) is brighter than under Schlick by F_exact / F_Schlick
    at 85 degrees, F from Fresnel's equations written above (F0 0.04 = IOR 1.5)."""
    from test_phenomena import _mirror_scene

    theta = math.radians(85.0)
    images = {}
    for option in ("schlick", "exact"):
        scene = _configured(_mirror_scene(85.0, "PBR", base_color=(0, 0, 0), metalness=0.0, f0=0.04,
                                          roughness=0.3), "--fresnel", option)
        assert scene.shading_lab.fresnel == option.upper()
        images[option] = scenes.render(scene, tmp_path / f"{option}.exr")[..., :3].astype(np.float64)
    schlick = 0.04 + 0.96 * (1.0 - math.cos(theta)) ** 5
    want = _fresnel_exact(theta) / schlick
    got = images["exact"].mean() / images["schlick"].mean()
    err = abs(got / want - 1.0)
    print(f"exact / Schlick at 85 degrees: {got:.6f}, Fresnel's equations {want:.6f} (relative {err:.1e})")
    assert err < 1e-6, f"{got:.6f} against {want:.6f}: relative error {err:.1e} (measured 1.9e-7)"
    assert abs(want - 1.0) > 0.05, "the two Fresnel terms differ here"


def test_term_set_options_reach_the_scene_and_the_image(tmp_path, monkeypatch):
    """--principled and --term-set principled are one setting: the same image, to the bit, and
    not the custom terms' image; --term-set auto with --error-bound: a loose bound lets Auto take
    cheaper terms than the Principled set, a tight one keeps the Principled set."""
    from addon.blender import engine
    from addon.blender.scene_builder import principled_material
    from addon.plan import auto_terms

    # one small scene: a cheaper program would not repay its first use within Auto's payback
    # frames, so Auto keeps one program unless its cost is spread over many frames
    monkeypatch.setattr(auto_terms, "PAYBACK_FRAMES", 1e12)

    def scene_():
        scene = scenes.reset(size=16)
        scenes.ortho_camera(scene, scale=2.0)
        scenes.plane(scene, size=4.0, rotation=(math.radians(20.0), 0.0, 0.0),
                     material=principled_material("gold", (1.0, 0.71, 0.29), 1.0, 0.6))
        scenes.light(scene, "POINT", energy=200.0, location=(0.3, 0.2, 1.0))
        return scene

    images = {}
    for name, options in {"custom": ("--term-set", "custom"), "principled": ("--principled",),
                          "term-set": ("--term-set", "principled")}.items():
        scene = _configured(scene_(), *options)
        assert scene.shading_lab.term_set == ("CUSTOM" if name == "custom" else "PRINCIPLED")
        images[name] = scenes.render(scene, tmp_path / f"{name}.exr")
    assert np.array_equal(images["principled"], images["term-set"])
    apart = float(np.abs(images["principled"] - images["custom"]).max())
    assert apart > 1e-3, f"the Principled set's image is the custom terms' ({apart:.2e})"
    chosen = {}
    for bound in (50.0, 0.01):
        scene = _configured(scene_(), "--term-set", "auto", "--error-bound", str(bound))
        props = scene.shading_lab
        assert (props.term_set, props.auto_error_bound) == ("AUTO", pytest.approx(bound))
        images[bound] = scenes.render(scene, tmp_path / f"auto{bound}.exr")
        chosen[bound] = {c.name for c in engine.last_term_choices.values()}
    print(f"Auto's choices: bound 50 {chosen[50.0]}, bound 0.01 {chosen[0.01]}")
    assert chosen[0.01] == {"PRINCIPLED"} and "PRINCIPLED" not in chosen[50.0], chosen
    assert np.array_equal(images[0.01], images["principled"])
    assert float(np.abs(images[50.0] - images["principled"]).max()) > 1e-4, "the cheaper terms' image"


def test_normalized_blinn_phong_option_scales_the_highlight(tmp_path):
    """--normalized-blinn-phong: at n.h = 1 the highlight is (s + 8) / 8 times the seed's
    unnormalised one (the (s + 8) / (8 pi) normalisation against c_PL's 1 / pi)."""
    images = {}
    for option in ("--no-normalized-blinn-phong", "--normalized-blinn-phong"):
        scene = scenes.reset(size=8)
        scene.shading_lab.model, scene.shading_lab.ambient = "BLINN_PHONG", 0.0
        scenes.ortho_camera(scene, scale=1.0)
        scenes.plane(scene, size=4.0, material=scenes.material(base_color=(0, 0, 0), shininess=20.0,
                                                               specular_color=(0.1, 0.1, 0.1)))
        scenes.light(scene, "SUN", energy=1.0)
        _configured(scene, option)
        assert scene.shading_lab.normalized_blinn_phong == (option == "--normalized-blinn-phong")
        images[option] = scenes.render(scene, tmp_path / f"{option}.exr")[..., :3].astype(np.float64)
    ratio = images["--normalized-blinn-phong"] / images["--no-normalized-blinn-phong"]
    err = float(np.abs(ratio / ((20.0 + 8.0) / 8.0) - 1.0).max())
    assert err < 1e-5, f"normalised / unnormalised off (s + 8) / 8 by {err:.1e}"


def _gradient_scene(size=32):
    """A Lambert plane (rho 0.5) filling a 6 m view, 1 m under a 100 W point light and nothing
    else: a range of radiance to meter."""
    scene = scenes.reset(size=size)
    scene.shading_lab.ambient = 0.0
    scenes.ortho_camera(scene, scale=6.0)
    scenes.plane(scene, size=8.0, material=scenes.material(base_color=(0.5, 0.5, 0.5), f0=0.0, metalness=0.0,
                                                           shininess=10.0, specular_color=(0.0, 0.0, 0.0)))
    scenes.light(scene, "POINT", energy=100.0, location=(0.0, 0.0, 1.0))
    return scene


def test_exposure_options_meter_and_compensate_as_they_say(tmp_path):
    """--exposure auto --exposure-metering log-average meters log2(0.18 / L_w), L_w the frame's
    log-average luminance (Reinhard et al. 2002, eq. 1) computed here from the radiance; the
    histogram meters otherwise; --exposure-compensation 1 doubles the display values of the
    clamp tone mapper."""
    from addon.blender import engine

    radiance = scenes.render(_gradient_scene(), tmp_path / "radiance.exr")[..., :3].astype(np.float64)
    lum = radiance @ np.array([0.2126, 0.7152, 0.0722])
    want = math.log2(0.18 / 2.0 ** np.log2(np.maximum(lum, 2.0 ** -16)).mean())  # exposure.LOG_MIN
    metered, images = {}, {}
    for name, options in {"log": ("--exposure-metering", "log-average"), "hist": (),
                          "hist+1": ("--exposure-compensation", "1")}.items():
        scene = _configured(_gradient_scene(), "--exposure", "auto", "--tone-mapper", "clamp", *options)
        props = scene.shading_lab
        assert props.exposure_mode == "AUTO"
        assert props.exposure_method == ("LOG_AVERAGE" if name == "log" else "HISTOGRAM")
        assert props.exposure == (1.0 if name == "hist+1" else 0.0)
        images[name] = scenes.render(scene, tmp_path / f"{name}.exr")[..., :3].astype(np.float64)
        (used, metered[name]), = engine.last_exposures.values()
    print(f"log-average meters {metered['log']:.7f} stops (closed form {want:.7f}), "
          f"the histogram {metered['hist']:.5f}")
    assert abs(metered["log"] - want) < 5e-7, (metered["log"], want)  # measured 1e-7
    assert abs(metered["hist"] - want) > 0.05, "the histogram meters a different exposure here"
    unclamped = images["hist+1"] < 0.99
    ratio = images["hist+1"][unclamped] / images["hist"][unclamped]
    print(f"compensation +1: display ratio off 2 by {np.abs(ratio - 2.0).max():.1e}")
    assert unclamped.mean() > 0.5 and float(np.abs(ratio - 2.0).max()) < 1e-6, ratio  # measured 0


def test_light_threshold_option_windows_each_light(tmp_path):
    """--light-threshold t: in a scene of more than two lights (two under the plane, lighting none
    of it) a point light of intensity I fades by (1 - (d^2 t' / I)^2)^2 at distance d and is off
    beyond sqrt(I / t'), t' the threshold scaled by the scene's brightness (3 I / 32 W/m^2: each
    light within half the 8 m plane's diagonal of its centre) over pi, the window written here
    from its definition."""
    from addon.plan import light_tiles

    size, scale, height, power, option = 32, 6.0, 1.0, 100.0, 4.0
    images = {}
    for t in (0.0, option):
        scene = _gradient_scene(size)
        for x in (-1.0, 1.0):
            scenes.light(scene, "POINT", energy=power, location=(x, 0.0, -2.0))
        scene = _configured(scene, "--light-threshold", str(t))
        assert scene.shading_lab.light_threshold == pytest.approx(t)
        images[t] = scenes.render(scene, tmp_path / f"t{t}.exr")[..., 0].astype(np.float64)
    centres = ((np.arange(size) + 0.5) / size - 0.5) * scale
    x, y = np.meshgrid(centres, centres[::-1])
    d2 = x * x + y * y + height * height
    intensity = power / (4.0 * math.pi)
    effective = option * min(1.0, 3.0 * intensity / 32.0 / math.pi)
    reach2 = intensity * light_tiles.WINDOW_PEAK_LOSS / effective  # where I / r^2 = t' / 1.0887
    window = np.clip(1.0 - (d2 / reach2) ** 2, 0.0, 1.0) ** 2
    lit = images[0.0] > 1e-4
    err = float(np.abs(images[option][lit] - window[lit] * images[0.0][lit]).max() / images[0.0].max())
    print(f"threshold {option} W/m^2 (scaled to {effective:.4f}) against the window: {err:.1e}; dark beyond "
          f"{math.sqrt(reach2):.2f} m: {(window == 0).mean():.0%} of the frame")
    assert (window == 0).mean() > 0.1 and images[option][window == 0].max() == 0.0
    assert err < 5e-7, f"the thresholded image off the window by {err:.1e} (of the peak; measured 1.2e-7)"


def test_light_culling_option_shades_through_the_tiles_and_changes_no_pixel(tmp_path, monkeypatch):
    """--light-culling: lights of a short reach shaded through the tile lists, the image the same
    to the bit as --no-light-culling's."""
    from test_light_tiles import _lights_over_a_plane, _record_programs

    made = _record_programs(monkeypatch)
    images = {}
    for option in ("--light-culling", "--no-light-culling"):
        scene = _configured(_lights_over_a_plane(32, 12, cutoff=0.6), option)
        assert scene.shading_lab.light_culling == (option == "--light-culling")
        made.clear()
        images[option] = scenes.render(scene, tmp_path / f"{option}.exr")
        assert made and all(f.light_tiles == (option == "--light-culling") for f in made), made
    assert np.array_equal(images["--light-culling"], images["--no-light-culling"])


@pytest.mark.parametrize("family,value", [("ndf", "beckmann"), ("visibility", "vcavity"),
                                          ("diffuse", "oren-nayar"), ("multiscatter", None)])
def test_term_options_reach_the_scene_and_change_the_image(family, value, tmp_path):
    """The term options read back as set, and each changes a rough glossy plane's image."""
    def scene_():
        scene = scenes.reset(size=16)
        scenes.ortho_camera(scene, location=(0.0, -2.0, 2.0), rotation=(math.radians(45.0), 0.0, 0.0))
        scenes.plane(scene, size=8.0, material=scenes.material(base_color=(0.6, 0.5, 0.4), roughness=0.7,
                                                               metalness=0.5))
        scenes.light(scene, "POINT", energy=100.0, location=(0.5, 0.5, 1.0))
        return scene

    default = scenes.render(scene_(), tmp_path / "default.exr")
    option = [f"--{family}", value] if value else [f"--{family}"]
    scene = _configured(scene_(), *option)
    want = True if value is None else value.upper().replace("-", "_")
    assert getattr(scene.shading_lab, family) == want
    changed = float(np.abs(scenes.render(scene, tmp_path / "set.exr") - default).max())
    assert changed > 1e-3, f"{family}: the image changed by {changed:.1e}"
