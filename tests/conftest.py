"""Fails the whole run, loudly, when Blender-as-a-module or a GPU context is unavailable: a
suite that skipped its renders would pass while proving nothing."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
# the world's maps are computed in every test (tests/test_world_cache.py turns the disk cache on
# in folders of its own): a cache filled by earlier runs would hide the computation under test
os.environ["SHADING_LAB_CACHE"] = "off"
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

try:
    import bpy  # noqa: F401
except ImportError as exc:  # pragma: no cover - the message is the point
    pytest.exit(f"Shading Lab's tests need Blender as a Python module (pip install bpy==5.0.1): {exc}",
                returncode=3)

import addon  # noqa: E402

addon.register()


@pytest.fixture(scope="session", autouse=True)
def gpu_available(tmp_path_factory):
    """One tiny render up front: no GPU context (no EGL/Mesa) means every render test is moot."""
    import numpy as np
    import scenes

    scene = scenes.reset(size=8)
    scenes.ortho_camera(scene)
    scenes.plane(scene)
    scenes.light(scene, "SUN", energy=1.0)
    path = tmp_path_factory.mktemp("gpu") / "probe.exr"
    try:
        pixels = scenes.render(scene, path)
    except Exception as exc:
        pytest.exit(f"Shading Lab could not render (no GPU context? install Mesa's EGL: "
                    f"libegl1 libgl1-mesa-dri): {exc}", returncode=3)
    if not np.isfinite(pixels).all() or pixels[..., :3].max() <= 0.0:
        pytest.exit("Shading Lab rendered an empty image: the GPU context is not drawing "
                    "(check Mesa's EGL/llvmpipe installation)", returncode=3)
