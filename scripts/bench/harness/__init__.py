"""The benchmark harness: what every benchmark in ``scripts/bench/`` shares, written once.

- ``timing``: renders round-robin in one process (warm-up, rotated rounds, medians), timed renders;
- ``process``: a fresh process per case where a first use is measured, and ``run --all``;
- ``engines``: the peers (EEVEE, Workbench) and the Cycles reference, set up one way;
- ``scenes``: the scenes benchmarks start from (empty, demo, presets), lights, cameras;
- ``page``: the page header (command, commit, machine, date), Markdown tables, writing a page;
- ``plots``: matplotlib figures, written whole.

This module is the command line (``scripts/bench/__main__.py``) and the ``Run`` a benchmark's
``run(ctx)`` gets: its parsed options, its progress line, and where its page goes.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import shlex
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

import render as cli

from . import engines, page, process, timing

ROOT = page.ROOT
DOCS = ROOT / "docs" / "bench"
USAGE = """usage: .venv/bin/python scripts/bench list
       .venv/bin/python scripts/bench run NAME [--quick] [--out DIR] [options]   (run NAME --help)
       .venv/bin/python scripts/bench run --all --quick [--out DIR]    each in a fresh process"""


# --- the benchmarks ---------------------------------------------------------------------------


def names() -> list[str]:
    """Every benchmark: each module of the ``bench`` package but the harness."""
    import bench

    return sorted(m.name for m in pkgutil.iter_modules(bench.__path__)
                  if m.name != "harness" and not m.name.startswith("_"))


def load(name: str) -> ModuleType:
    if name not in names():
        raise cli.CliError(f"no benchmark {name!r}; there are: {', '.join(names())}")
    return importlib.import_module(f"bench.{name}")


def summary(module: ModuleType, width: int = 72) -> str:
    """The first sentence of a benchmark's docstring, on one line of at most ``width``."""
    text = " ".join((module.__doc__ or "").split("\n\n")[0].split()).split(". ")[0].rstrip(".")
    return text if len(text) <= width else text[:width - 1].rsplit(" ", 1)[0] + " …"


def list_benchmarks() -> int:
    for name in names():
        module = load(name)
        print(f"{name:17s} {module.PAGE:21s} {summary(module)}")
    return 0


# --- options ----------------------------------------------------------------------------------


def size(text: str) -> tuple[int, int]:
    """WxH -> (W, H), for argparse."""
    try:
        return cli.parse_resolution(text)
    except cli.CliError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def count(text: str) -> int:
    """A whole number of at least 1, for argparse."""
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"a whole number of at least 1, got {text!r}")
    return int(text)


def choices(allowed) -> callable:
    """A comma-separated list of some of ``allowed`` (a sequence, or a function giving it), for
    argparse."""

    def parse(text: str) -> list[str]:
        known = list(allowed() if callable(allowed) else allowed)
        items = [item.strip() for item in text.split(",") if item.strip()]
        unknown = [item for item in items if item not in known]
        if unknown or not items:
            raise argparse.ArgumentTypeError(f"unknown {', '.join(unknown) or '(none given)'}; "
                                             f"choose from {', '.join(known)}")
        return items

    return parse


def shipped_presets() -> list[str]:
    from addon.scene import presets

    return presets.scene_preset_names()


def standard(parser, *, resolution: str | None = None, frames: int | None = None, presets: str | None = None,
             reference_samples: int | None = None, peers: str | None = None) -> None:
    """The options most benchmarks take, with their defaults: ``--resolution WxH``, ``--frames N``
    (timed rounds after the warm-up), ``--presets a,b`` ("all": every shipped preset),
    ``--reference-samples N`` (Cycles) and ``--peers a,b`` (of ``engines.PEERS``)."""
    if resolution is not None:
        parser.add_argument("--resolution", type=size, default=resolution, metavar="WxH",
                            help=f"render size (default {resolution})")
    if frames is not None:
        parser.add_argument("--frames", type=count, default=frames,
                            help=f"timed rounds after the warm-up round (default {frames})")
    if presets is not None:
        parser.add_argument("--presets", type=choices(shipped_presets),
                            default=",".join(shipped_presets()) if presets == "all" else presets,
                            help=f"comma-separated scene presets (default {presets})")
    if reference_samples is not None:
        parser.add_argument("--reference-samples", type=count, default=reference_samples,
                            help=f"Cycles samples per pixel of the reference (default {reference_samples})")
    if peers is not None:
        parser.add_argument("--peers", type=choices(engines.PEERS), default=peers,
                            help=f"the other engines timed beside ours, of {', '.join(engines.PEERS)} "
                                 f"(default {peers})")


