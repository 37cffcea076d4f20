"""A benchmark's page: the header every page starts with (the command, the commit, the machine,
the date), Markdown tables, and writing the file whole (a reader never sees half a page)."""

from __future__ import annotations

import math
import os
import platform
import subprocess
import sys
import time
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]


def git_state() -> str:
    """The short commit, with "dirty" when the tree has changes it does not hold."""
    def git(*args: str) -> str:
        done = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, check=True)
        return done.stdout.strip()

    try:
        return git("rev-parse", "--short", "HEAD") + (" (dirty)" if git("status", "--porcelain") else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def load_average() -> str:
    try:
        return Path("/proc/loadavg").read_text().split()[0]
    except (OSError, IndexError):
        return "?"


@cache
def gl_renderer() -> str:
    """The GL renderer and version Blender draws with (a 4 x 4 render of a test-only engine); ""
    where Blender is not loaded in this process (nothing is started for the header's sake)."""
    if "bpy" not in sys.modules:
        return ""
    import gpu_harness

    def job(_depsgraph):
        import gpu

        return f"{gpu.platform.renderer_get()} (OpenGL {gpu.platform.version_get()})"

    try:
        return gpu_harness.run_on_gpu(job)
    except Exception as exc:  # the header is no reason to lose a run's numbers
        return f"unknown ({exc})"


def blender_version() -> str:
    return sys.modules["bpy"].app.version_string if "bpy" in sys.modules else ""


def elapsed(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


def header(title: str, command: str, started: float, load_start: str, gl: str | None = None,
           timing: bool = True) -> list[str]:
    """The page's first lines: what produced it, where and when; ``gl`` when the renderer was
    queried elsewhere (in a child process)."""
    gl = gl if gl is not None else gl_renderer()
    blender = blender_version()
    machine = ", ".join(filter(None, [f"{cpu_model()}, {os.cpu_count()} logical CPUs",
                                      f"GL: {gl}" if gl else "",
                                      f"Blender {blender} (bpy)" if blender else "",
                                      f"Python {platform.python_version()}"]))
    lines = [f"# {title}", "",
             f"`{command}` — commit {git_state()}, {time.strftime('%Y-%m-%d %H:%M')}, "
             f"{elapsed(time.perf_counter() - started)}.", "",
             f"**Machine:** {machine}. Load average (1 min) {load_start} at start, {load_average()} at "
             "end.", ""]
    if timing:
        lines += ["**Times are CPU-rasteriser times (Mesa llvmpipe, no GPU): compare ratios within one run, "
                  "not absolute times.**", ""]
    return lines


def table(header: list[str], rows: list[list[str]], align: str | None = None) -> list[str]:
    """A Markdown table; ``align`` one letter a column (l, r or c), default the first left, the
    rest right."""
    align = align or "l" + "r" * (len(header) - 1)
    return ["| " + " | ".join(header) + " |",
            "|" + "|".join({"l": "---", "r": "---:", "c": ":---:"}[a] for a in align) + "|",
            *("| " + " | ".join(str(cell) for cell in r) + " |" for r in rows)]


def write(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a partial file moved into place."""
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.partial")
    partial.write_text(text, encoding="utf-8")
    partial.replace(path)


def geomean(values) -> float:
    values = list(values)
    return math.exp(sum(math.log(v) for v in values) / len(values))


def res(size) -> str:
    return f"{size[0]}×{size[1]}"
