"""The package's layers, as the README draws them: pure modules import neither ``bpy`` nor
``gpu``; the GPU side draws without reading Blender data (images arrive as pixels); only the
Blender layer and ``extract`` import ``bpy``. Checked on the source (imports at any depth,
including those inside functions), and pure modules by importing them in a Python without
Blender."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ADDON = Path(__file__).resolve().parent.parent / "addon"
PURE = ("snapshot", "programs", "brdf", "multiscatter", "ltc", "shading", "tonemap", "presets", "world_cache",
        "matrices")
GPU_SIDE = ("gpu_library", "gpu_scene", "passes", "renderer")


def _imports(module: str) -> set[str]:
    tree = ast.parse((ADDON / f"{module}.py").read_text())
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            names.add(("." * node.level) + (node.module or "").split(".")[0])
    return names


@pytest.mark.parametrize("module", PURE)
def test_pure_modules_import_neither_bpy_nor_gpu(module):
    assert not _imports(module) & {"bpy", "gpu", "mathutils"}, _imports(module)


@pytest.mark.parametrize("module", GPU_SIDE)
def test_the_gpu_side_reads_no_blender_data(module):
    imports = _imports(module)
    assert "bpy" not in imports and ".extract" not in imports, imports


def test_pure_modules_import_without_blender():
    code = ("import sys; sys.modules['bpy'] = sys.modules['gpu'] = None  # importing them fails\n"
            f"sys.path.insert(0, {str(ADDON.parent)!r})\n"
            + "".join(f"import addon.{m}\n" for m in PURE) + "print('ok')\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr[-2000:]
