"""Automatic exposure: metering against closed forms, the GPU reduction against numpy, adaptation
against the adaptation formula, in final renders, animations, the CLI and the viewport.

Expected values are computed here from the definitions: a frame of uniform luminance L gets
exposure key / L (Reinhard et al. 2002: a / L_w); a two-level frame's percentile-clipped
log-average is the weighted mean of the kept levels' log2 L; adaptation from E0 to a new target T
after t seconds is T + (E0 - T) exp(-t / tau).
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import bpy
import gpu
import numpy as np
import OpenEXR
import pytest
import scenes
from gpu_harness import run_on_gpu

from addon.blender import engine
from addon.frame.gpu_scene import SceneResources
from addon.frame.passes import ExposurePass, Frame, Target, full_screen_batch
from addon.scene import exposure

ROOT = Path(__file__).resolve().parent.parent
KEY = 0.18


# --- metering, closed forms ----------------------------------------------------------------------

@pytest.mark.parametrize("method", ["LOG_AVERAGE", "HISTOGRAM"])
@pytest.mark.parametrize("lum", [1e-3, 0.5, 7.0, 3e3])
def test_uniform_frame_gets_key_over_luminance(method, lum):
    frame = np.full((40, 60, 4), [lum, lum, lum, 1.0])
    stops = exposure.meter(*exposure.histogram(frame), exposure.AutoExposure(method=method))
    assert stops == pytest.approx(math.log2(KEY / lum), abs=1e-9)


def _two_level(fraction_dark: float, dark: float, bright: float, size: int = 100) -> np.ndarray:
    frame = np.full((size, size, 4), [bright, bright, bright, 1.0])
    frame[:round(fraction_dark * size)] = [dark, dark, dark, 1.0]  # whole rows: exact fractions
    return frame


@pytest.mark.parametrize(("p_dark", "low", "high"), [(0.3, 0.1, 0.9), (0.3, 0.4, 0.9), (0.7, 0.1, 0.5),
                                                      (0.5, 0.0, 1.0), (0.05, 0.1, 0.9)])
def test_two_level_frame_gets_the_percentile_clipped_log_average(p_dark, low, high):
    dark, bright = 0.01, 20.0
    frame = _two_level(p_dark, dark, bright)
    # the kept ranks [low, high] of a frame whose darkest p_dark are at `dark`
    kept_dark = max(min(high, p_dark) - low, 0.0)
    kept_bright = max(high - max(low, p_dark), 0.0)
    mean = (kept_dark * math.log2(dark) + kept_bright * math.log2(bright)) / (kept_dark + kept_bright)
    auto = exposure.AutoExposure(method="HISTOGRAM", low=low, high=high)
    stops = exposure.meter(*exposure.histogram(frame), auto)
    assert stops == pytest.approx(math.log2(KEY) - mean, abs=1e-9)


def test_log_average_is_reinhards():
    rng = np.random.default_rng(3)
    frame = np.concatenate([rng.lognormal(0.0, 3.0, (50, 70, 3)), np.ones((50, 70, 1))], axis=-1)
    lum = frame[..., :3] @ np.array(exposure.LUMA)
    lw = np.exp(np.mean(np.log(np.clip(lum, 2.0 ** -16, 2.0 ** 16))))  # Reinhard 2002, eq. 1
    stops = exposure.meter(*exposure.histogram(frame), exposure.AutoExposure(method="LOG_AVERAGE"))
    assert 2.0 ** stops == pytest.approx(KEY / lw, rel=1e-9)


def test_compensation_and_limits():
    frame = np.full((8, 8, 4), [1e-3, 1e-3, 1e-3, 1.0])
    hist = exposure.histogram(frame)
    free = math.log2(KEY / 1e-3)
    assert exposure.meter(*hist, exposure.AutoExposure(compensation=1.5)) == pytest.approx(free + 1.5)
    assert exposure.meter(*hist, exposure.AutoExposure(max_stops=4.0)) == 4.0
    assert exposure.meter(*hist, exposure.AutoExposure(min_stops=9.0)) == 9.0


def test_transparent_pixels_are_not_counted():
    frame = np.full((10, 10, 4), [2.0, 2.0, 2.0, 1.0])
    frame[:5] = 0.0  # a transparent film's empty background
    stops = exposure.meter(*exposure.histogram(frame), exposure.AutoExposure(method="LOG_AVERAGE"))
    assert stops == pytest.approx(math.log2(KEY / 2.0))
    assert exposure.meter(*exposure.histogram(np.zeros((4, 4, 4))), exposure.AutoExposure()) is None


# --- the GPU reduction ----------------------------------------------------------------------------

def _gpu_histogram(image: np.ndarray):
    """ExposurePass's histogram of ``image`` (h, w, 4), as a frame's radiance target."""
    h, w = image.shape[:2]

    def job(_depsgraph):
        target = Target(w, h, depth=False)
        buffer = gpu.types.Buffer("FLOAT", w * h * 4, np.ascontiguousarray(image, np.float32).ravel())
        target.texture_color = gpu.types.GPUTexture((w, h), format="RGBA32F", data=buffer)
        frame = Frame(None, SceneResources(), full_screen_batch())
        step = ExposurePass()
        try:
            return step.histogram(frame, target)
        finally:
            step.free()

    return run_on_gpu(job)


@pytest.mark.parametrize("size", [(64, 48), (1280, 720), (301, 517)])
def test_reduction_pass_equals_numpy(size):
    """The GPU's histogram equals the twin's, and its log-average equals numpy's log-average of
    the frame within 1e-4 (stops)."""
    w, h = size
    rng = np.random.default_rng(w)
    rgb = rng.lognormal(-1.0, 4.0, (h, w, 3))
    image = np.concatenate([rgb, np.ones((h, w, 1))], axis=-1).astype(np.float32)
    image[: h // 7, :, 3] = 0.0  # some transparent pixels
    sums, counts = _gpu_histogram(image)
    twin_sums, twin_counts = exposure.histogram(image)
    assert np.array_equal(counts, twin_counts), np.abs(counts - twin_counts).max()
    np.testing.assert_allclose(sums, twin_sums, rtol=1e-5, atol=1e-3 * max(w, h) / 256)
    lum = image[..., :3].astype(np.float64) @ np.array(exposure.LUMA)
    kept = image[..., 3] > 0
    numpy_mean = np.mean(np.log2(np.clip(lum[kept], 2.0 ** -16, 2.0 ** 16)))
    gpu_mean = sums.sum() / counts.sum()
    assert abs(gpu_mean - numpy_mean) < 1e-4, f"log-average differs by {abs(gpu_mean - numpy_mean):.2e} stops"


# --- final renders -----------------------------------------------------------------------------------

def _world_scene(lum: float, size: int = 32, method: str = "HISTOGRAM"):
    scene = scenes.reset(size=size)
    scenes.ortho_camera(scene)
    background = next(n for n in scenes.node_tree(scene.world).nodes if n.bl_idname == "ShaderNodeBackground")
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = lum
    props = scene.shading_lab
    props.exposure_mode = "AUTO"
    props.exposure_method = method
    return scene, background


def _combined_and_radiance(scene, tmp_path, name="frame"):
    bpy.ops.render.render()
    path = scenes.save_result(scene, tmp_path / f"{name}.exr", "MULTILAYER")
    layers = scenes.read_exr_layers(path)
    return layers["Combined"], layers[engine.RADIANCE_PASS], path


@pytest.mark.parametrize("method", ["LOG_AVERAGE", "HISTOGRAM"])
@pytest.mark.parametrize("lum", [2e-3, 1.0, 500.0])
def test_final_render_of_a_uniform_world_shows_the_key(method, lum, tmp_path):
    """Under Blender's view transform Combined holds radiance x 2^stops: a uniform frame's
    Combined is the key itself, the Radiance pass the raw radiance."""
    scene, _ = _world_scene(lum, method=method)
    combined, radiance, _ = _combined_and_radiance(scene, tmp_path)
    np.testing.assert_allclose(radiance[..., :3], lum, rtol=1e-6)
    err = np.abs(combined[..., :3] / KEY - 1.0).max()
    assert err < 1e-5, f"Combined / key - 1 = {err:.2e}"
    stops, metered = engine.last_exposures["main"]
    assert stops == metered == pytest.approx(math.log2(KEY / lum), abs=1e-5)


def _two_level_scene(dark: float = 0.01, bright: float = 0.8):
    """20 x 20 pixels looking straight down: the bottom 6 rows (30 %) a plane of albedo ``dark``,
    the rest one of albedo ``bright``, under a sun of pi W/m^2 overhead, F0 0: radiance = albedo."""
    scene = scenes.reset(size=20)
    scene.shading_lab.ambient = 0.0
    scenes.ortho_camera(scene, scale=2.0)
    for name, albedo, y0, y1 in (("dark", dark, -1.5, -0.4), ("bright", bright, -0.4, 1.5)):
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata([(-1.5, y0, 0), (1.5, y0, 0), (1.5, y1, 0), (-1.5, y1, 0)], [], [(0, 1, 2, 3)])
        mesh.materials.append(scenes.material(name, base_color=(albedo,) * 3, f0=0.0, metalness=0.0))
        scene.collection.objects.link(bpy.data.objects.new(name, mesh))
    scenes.light(scene, "SUN", energy=math.pi)
    props = scene.shading_lab
    props.exposure_mode, props.exposure_method = "AUTO", "HISTOGRAM"
    return scene


def _kept_mean(p_dark, low, high, dark, bright):
    """The mean log2 luminance of the ranks [low, high] of a frame whose darkest p_dark are at
    ``dark`` and the rest at ``bright`` (as in the two-level test above)."""
    kept_dark = max(min(high, p_dark) - low, 0.0)
    kept_bright = max(high - max(low, p_dark), 0.0)
    return (kept_dark * math.log2(dark) + kept_bright * math.log2(bright)) / (kept_dark + kept_bright)


@pytest.mark.parametrize("setting,value", [("exposure_key", 0.36), ("exposure_low", 40.0),
                                           ("exposure_high", 25.0), ("exposure_min", 3.0),
                                           ("exposure_max", -2.0)])
def test_each_automatic_exposure_setting_reaches_the_render(setting, value, tmp_path):
    """Key, Low, High, Minimum and Maximum set in the Render panel, each away from its default,
    change the final render's exposure as their closed forms say: log2(key) minus the mean log2
    luminance of the kept ranks (Low and High in percent), then limited to [Minimum, Maximum]."""
    scene = _two_level_scene()
    props = scene.shading_lab
    setattr(props, setting, value)
    assert getattr(props, setting) == pytest.approx(value)
    auto = dict(key=KEY, low=0.1, high=0.9, lo=-16.0, hi=16.0)
    auto.update({"exposure_key": {"key": value}, "exposure_low": {"low": value / 100.0},  # percentages
                 "exposure_high": {"high": value / 100.0}, "exposure_min": {"lo": value},
                 "exposure_max": {"hi": value}}[setting])
    free = math.log2(auto["key"]) - _kept_mean(0.3, auto["low"], auto["high"], 0.01, 0.8)
    want = min(max(free, auto["lo"]), auto["hi"])
    default = math.log2(KEY) - _kept_mean(0.3, 0.1, 0.9, 0.01, 0.8)
    combined, radiance, _ = _combined_and_radiance(scene, tmp_path)
    used, metered = engine.last_exposures["main"]
    print(f"{setting} = {value}: exposure {used:.6f} stops (closed form {want:.6f}, defaults' {default:.6f})")
    assert abs(used - want) < 1e-5 and abs(want - default) > 0.5, (used, want, default)
    err = float(np.abs(combined[..., :3] / (radiance[..., :3] * 2.0 ** used) - 1.0).max())
    assert err < 1e-5, f"Combined is not the radiance x 2^{used:.3f}: {err:.1e}"


def test_engine_tone_mapper_gets_the_exposure_and_the_header_says_it(tmp_path):
    scene, _ = _world_scene(40.0)
    scene.shading_lab.tone_mapper = "REINHARD"
    scene.shading_lab.exposure = 1.0  # compensation
    combined, radiance, path = _combined_and_radiance(scene, tmp_path)
    exposed = 40.0 * 2.0 ** (math.log2(KEY / 40.0) + 1.0)  # = 2 x key
    np.testing.assert_allclose(combined[..., :3], exposed / (1.0 + exposed), rtol=1e-5)
    with OpenEXR.File(str(path)) as exr:  # the header is the file's: read it while it is open
        said = {k: v for k, v in exr.header().items() if "Exposure" in k}
    assert said, "no exposure in the EXR header"
    (value,) = said.values()
    value = value.decode() if isinstance(value, bytes) else str(value)
    assert value == f"{math.log2(KEY / 40.0) + 1.0:+.3f} EV (auto)", value


def test_manual_exposure_leaves_combined_alone(tmp_path):
    scene, _ = _world_scene(40.0)
    scene.shading_lab.exposure_mode = "MANUAL"
    image = scenes.render(scene, tmp_path / "manual.exr")
    np.testing.assert_allclose(image[..., :3], 40.0, rtol=1e-6)


# --- animations: adaptation ------------------------------------------------------------------------

def _step_world(scene, background, lum: float, step_frame: int, factor: float) -> None:
    """The world's strength ``lum`` before ``step_frame``, ``factor`` x ``lum`` from it on."""
    strength = background.inputs["Strength"]
    strength.default_value = lum
    strength.keyframe_insert("default_value", frame=step_frame - 1)
    strength.default_value = lum * factor
    strength.keyframe_insert("default_value", frame=step_frame)
    for curve in _fcurves(scene.world):
        for point in curve.keyframe_points:
            point.interpolation = "CONSTANT"


