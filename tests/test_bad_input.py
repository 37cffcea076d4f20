"""Bad input as a user hits it: odd geometry, odd lights and cameras, sizes Blender refuses,
unwritable outputs, broken presets, missing files and a cancelled render.

Each case renders in-process through ``bpy.ops.render.render()`` or runs ``scripts/render.py`` in
a subprocess, and checks: a clear message (Blender's report, or the CLI's exit status 2 and one
line on stderr), no crash, no file left behind in the output directory, and that the next render
still matches a closed form.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import bpy
import numpy as np
import pytest
import scenes
from gpu_harness import run_on_gpu

from addon.blender import engine, extract
from addon.frame import renderer

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = ROOT / "scripts" / "render.py"

#: The "next render": a Lambert plane (rho 0.5, no specular in any model) under a 2 W/m^2 sun
#: at 45 degrees seen by an orthographic camera: L = rho / pi * E * cos 45 at every pixel.
LAMBERT = scenes.LAMBERT



def _lambert_scene(size: int = 8):
    return scenes.lambert_scene(size)


def _next_render_works(tmp_path: Path) -> None:
    """A normal scene after the bad one: every pixel equals the closed form, in every model."""
    scene = _lambert_scene()
    for model in ("BLINN_PHONG", "PHONG", "PBR"):
        scene.shading_lab.model = model
        image = scenes.render(scene, tmp_path / f"next_{model}.exr")
        assert image.shape == (8, 8, 4)
        np.testing.assert_allclose(image[..., :3], LAMBERT, rtol=1e-4, err_msg=model)


@pytest.mark.parametrize("scale", [(-1, 1, 1), (1, 1, -1), (-1, -1, -1), (-2, 0.5, 1)])
def test_mirrored_objects_are_lit_like_their_originals(scale, tmp_path):
    """A negative scale (mirrored geometry: the triangles' winding reverses) changes nothing on a
    Lambert plane at the origin: every pixel is still rho / pi E cos 45, in every model."""
    scene = _lambert_scene()
    plane = next(o for o in scene.objects if o.type == "MESH")
    plane.scale = scale
    for model in ("BLINN_PHONG", "PHONG", "PBR"):
        scene.shading_lab.model = model
        image = scenes.render(scene, tmp_path / f"mirrored_{model}.exr")[..., :3]
        covered = image[2:-2, 2:-2]  # (-2, 0.5): the plane is 1 unit tall, 2 of the view's 4
        err = float(np.abs(covered - LAMBERT).max())
        assert err < 1e-4, f"{scale} {model}: mean {covered.mean():.5f}, want {LAMBERT:.5f}"


def _files(folder: Path) -> list[str]:
    """Everything inside ``folder`` (hidden partial files included), sorted; [] when absent."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*")) if folder.exists() else []


def _mesh(scene, verts, faces=(), edges=(), name="Mesh"):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(list(verts), list(edges), list(faces))
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    return obj


def _write_still(scene, path: Path) -> None:
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)


# --- geometry ------------------------------------------------------------------------------------

@pytest.mark.parametrize("slots", ["none", "empty_slot"])
def test_object_without_material(slots, tmp_path, capfd):
    """No material (or an empty slot) renders as the documented default surface: grey 0.8,
    shininess 30 in Blinn-Phong."""
    scene = scenes.reset(size=8)
    scene.shading_lab.model = "BLINN_PHONG"
    scene.shading_lab.ambient = 0.0
    scenes.ortho_camera(scene)
    obj = scenes.plane(scene, size=4.0)
    if slots == "empty_slot":
        obj.data.materials.append(None)
        assert len(obj.material_slots) == 1 and obj.material_slots[0].material is None
    scenes.light(scene, "SUN", energy=1.5, rotation=(math.radians(60.0), 0.0, 0.0))
    image = scenes.render(scene, tmp_path / "d.exr")
    E = 1.5
    want = 0.8 * E / math.pi * 0.5 + E / math.pi * math.cos(math.radians(30.0)) ** 30
    np.testing.assert_allclose(image[..., :3], want, rtol=1e-4)
    assert "Shading Lab:" not in capfd.readouterr().out  # no error printed
    _next_render_works(tmp_path)