# --- a run ------------------------------------------------------------------------------------


@dataclass
class Run:
    """One benchmark's run: what ``run(ctx)`` gets."""

    name: str
    module: ModuleType
    args: argparse.Namespace
    argv: list[str]
    started: float = field(default_factory=time.perf_counter)
    load_start: str = field(default_factory=page.load_average)
    progress: timing.Progress = field(default_factory=timing.Progress)

    @property
    def out(self) -> Path:
        return self.args.out

    @property
    def command(self) -> str:
        return ".venv/bin/python scripts/bench " + shlex.join(["run", self.name, *self.argv])

    def path(self, default: Path) -> Path:
        """Where an output kept outside ``docs/bench`` goes (an image of the manual, the add-on's
        cost table): ``default`` when the pages go to ``docs/bench``, else beside the pages (a
        quick run into a temporary folder changes nothing of the repository's)."""
        return default if self.out.resolve() == DOCS.resolve() else self.out / default.name

    def page(self, title: str, body: list[str], *, name: str | None = None, gl: str | None = None,
             timing: bool = True) -> Path:
        """Write the page ``name`` (default the benchmark's ``PAGE``): the header, then ``body``;
        printed too. ``timing`` False: no note on CPU-rasteriser times (a page of errors only)."""
        lines = page.header(title, self.command, self.started, self.load_start, gl=gl, timing=timing)
        text = "\n".join([*lines, *body]).rstrip("\n") + "\n"
        path = self.out / (name or self.module.PAGE)
        page.write(path, text)
        print(text)
        print(f"wrote {path}", file=sys.stderr)
        return path


def writable(folder: Path, file: Path) -> None:
    """Fail before any rendering, not after, where the page could not be written."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise cli.CliError(f"cannot write {folder}: {exc.strerror}") from None
    if not os.access(folder, os.W_OK) or file.is_dir() or (file.exists() and not os.access(file, os.W_OK)):
        raise cli.CliError(f"cannot write {file}")


def parser_for(name: str, module: ModuleType, argv: list[str]) -> argparse.ArgumentParser:
    doc = module.__doc__ or ""
    parser = argparse.ArgumentParser(prog=f"scripts/bench run {name}", description=doc.split("\n\n")[0],
                                     epilog=doc.partition("\n\n")[2],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=DOCS, help="folder of the page (default docs/bench)")
    quick = ", ".join(f"--{k.replace('_', '-')} {v}" for k, v in module.QUICK.items())
    parser.add_argument("--quick", action="store_true", help=f"a smoke run in seconds: {quick}")
    module.options(parser)
    if "--quick" in argv:
        parser.set_defaults(**module.QUICK)
    return parser


def run(name: str, argv: list[str]) -> int:
    """Parse ``argv`` with the benchmark's options, check where its page goes, load Blender with
    the add-on (unless the benchmark says ``BLENDER = False``), and run it."""
    try:
        module = load(name)
    except cli.CliError as exc:
        print(f"bench: error: {exc}", file=sys.stderr)
        return 2
    args = parser_for(name, module, argv).parse_args(argv)
    os.environ.update(getattr(module, "ENV", {}))
    try:
        writable(args.out, args.out / module.PAGE)
        if getattr(module, "BLENDER", True):
            cli.ensure_addon()
        return module.run(Run(name, module, args, argv)) or 0
    except (cli.CliError, ValueError) as exc:
        print(f"\nbench run {name}: error: {exc}", file=sys.stderr)
        return 2


def main(argv: list[str]) -> int:
    command, rest = (argv[0], argv[1:]) if argv else ("", [])
    if command == "list":
        return list_benchmarks()
    if command == "run" and rest and rest[0] == "--all":
        if "--quick" not in rest:
            print("bench: run --all takes hours without --quick; give --quick", file=sys.stderr)
            return 2
        return process.run_each(names(), rest[1:])
    if command == "run" and rest and not rest[0].startswith("-"):
        return run(rest[0], rest[1:])
    if command == "_case":
        return process.case_main(rest)
    print(USAGE, file=sys.stderr)
    return 0 if command in ("-h", "--help") else 2
