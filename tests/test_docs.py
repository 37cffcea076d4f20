"""The user manual (``docs/``, ``mkdocs.yml``): it builds with ``mkdocs build --strict`` (and a
broken link, a missing image or a missing anchor fails that build), every setting the add-on
registers is on a settings page with its default and its range, the command-line page lists every
option of ``scripts/render.py``'s parser, and the README stays a short door into the manual."""

from __future__ import annotations

import html
import importlib.util
import math
import os
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import bpy
import pytest

from addon.blender import properties

ROOT = Path(__file__).resolve().parent.parent
SETTINGS_PAGES = ("settings/render", "settings/material", "settings/world")
README_LINES = 150


def build(root: Path, site: Path) -> subprocess.CompletedProcess:
    """``mkdocs build --strict`` of the manual whose ``mkdocs.yml`` is in ``root``, into ``site``."""
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)],
                          cwd=root, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})


@pytest.fixture(scope="module")
def manual(tmp_path_factory):
    """The manual built once for this file's tests: (the build's process, the site folder)."""
    site = tmp_path_factory.mktemp("site")
    return build(ROOT, site), site


def built_page(manual, page: str) -> str:
    proc, site = manual
    assert proc.returncode == 0, f"mkdocs build --strict failed:\n{proc.stderr}"
    return (site / page / "index.html").read_text(encoding="utf-8")


def test_the_manual_builds_strict(manual):
    proc, site = manual
    assert proc.returncode == 0, f"mkdocs build --strict failed:\n{proc.stderr}"
    assert (site / "index.html").is_file()
    for page in (ROOT / "docs" / "bench").glob("*.md"):  # every benchmark page is a page of the site
        assert (site / "bench" / page.stem / "index.html").is_file(), page.name


@pytest.mark.parametrize("broken, named", [
    ("[a page that is not there](no-such-page.md)", "no-such-page.md"),
    ("![an image that is not there](images/no-such-image.png)", "no-such-image.png"),
    ("[a setting that is not there](settings/render.md#no-such-setting)", "no-such-setting"),
])
def test_a_broken_link_fails_the_build(tmp_path, broken, named):
    """The strict build is worth its name: a copy of the manual with one broken reference fails."""
    copy = tmp_path / "repo"
    copy.mkdir()
    shutil.copy2(ROOT / "mkdocs.yml", copy / "mkdocs.yml")
    shutil.copytree(ROOT / "docs", copy / "docs", ignore=shutil.ignore_patterns("__pycache__"))
    for folder in ("addon", "scripts"):  # the command-line hook reads the parser and the settings
        (copy / folder).symlink_to(ROOT / folder, target_is_directory=True)
    page = copy / "docs" / "limits.md"
    page.write_text(page.read_text(encoding="utf-8") + f"\n{broken}\n", encoding="utf-8")
    proc = build(copy, tmp_path / "site")
    assert proc.returncode != 0, f"the build passed with {broken}:\n{proc.stderr}"
    assert named in proc.stderr, proc.stderr


class _Tables(HTMLParser):
    """The rows of a page's tables, each a list of cells: (text, the texts in ``<strong>``)."""

    def __init__(self):
        super().__init__()
        self.rows: list[list[tuple[str, list[str]]]] = []
        self._cell: list[str] | None = None
        self._strong: list[str] | None = None
        self._strongs: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag == "tr":
            self.rows.append([])
        elif tag in ("td", "th"):
            self._cell, self._strongs = [], []
        elif tag == "strong" and self._cell is not None:
            self._strong = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            text = " ".join("".join(self._cell).split())
            self.rows[-1].append((text, self._strongs))
            self._cell = None
        elif tag == "strong" and self._strong is not None:
            self._strongs.append(" ".join("".join(self._strong).split()))
            self._strong = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)
        if self._strong is not None:
            self._strong.append(data)


def settings_rows(manual) -> list[list[tuple[str, list[str]]]]:
    rows = []
    for page in SETTINGS_PAGES:
        parser = _Tables()
        parser.feed(built_page(manual, page))
        rows += [row for row in parser.rows if len(row) >= 4]
    return rows