def _fcurves(world):
    action = world.node_tree.animation_data.action
    if hasattr(action, "fcurves"):
        return action.fcurves
    return [c for layer in action.layers for strip in layer.strips  # Blender 5 layered actions
            for bag in strip.channelbags for c in bag.fcurves]


def _expected_sequence(lum: float, factor: float, frames: range, step_frame: int, fps: float,
                       auto: exposure.AutoExposure) -> list[float]:
    """Frame by frame, from the formula: converged at the first frame, then
    E_f = T_f + (E_{f-1} - T_f) exp(-dt / tau), tau by the direction of the change."""
    out = []
    for f in frames:
        target = math.log2(auto.key / (lum if f < step_frame else lum * factor))
        if not out:
            out.append(target)
            continue
        tau = auto.brighter if target < out[-1] else auto.darker
        out.append(target + (out[-1] - target) * math.exp(-(1.0 / fps) / tau))
    return out


@pytest.mark.parametrize(("factor", "tau_name"), [(100.0, "brighter"), (0.01, "darker")])
def test_a_step_in_brightness_adapts_with_its_time_constant(factor, tau_name, tmp_path):
    """A step from L to 100 L (or L / 100) in a frame sequence: each frame's exposure follows the
    adaptation formula with that direction's time constant, not faster, not slower; the same
    frames render the same images; a still afterwards uses the converged value."""
    lum, step_frame, frames = 0.5, 3, range(1, 13)
    scene, background = _world_scene(lum, size=16)
    scene.render.fps, scene.render.fps_base = 24, 1.0
    _step_world(scene, background, lum, step_frame, factor)
    props = scene.shading_lab
    props.adapt_brighter, props.adapt_darker = 0.1, 0.25
    auto = exposure.AutoExposure(brighter=0.1, darker=0.25)
    expected = _expected_sequence(lum, factor, frames, step_frame, 24.0, auto)

    def sequence():
        seen = []
        with exposure.TRACK.sequence():
            for f in frames:
                scene.frame_set(f)
                bpy.ops.render.render()
                seen.append(engine.last_exposures["main"][0])
        return seen

    first = sequence()
    measured = np.abs(np.array(first) - expected).max()
    assert measured < 1e-4, f"exposure off the formula by {measured:.2e} stops: {first} vs {expected}"
    after = math.log2(KEY / (lum * factor))
    assert abs(first[step_frame] - after) > 0.5, f"{tau_name}: must not jump to the target at once"
    assert sequence() == first, "the same frames must render the same exposures"
    scene.frame_set(step_frame + 1)
    bpy.ops.render.render()  # a still
    assert engine.last_exposures["main"][0] == pytest.approx(after, abs=1e-5)


