"""MkDocs hook: the command-line page's option tables, generated from ``scripts/render.py``.

``docs/command-line.md`` holds the marker ``<!-- render.py options -->``; this hook replaces it
with one table per argument group of the parser ``scripts/render.py`` builds (each option, its
value, its default and its help) and the full ``--help`` text, so the page cannot drift from the
command line. ``render.py``'s top-level imports are pure Python: no Blender is needed.
"""

from __future__ import annotations

import argparse
import ast
import html
import importlib.util
import os
import re
import sys
from pathlib import Path
from unittest import mock

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "render.py"
PROPERTIES = ROOT / "addon" / "blender" / "properties.py"
SETTINGS_CLASS = "ShadingLabSceneSettings"
PAGE = "command-line.md"
MARKER = "<!-- render.py options -->"
#: argparse's own groups by their headings here and their anchors; the script's groups keep their
#: titles, anchored by a slug of the title up to its parenthesis.
OWN_GROUPS = {"positional arguments": ("Positional argument", "scene"),
              "options": ("General options", "options")}


def load_render_module():
    """``scripts/render.py`` as a module (its own name, so a ``render`` elsewhere is not taken)."""
    for folder in (ROOT, ROOT / "scripts"):
        if str(folder) not in sys.path:
            sys.path.insert(0, str(folder))
    spec = importlib.util.spec_from_file_location("shading_lab_render_cli", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def render_parser() -> argparse.ArgumentParser:
    """The parser ``render.py`` parses its arguments with: ``build_parser()`` if it has one, else
    the one ``parse_args`` builds, caught as it parses ``--list``."""
    module = load_render_module()
    if hasattr(module, "build_parser"):
        return module.build_parser()
    built: list[argparse.ArgumentParser] = []
    original = argparse.ArgumentParser.parse_args

    def catch(self, args=None, namespace=None):
        built.append(self)
        return original(self, args, namespace)

    with mock.patch.object(argparse.ArgumentParser, "parse_args", catch):
        module.parse_args(["--list"])
    if not built:
        raise RuntimeError(f"{SCRIPT}: parse_args built no argparse parser")
    return built[0]


#: Options whose destination is not named like the scene setting they change (None: not one of
#: Shading Lab's settings); every other option's destination is a setting's identifier, or none.
SETTING_OF = {"exposure_compensation": "exposure", "exposure_metering": "exposure_method",
              "error_bound": "auto_error_bound", "principled": "term_set", "persistent_data": None}
#: Blender's own settings an option changes.
BLENDER_SETTING = {"persistent_data": "Persistent Data (Blender's)"}


def scene_settings() -> dict[str, str]:
    """Identifier -> UI name of every scene setting, read from the property group's source."""
    tree = ast.parse(PROPERTIES.read_text(encoding="utf-8"), str(PROPERTIES))
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name == SETTINGS_CLASS:
            return {field.target.id: kw.value.value  # ``model: EnumProperty(name="Model", ...)``
                    for field in node.body if isinstance(field, ast.AnnAssign)
                    and isinstance(field.annotation, ast.Call)
                    for kw in field.annotation.keywords if kw.arg == "name"}
    raise RuntimeError(f"{PROPERTIES}: no class {SETTINGS_CLASS}")


def _setting(action: argparse.Action, settings: dict[str, str]) -> str:
    if action.dest in BLENDER_SETTING:
        return _text(BLENDER_SETTING[action.dest])
    identifier = SETTING_OF.get(action.dest, action.dest)
    if action.dest in SETTING_OF and identifier is not None and identifier not in settings:
        raise RuntimeError(f"{PROPERTIES}: no scene setting {identifier!r} (for {action.option_strings})")
    name = settings.get(identifier) if identifier else None
    return f"<strong>{_text(name)}</strong>" if name else ""


def _text(value: str) -> str:
    """Plain text for a Markdown table cell: nothing in it is read as Markdown or splits the row."""
    escaped = html.escape(" ".join(value.split()), quote=False)
    for char in "|*_`[]\\":
        escaped = escaped.replace(char, f"&#{ord(char)};")
    return escaped


def _code(value: str) -> str:
    return f"<code>{_text(value)}</code>"


def _options(action: argparse.Action) -> str:
    if not action.option_strings:
        return _code(action.metavar or action.dest.upper())
    return "<br>".join(_code(option) for option in action.option_strings)


def _value(action: argparse.Action) -> str:
    if isinstance(action, argparse.BooleanOptionalAction):
        return "flag: on / off"
    if action.nargs == 0:
        return "flag"
    if action.choices is not None:
        return " · ".join(_code(str(choice)) for choice in action.choices)
    if action.metavar:
        return _code(action.metavar)
    kind = getattr(action.type, "__name__", None)
    return {"int": "integer", "float": "number"}.get(kind, "text")


def _default(action: argparse.Action, group_title: str) -> str:
    if action.default is None or action.default == argparse.SUPPRESS:
        # argparse's own groups hold the scene and the output; the script's groups change settings
        return "—" if group_title.lower() in OWN_GROUPS else "the scene's"
    if action.default is False:
        return "off"
    if action.default is True:
        return "on"
    return _code(str(action.default))


def _heading(title: str) -> tuple[str, str]:
    """(heading, anchor) of an argument group."""
    if title.lower() in OWN_GROUPS:
        return OWN_GROUPS[title.lower()]
    anchor = re.sub(r"[^a-z0-9]+", "-", title.split("(")[0].lower().replace("'", "")).strip("-")
    return title[:1].upper() + title[1:], anchor


def option_tables(parser: argparse.ArgumentParser) -> str:
    """One Markdown table per argument group, the groups in the parser's order."""
    settings = scene_settings()
    parts = []
    for group in parser._action_groups:
        actions = [a for a in group._group_actions if not isinstance(a, argparse._HelpAction)]
        if not actions:
            continue
        title, anchor = _heading(group.title)
        parts.append(f"### {_text(title)} {{#{anchor}}}\n")
        if group.description:
            parts.append(_text(group.description) + "\n")
        parts.append("| option | value | default | sets | what it does |\n|---|---|---|---|---|")
        for action in actions:
            parts.append(f"| {_options(action)} | {_value(action)} | {_default(action, group.title)} | "
                         f"{_setting(action, settings)} | {_text(action.help or '')} |")
        parts.append("")
    return "\n".join(parts)


def help_text(parser: argparse.ArgumentParser) -> str:
    """``render.py --help`` as a terminal 100 columns wide prints it."""
    with mock.patch.dict(os.environ, {"COLUMNS": "100"}):
        text = parser.format_help()
    lines = ["```text", *text.rstrip().splitlines(), "```"]
    body = "\n".join("    " + line if line else "" for line in lines)
    return f'??? example "`render.py --help`"\n\n{body}\n'


def on_page_markdown(markdown: str, page, config, files) -> str:
    if page.file.src_uri != PAGE:
        return markdown
    if MARKER not in markdown:
        raise RuntimeError(f"{PAGE}: the marker {MARKER} is missing")
    parser = render_parser()
    generated = (f"{option_tables(parser)}\n{help_text(parser)}\n"
                 f"*These tables and the help text are generated from `scripts/render.py`'s argument "
                 f"parser when the manual is built.*\n")
    return markdown.replace(MARKER, generated)
