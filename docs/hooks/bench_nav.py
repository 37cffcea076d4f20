"""MkDocs hook: every benchmark page in ``docs/bench/`` is in the navigation.

The benchmark scripts write their pages to ``docs/bench/<name>.md``. ``mkdocs.yml`` lists the
known ones under their titles; a page a script adds later joins the same section, titled by its
first heading (or its file name), instead of failing the strict build as a page left out.
"""

from __future__ import annotations

from pathlib import Path

FOLDER = "bench"


def _value(item):
    """A navigation item's target: a path, or the list of a section."""
    return next(iter(item.values())) if isinstance(item, dict) else item


def _entries(section: list) -> list[str]:
    """Every page path in a navigation list, sections included."""
    paths = []
    for item in section:
        value = _value(item)
        paths += _entries(value) if isinstance(value, list) else [value]
    return paths


def _bench_section(nav: list) -> list | None:
    """The first navigation list with a ``bench/`` page among its own items."""
    for item in nav:
        if isinstance(_value(item), list):
            found = _bench_section(_value(item))
            if found is not None:
                return found
    if any(isinstance(_value(i), str) and _value(i).startswith(f"{FOLDER}/") for i in nav):
        return nav
    return None


def _title(path: Path) -> str:
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("# "):
            return line[2:].strip()
    return path.stem.replace("_", " ").capitalize()


def on_config(config):
    nav = config.nav
    if not nav:
        return config
    section = _bench_section(nav)
    if section is None:
        section = []
        nav.append({"Benchmark pages": section})
    listed = set(_entries(nav))
    for path in sorted(Path(config.docs_dir, FOLDER).glob("*.md")):
        uri = f"{FOLDER}/{path.name}"
        if uri not in listed:
            section.append({_title(path): uri})
    return config