def test_an_animation_render_job_adapts_from_its_first_frame(tmp_path):
    """Blender's own animation render (one job, many frames) adapts as the sequence does."""
    lum, step_frame = 0.5, 3
    scene, background = _world_scene(lum, size=16)
    scene.render.fps, scene.render.fps_base = 24, 1.0
    _step_world(scene, background, lum, step_frame, 100.0)
    scene.shading_lab.adapt_brighter = 0.1
    scene.frame_start, scene.frame_end = 1, 6
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = str(tmp_path / "anim_")
    bpy.ops.render.render(animation=True)
    auto = exposure.AutoExposure(brighter=0.1)
    expected = _expected_sequence(lum, 100.0, range(1, 7), step_frame, 24.0, auto)
    for f, stops in zip(range(1, 7), expected):
        image = scenes.read_exr(tmp_path / f"anim_{f:04d}.exr")
        radiance = lum if f < step_frame else lum * 100.0
        np.testing.assert_allclose(image[..., :3], radiance * 2.0 ** stops, rtol=1e-4,
                                   err_msg=f"frame {f}")


def test_cli_exposure_auto_reports_the_exposure(tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "scripts" / "render.py"), "world", "--model", "pbr",
                           "--resolution", "32x18", "--exposure", "auto", "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = [line for line in proc.stdout.splitlines() if "exposure" in line and "EV (auto)" in line]
    assert lines, proc.stdout[-2000:]