def test_empty_mesh_is_skipped(tmp_path):
    """A mesh with no vertices at all: alone it draws nothing (the black world); beside a
    normal plane, the plane renders exactly."""
    alone = scenes.reset(size=8)
    scenes.ortho_camera(alone)
    _mesh(alone, [], name="Empty")
    scenes.light(alone, "SUN", energy=1.0)
    image = scenes.render(alone, tmp_path / "alone.exr")  # nothing to draw: the black world only
    np.testing.assert_array_equal(image[..., :3], 0.0)
    scene = _lambert_scene()
    _mesh(scene, [], name="Empty")
    image = scenes.render(scene, tmp_path / "with_plane.exr")
    np.testing.assert_allclose(image[..., :3], LAMBERT, rtol=1e-4)
    _next_render_works(tmp_path)


def test_degenerate_zero_area_triangles(tmp_path):
    """Collinear and coincident-vertex triangles (normals 0/0) in front of a plane: finite output,
    the plane's closed form everywhere (zero-area triangles cover no pixel)."""
    scene = _lambert_scene()
    verts = [(-1.0, -1.0, 0.5), (0.0, 0.0, 0.5), (1.0, 1.0, 0.5),  # collinear
             (0.3, 0.3, 0.6), (0.3, 0.3, 0.6), (0.3, 0.3, 0.6),  # one point
             (-0.5, 0.5, 0.7), (-0.5, 0.5, 0.7), (0.5, -0.5, 0.7)]  # two coincident corners
    _mesh(scene, verts, faces=[(0, 1, 2), (3, 4, 5), (6, 7, 8)], name="Degenerate")
    for model in ("BLINN_PHONG", "PHONG", "PBR"):
        scene.shading_lab.model = model
        image = scenes.render(scene, tmp_path / f"deg_{model}.exr")
        assert np.isfinite(image).all(), model
        np.testing.assert_allclose(image[..., :3], LAMBERT, rtol=1e-4, err_msg=model)
    _next_render_works(tmp_path)


def test_loose_vertices_and_edges_only(tmp_path):
    """A mesh of loose vertices and edges (no faces) draws nothing and does not fail."""
    scene = scenes.reset(size=8)
    scenes.ortho_camera(scene)
    scenes.light(scene, "SUN", energy=1.0)
    _mesh(scene, [(0, 0, 0), (0.5, 0, 0), (0, 0.5, 0), (0.2, 0.2, 0.2)], edges=[(0, 1)], name="Loose")
    image = scenes.render(scene, tmp_path / "loose.exr")
    np.testing.assert_array_equal(image[..., :3], 0.0)
    _next_render_works(tmp_path)


# --- lights and cameras --------------------------------------------------------------------------

def test_light_inside_a_surface(tmp_path):
    """A 1000 W point light lying in the plane (d = 0 at one point, n.l = 0 everywhere) plus a
    sun: finite everywhere, and the point light adds nothing (it grazes the surface)."""
    scene = _lambert_scene()
    scenes.light(scene, "POINT", energy=1000.0, location=(0.125, 0.125, 0.0))  # a pixel centre
    for model in ("BLINN_PHONG", "PHONG", "PBR"):
        scene.shading_lab.model = model
        image = scenes.render(scene, tmp_path / f"lop_{model}.exr")
        assert np.isfinite(image).all(), model
        np.testing.assert_allclose(image[..., :3], LAMBERT, rtol=1e-4, atol=1e-6, err_msg=model)
    _next_render_works(tmp_path)


def test_camera_inside_a_closed_cube(tmp_path):
    """A perspective camera and a point light at the centre of a 2 m cube: the camera sees the
    inside of the floor face (back faces, normal flipped towards the viewer); pixel ray
    (x, y, -1) meets it at distance d = |(x, y, 1)| with cos = 1 / d, so L = rho / pi * I / d^3."""
    n = 9
    scene = scenes.reset(size=n)
    scene.shading_lab.ambient = 0.0
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.lens, cam.data.sensor_width, cam.data.sensor_fit = 50.0, 36.0, "HORIZONTAL"
    cam.data.clip_start = 0.01
    scene.collection.objects.link(cam)
    scene.camera = cam
    s = 1.0
    cube = _mesh(scene, [(x, y, z) for x in (-s, s) for y in (-s, s) for z in (-s, s)],
                 faces=[(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)],
                 name="Cube")
    cube.data.materials.append(scenes.material(base_color=(0.5, 0.5, 0.5), f0=0.0, metalness=0.0,
                                               shininess=10.0, specular_color=(0.0, 0.0, 0.0)))
    power = 10.0
    scenes.light(scene, "POINT", energy=power, location=(0.0, 0.0, 0.0))
    centres = ((np.arange(n) + 0.5) / n - 0.5) * 36.0 / 50.0
    x, y = np.meshgrid(centres, -centres)  # top row first
    d = np.sqrt(x * x + y * y + 1.0)
    want = 0.5 / math.pi * power / (4.0 * math.pi) / d ** 3
    for model in ("BLINN_PHONG", "PHONG", "PBR"):
        scene.shading_lab.model = model
        image = scenes.render(scene, tmp_path / f"cube_{model}.exr")
        assert np.isfinite(image).all(), model
        np.testing.assert_allclose(image[..., 0], want, rtol=1e-3, err_msg=model)
    _next_render_works(tmp_path)


