"""Build the installable Shading Lab extension zip with Blender's own extension tooling.

    .venv/bin/python scripts/build_extension.py [--out DIR]

Blender wants ``__init__.py`` beside ``blender_manifest.toml``, so the package is staged in a
temporary folder: the manifest, the contents of ``addon/`` at the top level, and the ``glsl/``
and ``presets/`` folders (no ``__pycache__``). The stage is built and the zip validated by the
``bl_pkg`` command line shipped with Blender (``blender_ext.py build`` / ``validate``, run under
this Python), the same code as ``blender --command extension build``. Prints the zip's path;
on failure prints one line to stderr and exits with status 1. Default output directory: ``dist/``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import shutil
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MANIFEST = "blender_manifest.toml"
PACKAGE = "addon"
DATA_DIRS = ("glsl", "presets")
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "*.pyo")
CLI = Path("scripts", "addons_core", "bl_pkg", "cli", "blender_ext.py")
TAGS = Path("scripts", "modules", "_bpy_internal", "extensions", "tags.py")


class BuildError(Exception):
    pass


def _bpy_dirs():
    """Candidate ``bpy`` package folders: this interpreter's, then the repository's .venv."""
    spec = importlib.util.find_spec("bpy")  # locates the wheel without importing Blender
    if spec is not None and spec.origin:
        yield Path(spec.origin).parent
    yield from sorted(ROOT.glob(".venv/lib/python*/site-packages/bpy"))


def blender_tools() -> tuple[Path, Path]:
    """(``blender_ext.py``, ``tags.py``) from the bpy wheel (``bpy/<version>/scripts/...``)."""
    for bpy_dir in _bpy_dirs():
        for version_dir in sorted(bpy_dir.glob("[0-9]*.[0-9]*"), reverse=True):
            cli, tags = version_dir / CLI, version_dir / TAGS
            if cli.is_file() and tags.is_file():
                return cli, tags
    raise BuildError("Blender's extension tool (bpy/<version>/scripts/addons_core/bl_pkg/cli/"
                     "blender_ext.py) was not found: install bpy==5.0.1 (./run test creates .venv)")


def stage(root: Path, dest: Path) -> dict:
    """Lay the package out as Blender installs it; returns the parsed manifest."""
    manifest_path = root / MANIFEST
    package = root / PACKAGE
    if not manifest_path.is_file():
        raise BuildError(f"no {MANIFEST} in {root}")
    if not (package / "__init__.py").is_file():
        raise BuildError(f"no {PACKAGE}/__init__.py in {root}")
    try:
        manifest = tomllib.loads(manifest_path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise BuildError(f"{manifest_path} is not valid TOML: {exc}") from None
    for name in (MANIFEST, *DATA_DIRS):
        if (package / name).exists():
            raise BuildError(f"{PACKAGE}/{name} would collide with the top-level {name} in the package")

    dest.mkdir(parents=True)
    shutil.copy2(manifest_path, dest / MANIFEST)
    shutil.copytree(package, dest, ignore=IGNORE, dirs_exist_ok=True)
    for name in DATA_DIRS:
        if not (root / name).is_dir():
            raise BuildError(f"no {name}/ folder in {root}")
        shutil.copytree(root / name, dest / name, ignore=IGNORE)
    return manifest


def _run_tool(cli: Path, *args: str) -> None:
    """Run ``blender_ext.py`` with JSON output; raise with its last message on failure."""
    proc = subprocess.run([sys.executable, str(cli), *args, "--output-type", "JSON"],
                          capture_output=True, text=True, stdin=subprocess.DEVNULL)
    messages = []
    for line in proc.stdout.splitlines():
        try:
            kind, text = json.loads(line)
        except (ValueError, TypeError):
            kind, text = "TEXT", line
        messages.append((kind, str(text)))
    fatal = [text for kind, text in messages if kind in ("FATAL_ERROR", "ERROR")]
    if proc.returncode != 0 or fatal:
        detail = (fatal or [text for _, text in messages] or proc.stderr.strip().splitlines()
                  or [f"exit status {proc.returncode}"])[-1]
        raise BuildError(f"blender_ext {args[0]} failed: {detail}")


def build(out_dir: Path, root: Path = ROOT) -> Path:
    cli, tags = blender_tools()
    out_dir = out_dir.resolve()
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BuildError(f"cannot create the output directory {out_dir}: {exc.strerror}") from None
    with tempfile.TemporaryDirectory(prefix="shading_lab_ext_") as tmp:
        source = Path(tmp) / "stage"
        manifest = stage(root, source)
        try:
            zip_path = out_dir / f"{manifest['id']}-{manifest['version']}.zip"
        except KeyError as exc:
            raise BuildError(f"{MANIFEST} has no {exc.args[0]!r}") from None
        _run_tool(cli, "build", "--source-dir", str(source), "--output-dir", str(out_dir),
                  "--valid-tags", str(tags))
    if not zip_path.is_file():
        raise BuildError(f"blender_ext build reported success but {zip_path} is missing")
    _run_tool(cli, "validate", str(zip_path), "--valid-tags", str(tags))
    return zip_path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "dist",
                        help="output directory for the zip (default: dist/ in the repository)")
    args = parser.parse_args(argv)
    try:
        zip_path = build(args.out)
    except BuildError as exc:
        print(f"build_extension: error: {exc}", file=sys.stderr)
        return 1
    print(zip_path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