# --- the viewport ------------------------------------------------------------------------------------

def test_viewport_adapts_by_the_time_between_draws():
    """The viewport's first draw is converged; after the light gets 100 x brighter, each draw moves
    the exposure by the formula over the (here simulated) time since the previous draw, asks for
    another redraw while it has not settled, and settles."""
    from addon.blender.viewport import ADAPTED_STOPS, ViewportSession

    scene = scenes.lambert_scene(size=16)
    props = scene.shading_lab
    props.exposure_mode, props.exposure_method, props.adapt_brighter = "AUTO", "LOG_AVERAGE", 0.2
    bpy.context.view_layer.update()  # the camera's matrix_world
    cam = scene.camera
    view = np.linalg.inv(np.array(cam.matrix_world))
    proj = np.array(cam.calc_matrix_camera(bpy.context.evaluated_depsgraph_get(), x=16, y=16))
    session = ViewportSession()
    now = [0.0]
    session.clock = lambda: now[0]

    def draw(t):
        now[0] = t
        session.update(bpy.context.evaluated_depsgraph_get())
        run_on_gpu(lambda _d: session.draw(16, 16, view, proj, False))
        return session.renderer.exposures["main"], session.adapting

    try:
        (stops, metered), adapting = draw(0.0)
        start = math.log2(KEY / scenes.LAMBERT)
        assert stops == metered == pytest.approx(start, abs=2e-3) and not adapting
        next(o for o in scene.objects if o.type == "LIGHT").data.energy *= 100.0
        target = start - math.log2(100.0)
        expected, t = start, 0.0
        for dt in (0.05, 0.05, 0.1, 0.3):
            t += dt
            (stops, metered), adapting = draw(t)
            expected = target + (expected - target) * math.exp(-dt / 0.2)
            assert metered == pytest.approx(target, abs=2e-3)
            assert stops == pytest.approx(expected, abs=2e-3), (t, stops, expected)
            assert adapting == (abs(expected - target) > ADAPTED_STOPS)
        (stops, _), adapting = draw(t + 5.0)
        assert stops == pytest.approx(target, abs=2e-3) and not adapting
    finally:
        session.free()


def test_previews_use_manual_exposure():
    """A material preview shows the material's own brightness: no metering to middle grey."""
    from addon.blender import extract

    scene, _ = _world_scene(40.0)
    bpy.ops.render.render()  # remembers the artist's settings, which previews follow
    assert extract.scene_settings(scene).auto_exposure is not None
    settings = extract.preview_settings(scene)
    assert settings.auto_exposure is None and settings.model == scene.shading_lab.model