# --- sizes ---------------------------------------------------------------------------------------

def test_zero_resolution(tmp_path):
    """Blender clamps resolution_x = 0 to its minimum 4 and refuses a 0-pixel render itself
    ("Image too small") before the engine runs: a RuntimeError, no file. Where Blender rounds a
    tiny size down (399 x 7 at 25 %: 99 x 1), the engine's image has exactly Blender's size."""
    scene = _lambert_scene()
    r = scene.render
    r.resolution_x = 0
    assert r.resolution_x == 4  # RNA hard minimum
    r.resolution_x, r.resolution_y, r.resolution_percentage = 4, 4, 1  # 0.04 x 0.04 px
    assert extract.render_size(scene) == (1, 1)  # the engine's own floor, never reached here
    out = tmp_path / "out"
    out.mkdir()
    with pytest.raises(RuntimeError, match="(?i)too small"):
        _write_still(scene, out / "zero.exr")
    assert _files(out) == []
    r.resolution_x, r.resolution_y, r.resolution_percentage = 399, 7, 25
    image = scenes.render(scene, out / "tiny.exr")
    assert image.shape == (1, 99, 4)
    np.testing.assert_allclose(image[..., :3], LAMBERT, rtol=1e-4)
    _next_render_works(tmp_path)


# --- unwritable output ---------------------------------------------------------------------------

def test_render_filepath_under_a_regular_file(tmp_path):
    """write_still into a folder that cannot exist (its parent is a regular file): Blender's
    "cannot save" error, nothing written, the blocking file untouched."""
    scene = _lambert_scene()
    blocker = tmp_path / "blocker"
    blocker.write_text("not a directory")
    with pytest.raises(RuntimeError, match="(?i)cannot save"):
        _write_still(scene, blocker / "sub" / "out.exr")
    assert blocker.read_text() == "not a directory"
    assert _files(tmp_path) == ["blocker"]
    _next_render_works(tmp_path)


# --- cancelling ----------------------------------------------------------------------------------

def test_cancel_midway_stops_drawing_and_next_render_works(tmp_path, monkeypatch):
    """100 one-pixel planes; ``should_stop`` turns true at its second poll (after some objects
    are drawn): drawing stops there, the renderer is usable again at once, and the engine hands
    Blender's own ``test_break`` to the renderer as its ``should_stop``."""
    n, count = 16, 100
    scene = scenes.reset(size=n)
    scenes.ortho_camera(scene)  # 2 m across 16 px: pixel centres every 0.125 m
    scenes.light(scene, "SUN", energy=1.0)
    for k in range(count):
        row, col = divmod(k, 10)
        scenes.plane(scene, size=0.05, location=(-1.0 + (col + 0.5) * 0.125, 1.0 - (row + 0.5) * 0.125, 0.0))

    def job(depsgraph):
        snap = extract.snapshot(depsgraph, n, n)
        polls = []

        def should_stop():
            polls.append(1)
            return len(polls) >= 2

        r = renderer.Renderer()
        try:
            cancelled = r.render(snap, should_stop=should_stop)
            full = r.render(snap)
        finally:
            r.free()
        return len(polls), cancelled, full

    polls, cancelled, full = run_on_gpu(job)
    lit_cancelled = int((cancelled[..., 0] > 0.0).sum())
    lit_full = int((full[..., 0] > 0.0).sum())
    assert polls == 2, "the renderer must stop polling (and drawing) once should_stop is true"
    assert lit_full == count
    assert 0 < lit_cancelled < count, f"cancel was not honoured midway: {lit_cancelled} of {count} drawn"

    seen = []

    class Spy(renderer.Renderer):
        def run(self, *args, should_stop=None, **kwargs):
            seen.append(should_stop)
            return super().run(*args, should_stop=should_stop, **kwargs)

    monkeypatch.setattr(engine, "Renderer", Spy)
    image = scenes.render(scene, tmp_path / "wired.exr")
    assert int((image[..., 0] > 0.0).sum()) == count
    assert len(seen) == 1 and "SHADING_LAB.test_break" in repr(seen[0]), seen
    monkeypatch.undo()
    _next_render_works(tmp_path)