def registered_settings():
    """(group, RNA property) of every setting ``properties.py`` registers on scenes, materials
    and worlds (not the ``name`` every property group has)."""
    inherited = {p.identifier for p in bpy.types.PropertyGroup.bl_rna.properties}
    return [(group.__name__, prop) for group in properties.classes
            for prop in group.bl_rna.properties if prop.identifier not in inherited]


def _number(x: float) -> str:
    return f"{x:.6g}"


def documented_default(prop) -> str | None:
    """The default as a settings page writes it (None: nothing to check, e.g. an image)."""
    if prop.type == "ENUM":
        return prop.enum_items[prop.default].name
    if prop.type == "BOOLEAN":
        return "on" if prop.default else "off"
    if prop.type in ("INT", "FLOAT"):
        if prop.is_array:
            return "(" + ", ".join(_number(v) for v in prop.default_array) + ")"
        return _number(prop.default)
    return None


def documented_limits(prop) -> list[str]:
    """The hard limits a settings page's range must name: finite ones, not tiny floors that only
    keep a value above 0 (those read "> 0")."""
    if prop.type not in ("INT", "FLOAT"):
        return []
    return [_number(x) for x in (prop.hard_min, prop.hard_max)
            if math.isfinite(x) and abs(x) < 1e6 and (x == 0 or abs(x) >= 0.01)]


def _plain(text: str) -> str:
    return text.replace("\u2212", "-")  # the pages write minus signs


def test_every_setting_is_documented_with_its_default_and_range(manual):
    rows = settings_rows(manual)
    problems = []
    for group, prop in registered_settings():
        where = f"{group}.{prop.identifier} ({prop.name!r})"
        mine = [row for row in rows if prop.name in row[0][1]]
        if not mine:
            problems.append(f"{where}: no settings-page row names it in bold")
            continue
        default = documented_default(prop)
        if default is not None and not any(default in _plain(row[2][0]) for row in mine):
            problems.append(f"{where}: default {default!r} not in {[row[2][0] for row in mine]}")
        if prop.type == "ENUM":
            labels = [item.name for item in prop.enum_items]
            if not any(all(label in row[3][0] for label in labels) for row in mine):
                problems.append(f"{where}: its range does not name every choice {labels}")
        for limit in documented_limits(prop):
            if not any(re.search(rf"(?<![\d.]){re.escape(limit)}(?![\d.])", _plain(row[3][0]))
                       for row in mine):
                problems.append(f"{where}: range {[row[3][0] for row in mine]} does not name {limit}")
    assert not problems, "\n".join(problems)


def test_the_readme_is_a_short_door_into_the_manual():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= README_LINES, f"README.md has {len(readme.splitlines())} lines"
    for page in (*SETTINGS_PAGES, "command-line", "getting-started"):  # a setting one click away
        assert f"(docs/{page}.md)" in readme, f"README.md does not link docs/{page}.md"
    for target in re.findall(r"\]\((docs/[^)#]+)", readme):
        assert (ROOT / target).exists(), f"README.md links {target}, which does not exist"


def render_parser():
    """``scripts/render.py``'s parser, as the manual's hook finds it."""
    path = ROOT / "docs" / "hooks" / "cli.py"
    spec = importlib.util.spec_from_file_location("shading_lab_docs_cli_hook", path)
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    return hook.render_parser()


def test_the_command_line_page_lists_every_option(manual):
    page = html.unescape(built_page(manual, "command-line"))
    parser = render_parser()
    options = [o for a in parser._actions for o in a.option_strings if o not in ("-h", "--help")]
    assert "--light-threshold" in options and "--no-shadows" in options
    missing = [o for o in options if f"<code>{o}</code>" not in page]
    assert not missing, f"the command-line page lacks {missing}"
    choices = {str(c) for a in parser._actions for c in (a.choices or ())}
    missing = sorted(c for c in choices if f"<code>{c}</code>" not in page)
    assert not missing, f"the command-line page lacks the choices {missing}"
    assert "usage: render.py" in page  # the --help text
    assert "<!-- render.py options -->" not in page
