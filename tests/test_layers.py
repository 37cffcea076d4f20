"""The package's layers (``addon/__init__.py``): ``scene``, ``reference``, ``materials``,
``plan``, ``frame``, ``blender``, each importing only the packages before it; ``bpy`` (and
``mathutils``) only in the Blender layer, ``gpu`` only in the frame and the Blender layer.
Checked on the source: every import at any depth (inside functions too), relative ones resolved
to the module they name (``from . import extract``, ``from ..plan import programs``, ``from
.snapshot import X``); and the pure packages by importing every module of theirs in a Python
without Blender."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ADDON = Path(__file__).resolve().parent.parent / "addon"
#: The packages, lowest first, and the outside modules each may import besides the standard
#: library and numpy.
LAYERS = {
    "scene": set(),
    "reference": set(),
    "materials": set(),
    "plan": set(),
    "frame": {"gpu", "gpu_extras"},
    "blender": {"bpy", "bpy_extras", "gpu", "gpu_extras", "mathutils", "addon_utils", "bmesh"},
}
PURE = ("scene", "reference", "materials", "plan")
BLENDER_MODULES = {"bpy", "bpy_extras", "gpu", "gpu_extras", "mathutils", "addon_utils", "bmesh", "bgl"}


def modules(package: str) -> list[Path]:
    return sorted((ADDON / package).glob("*.py"))


def resolve(path: Path, node: ast.ImportFrom) -> list[str]:
    """The modules an ``ImportFrom`` names, as dotted names under ``addon`` (``plan.programs``),
    or the top-level name of an absolute import."""
    if node.level == 0:
        return [(node.module or "").split(".")[0]]
    base = list(path.relative_to(ADDON).with_suffix("").parts[:-1])  # the module's package
    if node.level - 1 > len(base):
        raise AssertionError(f"{path}: import beyond the package ({ast.dump(node)})")
    base = base[:len(base) - (node.level - 1)]
    if node.module:
        target = [*base, *node.module.split(".")]
        dotted = ".".join(target)
        if ADDON.joinpath(*target).with_suffix(".py").is_file():
            return [dotted]
        if ADDON.joinpath(*target).is_dir():  # ``from ..blender import extract``: its modules
            return [f"{dotted}.{a.name}" if ADDON.joinpath(*target, f"{a.name}.py").is_file() else dotted
                    for a in node.names]
        raise AssertionError(f"{path}: {dotted} is not a module of the package")
    # ``from . import a, b``: each name is a module (or a package) of ``base``
    return [".".join([*base, alias.name]) for alias in node.names]


def imports(path: Path) -> set[str]:
    """Every import of a file: names under the package as ``package.module`` (with a leading
    ``addon:``), others by their top-level name."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            names |= {f"addon:{n}" if node.level else n for n in resolve(path, node)}
    return names


def layer_of(name: str) -> str:
    return name.removeprefix("addon:").split(".")[0]


ALL = [(package, path) for package in LAYERS for path in modules(package)]


def test_every_module_is_in_a_layer():
    loose = [p.name for p in ADDON.glob("*.py") if p.name != "__init__.py"]
    assert not loose, f"modules outside the packages: {loose}"
    assert {p.name for p in ADDON.iterdir() if p.is_dir() and p.name != "__pycache__"} == set(LAYERS)


@pytest.mark.parametrize("package,path", ALL, ids=[f"{k}/{p.name}" for k, p in ALL])
def test_a_module_imports_only_the_layers_before_its_own(package, path):
    allowed = set(list(LAYERS)[:list(LAYERS).index(package) + 1])
    found = imports(path)
    inner = {n for n in found if n.startswith("addon:")}
    wrong = sorted(n for n in inner if layer_of(n) not in allowed)
    assert not wrong, f"{package}/{path.name} imports {wrong}; {package} may import {sorted(allowed)}"
    outside = {n for n in found - inner if n in BLENDER_MODULES}
    assert outside <= LAYERS[package], f"{package}/{path.name} imports {sorted(outside - LAYERS[package])}"


#: The Blender layer's readers of a frame's data: the snapshot and what it reads materials, meshes,
#: lights, worlds, node trees and images with.
READERS = ("extract", "materials", "geometry", "lights", "world", "nodes", "images")


def test_only_extract_reads_blender_data_for_the_frame():
    """The GPU side and the planning never import the extraction or its readers, in any import
    style."""
    for package in ("scene", "reference", "plan", "frame"):
        for path in modules(package):
            found = imports(path)
            assert not [r for r in READERS if f"addon:blender.{r}" in found], path


def test_the_scanner_sees_every_form_of_relative_import(tmp_path, monkeypatch):
    """The forms the package uses, each resolved to its module (the old scanner read
    ``from . import extract`` as the module ".")."""
    fake = tmp_path / "addon"
    (fake / "frame").mkdir(parents=True)
    (fake / "blender").mkdir()
    (fake / "blender" / "extract.py").write_text("")
    (fake / "frame" / "passes.py").write_text("")
    probe = fake / "frame" / "probe.py"
    probe.write_text("from . import passes\nfrom ..blender import extract\n"
                     "def f():\n    from ..blender.extract import X\n    from .. import blender\n"
                     "import gpu.types\n")
    monkeypatch.setattr(sys.modules[__name__], "ADDON", fake)
    want = {"addon:frame.passes", "addon:blender.extract", "addon:blender", "gpu"}
    assert imports(probe) == want, imports(probe)


def test_pure_packages_import_without_blender():
    names = [f"addon.{package}.{path.stem}" for package in PURE for path in modules(package)]
    code = ("import sys; sys.modules['bpy'] = sys.modules['gpu'] = sys.modules['mathutils'] = None\n"
            f"sys.path.insert(0, {str(ADDON.parent)!r})\n"
            + "".join(f"import {n}\n" for n in names) + "print('ok')\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr[-2000:]
    assert len(names) >= 15, names