# --- the command line ----------------------------------------------------------------------------

HEADER = """\
[scene]
name = "Lambert"
description = "an orthographic camera over a Lambert plane under a sun at 45 degrees"
resolution = [8, 8]
model = "pbr"
ambient = 0.0
world_color = [0.0, 0.0, 0.0]

[camera]
type = "orthographic"
location = [0.0, 0.0, 5.0]
rotation = [0.0, 0.0, 0.0]
ortho_scale = 2.0
clip_start = 0.01

[[lights]]
kind = "sun"
strength = 2.0
rotation = [45.0, 0.0, 0.0]
"""
PLANE = """
[[objects]]
primitive = "plane"
size = 4.0
[objects.material]  # Lambert in every model: no Fresnel (f0 = 0), no Blinn-Phong highlight
base_color = [0.5, 0.5, 0.5]
metalness = 0.0
roughness = 0.5
f0 = 0.0
shininess = 10.0
specular_color = [0.0, 0.0, 0.0]
"""


def _run(*args, cwd=ROOT):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=300, stdin=subprocess.DEVNULL)


def _error_lines(stderr: str) -> list[str]:
    """stderr without the harmless EGL lines and blank lines."""
    return [line for line in stderr.splitlines() if line.strip() and "EGL" not in line]


def _assert_one_line_error(proc, *parts: str) -> str:
    lines = _error_lines(proc.stderr)
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-3000:])
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert len(lines) == 1, lines
    line = lines[0]
    assert line.startswith("render.py: error: "), line
    for part in parts:
        assert part in line, (part, line)
    return line


def _cli_next_render_works(tmp_path: Path, out: Path) -> None:
    """The CLI renders a good preset file into the same folder: the closed form, every model."""
    good = tmp_path / "good" / "lambert.toml"
    good.parent.mkdir(exist_ok=True)
    good.write_text(HEADER + PLANE)
    proc = _run(good, "--model", "all", "--out", out)
    assert proc.returncode == 0, proc.stderr[-3000:]
    for model in ("blinn-phong", "phong", "pbr"):
        image = scenes.read_exr(out / f"lambert_{model}.exr")
        assert image.shape == (8, 8, 4)
        np.testing.assert_allclose(image[..., :3], LAMBERT, rtol=1e-4, err_msg=model)
    assert not [f for f in _files(out) if "partial" in f]


BAD_PRESETS = {
    # id: (file text, substrings of the one error line besides the file name)
    "toml_syntax": (HEADER + PLANE + "size = [1, 2\n", ["TOML syntax error"]),
    "wrong_type": (HEADER.replace("strength = 2.0", 'strength = "bright"') + PLANE,
                   ["lights[0].strength", "expected a number", '"bright"']),
    "wrong_type_resolution": (HEADER.replace("[8, 8]", "[8.5, true]") + PLANE, ["scene.resolution"]),
    "unknown_key": (HEADER + PLANE.replace("size = 4.0", "size = 4.0\nsmoth = true"),
                    ["objects[0].smoth", "unknown key", 'did you mean "smooth"']),
    "unknown_top_level_key": (HEADER + PLANE + "[[light]]\nkind = \"sun\"\nstrength = 1\n",
                              ["light", "unknown key"]),
    "escape_dotdot": (HEADER + '[[objects]]\nfile = "../outside.blend"\nobject = "Cube"\n',
                      ["objects[0].file", '".." leaves the presets folder']),
    "escape_absolute": (HEADER + '[[objects]]\nfile = "/etc/outside.blend"\nobject = "Cube"\n',
                        ["objects[0].file", "absolute paths are refused"]),
    "escape_material_library": (HEADER.replace("ambient = 0.0", 'materials = "../materials.toml"')
                                + '[[objects]]\nprimitive = "plane"\nmaterial = { preset = "gold" }\n',
                                ["scene.materials", "inside the presets folder", '"../materials.toml"']),
}


@pytest.mark.parametrize("case", sorted(BAD_PRESETS))
def test_cli_broken_preset_file(case, tmp_path):
    """A broken preset .toml: exit 2, one line naming the file and the key, nothing written."""
    text, parts = BAD_PRESETS[case]
    folder = tmp_path / "presets"
    folder.mkdir()
    (tmp_path / "outside.blend").write_bytes(b"BLENDER")
    (tmp_path / "materials.toml").write_text('[gold]\nbase_color = [1.0, 0.78, 0.34]\n'
                                             'metalness = 1.0\nroughness = 0.3\n')
    path = folder / f"{case}.toml"
    path.write_text(text)
    out = tmp_path / "out"
    proc = _run(path, "--model", "pbr", "--out", out)
    _assert_one_line_error(proc, f"{case}.toml", *parts)
    assert _files(out) == []
    _cli_next_render_works(tmp_path, out)


