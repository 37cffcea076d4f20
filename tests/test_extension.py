"""The shipped extension, not the source tree: scripts/build_extension.py builds the zip with
Blender's own tooling, Blender's validator accepts it, and a fresh Blender (a subprocess, since this
session already registered the source tree's ``SHADING_LAB`` engine and ``Scene.shading_lab``)
installs it into a temporary local repository, enables it as ``bl_ext.<repo>.shading_lab`` and
renders a Lambert plane that the test checks against the closed form, and a preset that reads every
shipped table, which must equal the source tree's render to the bit."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
import time
import tomllib
import zipfile
from pathlib import Path

import numpy as np
import pytest
import scenes

ROOT = Path(__file__).resolve().parent.parent
BUILD = ROOT / "scripts" / "build_extension.py"
MANIFEST = tomllib.loads((ROOT / "blender_manifest.toml").read_text(encoding="utf-8"))
REPO_NAME = "shading_lab_test_repo"

BASE = np.array([0.5, 0.35, 0.2])  # Diffuse BSDF colour: F0 = 0, a pure Lambert surface
SUN_STRENGTH = 3.0  # W/m^2
SUN_ANGLE = math.radians(30.0)  # from the plane's normal
SIZE = 16


def _build(out: Path, script: Path = BUILD) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(script), "--out", str(out)], capture_output=True,
                          text=True, timeout=120, stdin=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def built_zip(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("dist")
    proc = _build(out)
    assert proc.returncode == 0, proc.stderr[-2000:]
    zip_path = Path(proc.stdout.strip().splitlines()[-1])
    assert zip_path == out / f"{MANIFEST['id']}-{MANIFEST['version']}.zip"
    assert zip_path.is_file()
    return zip_path


def test_zip_holds_the_package_at_the_top_level(built_zip):
    names = set(zipfile.ZipFile(built_zip).namelist())
    expected = {"blender_manifest.toml"}
    # every file of the package, its sub-packages' modules and their data (tables.npz, term_costs.json)
    expected |= {p.relative_to(ROOT / "addon").as_posix() for p in (ROOT / "addon").rglob("*")
                 if p.is_file() and "__pycache__" not in p.parts}
    expected |= {f"glsl/{p.name}" for p in (ROOT / "glsl").iterdir() if p.is_file()}
    expected |= {f"presets/{p.name}" for p in (ROOT / "presets").iterdir() if p.is_file()}
    assert {"__init__.py", "reference/tables.npz", "plan/term_costs.json"} <= expected
    assert expected <= names, sorted(expected - names)
    assert not [n for n in names if "__pycache__" in n or n.endswith(".pyc")]
    assert not [n for n in names if n.split("/")[0] in ("addon", "tests", "scripts", ".venv", "dist")]


def test_blender_validates_the_zip(built_zip):
    sys.path.insert(0, str(BUILD.parent))
    try:
        import build_extension
    finally:
        sys.path.remove(str(BUILD.parent))
    cli, tags = build_extension.blender_tools()
    proc = subprocess.run([sys.executable, str(cli), "validate", str(built_zip), "--valid-tags", str(tags)],
                          capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "Success" in proc.stdout


def test_invalid_manifest_fails_with_one_line(tmp_path):
    """The script in a copy of the repository whose manifest Blender rejects."""
    fake = tmp_path / "repo"
    (fake / "scripts").mkdir(parents=True)
    (fake / "scripts" / BUILD.name).write_bytes(BUILD.read_bytes())
    (fake / "addon").mkdir()
    (fake / "addon" / "__init__.py").write_text("")
    (fake / "glsl").mkdir()
    (fake / "presets").mkdir()
    manifest = (ROOT / "blender_manifest.toml").read_text(encoding="utf-8")
    (fake / "blender_manifest.toml").write_text(manifest.replace('version = "', 'version = "not-semver-'))
    proc = _build(tmp_path / "out", script=fake / "scripts" / BUILD.name)
    assert proc.returncode == 1
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("build_extension: error:"), proc.stderr
    assert "version" in lines[0]
    assert not list((tmp_path / "out").glob("*.zip"))


# Runs in a fresh Python with bpy: nothing from the source tree is imported (only tests/scenes.py,
# which has no add-on code). Arguments: zip, repository directory, EXR path, source addon/ folder.
INSTALL_AND_RENDER = textwrap.dedent("""
    import importlib, json, math, sys
    from pathlib import Path

    import bpy

    zip_path, repo_dir, exr_path, source_addon, tests_dir = sys.argv[1:6]
    sys.path.insert(0, tests_dir)
    import scenes

    scene = scenes.reset(engine="CYCLES", size={size})  # factory settings: before the install
    prefs = bpy.context.preferences
    assert bpy.ops.preferences.extension_repo_add(
        name={repo_name!r}, type="LOCAL", use_custom_directory=True,
        custom_directory=repo_dir) == {{"FINISHED"}}
    repo = next(r for r in prefs.extensions.repos if Path(r.directory) == Path(repo_dir))
    result = bpy.ops.extensions.package_install_files(
        filepath=zip_path, repo=repo.module, enable_on_install=True)
    assert result == {{"FINISHED"}}, result
    module = "bl_ext." + repo.module + ".shading_lab"
    if module not in prefs.addons:  # enable_on_install should have done it
        bpy.ops.preferences.addon_enable(module=module)

    scene = bpy.context.scene
    scene.render.engine = "SHADING_LAB"
    scene.shading_lab.model = "PBR"
    scenes.ortho_camera(scene, location=(0.0, 0.0, 3.0), scale=2.0)
    mat = bpy.data.materials.new("Lambert")
    if mat.node_tree is None:
        mat.use_nodes = True
    tree = mat.node_tree
    tree.nodes.clear()
    bsdf = tree.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (*{base}, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    scenes.plane(scene, size=4.0, material=mat)
    scenes.light(scene, "SUN", energy={sun}, rotation=({angle}, 0.0, 0.0))
    pixels = scenes.render(scene, Path(exr_path))

    engine = next(c for c in bpy.types.RenderEngine.__subclasses__()
                  if getattr(c, "bl_idname", None) == "SHADING_LAB")
    programs = sys.modules[module + ".plan.programs"]

    # a preset that reads every shipped table: area lights (the LTC tables), the Principled set
    # (its S table, the albedo tables), Auto's cost table
    presets = sys.modules[module + ".scene.presets"]
    builder = importlib.import_module(module + ".blender.scene_builder")
    multiscatter = importlib.import_module(module + ".reference.multiscatter")
    auto_terms = importlib.import_module(module + ".plan.auto_terms")
    preset_scene = scene  # factory settings would disable the extension: the same scene, emptied
    for obj in list(preset_scene.objects):
        bpy.data.objects.remove(obj)
    builder.build_scene(presets.load_scene_preset("softbox"), preset_scene)
    {configure}
    scenes.render(preset_scene, Path(exr_path).with_name("preset.exr"))
    report = dict(
        module=module,
        addons=[a.module for a in prefs.addons],
        engine_module=engine.__module__,
        source_tree_imported="addon" in sys.modules or any(
            Path(getattr(m, "__file__", None) or "/").resolve().is_relative_to(Path(source_addon))
            for m in list(sys.modules.values())),
        package_files=sorted({{str(Path(m.__file__).resolve()) for name, m in list(sys.modules.items())
                              if name.startswith(module) and getattr(m, "__file__", None)}}),
        glsl_dir=str(programs.glsl_dir()),
        user_resources=bpy.utils.resource_path("USER"),
        centre=pixels[{size} // 2, {size} // 2].tolist(),
        tables=sorted(multiscatter._shipped()),
        tables_file=str(multiscatter.SHIPPED),
        cost_table=sorted(auto_terms.cost_table()),
    )
    bpy.ops.preferences.addon_disable(module=module)
    scene.render.engine = "CYCLES"
    try:
        scene.render.engine = "SHADING_LAB"
    except TypeError:
        pass
    report["disabled"] = (module not in prefs.addons and not hasattr(scene, "shading_lab")
                          and scene.render.engine == "CYCLES")
    print("RESULT " + json.dumps(report))
""").format(size=SIZE, repo_name=REPO_NAME, base=tuple(BASE.tolist()), sun=SUN_STRENGTH, angle=SUN_ANGLE,
           configure="preset_scene.shading_lab.term_set = 'PRINCIPLED'; "
                     "preset_scene.render.resolution_x, preset_scene.render.resolution_y = 64, 36")


def _preset_from_the_source_tree(path: Path):
    """The same preset, set up as the installed run sets it up, rendered by the source tree."""
    import bpy

    from addon.blender import scene_builder
    from addon.scene import presets

    scene = scenes.reset(size=SIZE)
    scene.shading_lab.model = "PBR"
    scenes.ortho_camera(scene, location=(0.0, 0.0, 3.0), scale=2.0)  # as the installed run's scene
    for obj in list(scene.objects):
        bpy.data.objects.remove(obj)
    scene_builder.build_scene(presets.load_scene_preset("softbox"), scene)
    scene.shading_lab.term_set = "PRINCIPLED"
    scene.render.resolution_x, scene.render.resolution_y = 64, 36
    return scenes.render(scene, path)


def _blender_user_files(home: Path) -> set[Path]:
    """Anything of Shading Lab's in a user's Blender configuration."""
    config = home / ".config" / "blender"
    return {p for p in config.rglob("*") if "shading_lab" in str(p)} if config.is_dir() else set()


def test_installed_extension_renders(built_zip, tmp_path):
    start = time.perf_counter()
    real_home = Path.home()
    before = _blender_user_files(real_home)

    sandbox = tmp_path / "sandbox"
    user_resources, home, repo_dir = sandbox / "blender_user", sandbox / "home", tmp_path / REPO_NAME
    for d in (user_resources, home, repo_dir):
        d.mkdir(parents=True)
    env = {k: v for k, v in os.environ.items() if not k.startswith("BLENDER_USER_")}
    env.update(HOME=str(home), XDG_CONFIG_HOME=str(home / ".config"), XDG_CACHE_HOME=str(home / ".cache"),
               XDG_DATA_HOME=str(home / ".local" / "share"), BLENDER_USER_RESOURCES=str(user_resources))
    script = tmp_path / "install_and_render.py"
    script.write_text(INSTALL_AND_RENDER)
    exr = tmp_path / "installed.exr"
    proc = subprocess.run([sys.executable, str(script), str(built_zip), str(repo_dir), str(exr),
                           str((ROOT / "addon").resolve()), str(ROOT / "tests")],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=180,
                          stdin=subprocess.DEVNULL)
    results = [line for line in proc.stdout.splitlines() if line.startswith("RESULT ")]
    assert proc.returncode == 0 and results, (proc.stdout + proc.stderr)[-3000:]
    report = json.loads(results[-1][len("RESULT "):])

    # The installed package, and only it, is the engine that rendered.
    module = report["module"]
    assert module == f"bl_ext.{REPO_NAME}.shading_lab", module  # the module takes the folder's name
    assert module in report["addons"]
    assert report["engine_module"].startswith(module + "."), report["engine_module"]
    assert not report["source_tree_imported"]
    installed = (repo_dir / "shading_lab").resolve()
    assert report["package_files"] and all(Path(f).is_relative_to(installed) for f in report["package_files"])
    assert Path(report["glsl_dir"]) == installed / "glsl"  # shaders shipped in the zip
    assert report["disabled"]  # unregisters the engine and its properties

    # Pure Lambert (Diffuse BSDF: F0 = 0) under a sun at 30 degrees: L = rho / pi * E * cos(theta).
    want = BASE / math.pi * SUN_STRENGTH * math.cos(SUN_ANGLE)
    pixels = scenes.read_exr(exr)
    assert pixels.shape == (SIZE, SIZE, 4)
    np.testing.assert_allclose(pixels[..., :3], np.broadcast_to(want, (SIZE, SIZE, 3)), rtol=1e-4)
    np.testing.assert_allclose(pixels[..., 3], 1.0)
    np.testing.assert_allclose(report["centre"][:3], want, rtol=1e-4)

    # The package's data came with it (a zip without them installs and computes or guesses), and
    # a preset that reads them renders to the source tree's bits.
    from addon.plan import auto_terms
    from addon.reference import multiscatter

    assert Path(report["tables_file"]) == installed / "reference" / "tables.npz"
    tables, costs = report["tables"], report["cost_table"]
    assert tables == sorted(multiscatter._shipped()) and len(tables) > 10, tables
    assert costs == sorted(auto_terms.cost_table()) and costs, costs
    installed_preset = scenes.read_exr(tmp_path / "preset.exr")
    source_preset = _preset_from_the_source_tree(tmp_path / "source_preset.exr")
    assert installed_preset.shape == (36, 64, 4) and source_preset[..., :3].max() > 0.05
    differ = float(np.abs(installed_preset - source_preset).max())
    assert differ == 0.0, f"the installed softbox differs from the source tree's by up to {differ:.3g}"

    # Nothing written to the real user configuration; the sandbox took Blender's user files.
    assert Path(report["user_resources"]).resolve() == user_resources.resolve()
    assert (user_resources / "extensions").is_dir()
    assert _blender_user_files(real_home) == before
    assert time.perf_counter() - start < 90.0