def test_cli_unknown_preset_name(tmp_path):
    out = tmp_path / "out"
    proc = _run("fresnell", "--model", "pbr", "--out", out)
    _assert_one_line_error(proc, "presets", '"fresnell"', 'did you mean "fresnel"')
    assert _files(out) == []
    _cli_next_render_works(tmp_path, out)


def test_cli_preset_name_renders(tmp_path):
    """A shipped preset by name (the "SCENE may be a preset name" contract)."""
    out = tmp_path / "out"
    proc = _run("fresnel", "--model", "pbr", "--resolution", "16x8", "--out", out)
    assert proc.returncode == 0, proc.stderr[-3000:]
    image = scenes.read_exr(out / "fresnel_pbr.exr")
    assert image.shape == (8, 16, 4) and np.isfinite(image).all() and image[..., :3].max() > 0.0
    assert _files(out) == ["fresnel_pbr.exr", "fresnel_pbr.png"]


@pytest.mark.parametrize("suffix", [".blend", ".glb"])
def test_cli_preset_referring_to_a_corrupt_model_file(suffix, tmp_path):
    """A preset whose object file lies inside the folder with the right suffix but is not a
    Blender/glTF file: the CLI must refuse it like any other bad preset value (exit 2, one line
    naming the file and the key), not with a traceback."""
    folder = tmp_path / "presets"
    folder.mkdir()
    (folder / f"broken{suffix}").write_bytes(b"BLENDER-not-really" if suffix == ".blend" else b"glTFgarbage")
    path = folder / "corrupt.toml"
    obj = 'object = "Cube"\n' if suffix == ".blend" else ""
    path.write_text(HEADER + f'[[objects]]\nfile = "broken{suffix}"\n{obj}')
    out = tmp_path / "out"
    proc = _run(path, "--model", "pbr", "--out", out)
    _assert_one_line_error(proc, "corrupt.toml", "objects[0].file", f"broken{suffix}")
    assert _files(out) == []
    _cli_next_render_works(tmp_path, out)


@pytest.mark.parametrize("scene_arg,message", [("nope.blend", "no such .blend file"),
                                               ("nope.toml", "no such preset file")])
def test_cli_missing_scene_file(scene_arg, message, tmp_path):
    out = tmp_path / "out"
    proc = _run(tmp_path / scene_arg, "--model", "pbr", "--out", out)
    _assert_one_line_error(proc, message, scene_arg)
    assert _files(out) == []
    _cli_next_render_works(tmp_path, out)


@pytest.mark.parametrize("resolution", ["0x0", "8x0", "0x8", "-8x8"])
def test_cli_zero_resolution(resolution, tmp_path):
    good = tmp_path / "good" / "lambert.toml"
    good.parent.mkdir()
    good.write_text(HEADER + PLANE)
    out = tmp_path / "out"
    proc = _run(good, "--model", "pbr", f"--resolution={resolution}", "--out", out)
    _assert_one_line_error(proc, "--resolution", resolution)
    assert _files(out) == []
    _cli_next_render_works(tmp_path, out)


def test_cli_out_under_a_regular_file(tmp_path):
    good = tmp_path / "good" / "lambert.toml"
    good.parent.mkdir()
    good.write_text(HEADER + PLANE)
    blocker = tmp_path / "blocker"
    blocker.write_text("not a directory")
    proc = _run(good, "--model", "pbr", "--out", blocker / "sub")
    _assert_one_line_error(proc, "cannot create output directory", str(blocker / "sub"))
    assert blocker.read_text() == "not a directory"
    _cli_next_render_works(tmp_path, tmp_path / "out")


def test_cli_output_file_cannot_be_replaced(tmp_path):
    """The EXR's name is taken by a directory: exit 2, one line, no partial file left beside it."""
    good = tmp_path / "good" / "lambert.toml"
    good.parent.mkdir()
    good.write_text(HEADER + PLANE)
    out = tmp_path / "out"
    (out / "lambert_pbr.exr").mkdir(parents=True)
    proc = _run(good, "--model", "pbr", "--out", out)
    _assert_one_line_error(proc, "could not write", "lambert_pbr.exr")
    assert _files(out) == ["lambert_pbr.exr"], _files(out)  # only the blocking directory
    (out / "lambert_pbr.exr").rmdir()
    _cli_next_render_works(tmp_path, out)
