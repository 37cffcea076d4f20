"""The benchmark harness (scripts/bench/) as its users run it, cheaply: ``list`` names every
benchmark module; quick runs write their page, with the header (command, commit, machine, date)
and a table of numbers, into a folder of the test's own and nothing into docs/bench; a case in a
fresh process hands its result back; a wrong name or option is one clear error."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
BENCH = ROOT / "scripts" / "bench"
sys.path.insert(0, str(ROOT / "scripts"))


def _bench(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(BENCH), *args], capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL, cwd=ROOT)


def _docs_state() -> dict:
    return {p.name: p.stat().st_mtime_ns for p in (ROOT / "docs" / "bench").iterdir()}


def test_list_names_every_benchmark_module():
    modules = sorted(p.stem for p in BENCH.glob("*.py") if not p.stem.startswith("_"))
    proc = _bench("list")
    assert proc.returncode == 0, proc.stderr[-2000:]
    listed = {line.split()[0]: line.split()[1] for line in proc.stdout.splitlines()}
    assert sorted(listed) == modules, proc.stdout
    assert len(modules) >= 18, modules
    assert all(page.endswith(".md") for page in listed.values()), listed
    assert listed["models"] == "bench.md" and listed["light_shapes"] == "light_shapes.md", listed


@pytest.mark.parametrize("name, rows", [("light_culling", ("BLINN_PHONG", "PBR")),
                                        ("frame_time", ("BLINN_PHONG", "PHONG", "PBR"))])
def test_a_quick_run_writes_its_page(tmp_path, name, rows):
    before = _docs_state()
    proc = _bench("run", name, "--quick", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert _docs_state() == before, "a run into another folder changed docs/bench"
    text = (tmp_path / f"{name}.md").read_text()
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                          text=True, check=True).stdout.strip()
    assert text.startswith("# "), text[:200]
    assert f"scripts/bench run {name} --quick --out {tmp_path}" in text, text[:400]
    assert f"commit {head}" in text, text[:400]
    assert time.strftime("%Y-%m-%d") in text, text[:400]
    assert "**Machine:** " in text and f"{os.cpu_count()} logical CPUs" in text and "GL: " in text, text[:600]
    table = [line.split("|")[1:-1] for line in text.splitlines()
             if line.startswith("| ") and "ms" not in line]  # the rows, not the header
    found = [cells[0].strip() for cells in table]
    assert all(row in found for row in rows), text
    for cells in table:  # every figure a number: medians measured, not blanks
        assert float(cells[-1].strip().rstrip("x")) > 0.0, cells


def test_a_case_runs_in_a_fresh_process():
    from bench.harness import process

    result = process.run_case("first_render", "case", "long_tail", "CUSTOM", 32, 18,
                              env={"SHADING_LAB_CACHE": "off"}, timeout=120)
    assert result["first_ms"] > 0.0 and result["second_ms"] > 0.0, result
    assert result["gl"], result  # the child's GL renderer, for the page's header


def test_a_wrong_name_or_option_is_one_clear_error(tmp_path):
    unknown = _bench("run", "no_such_bench")
    assert unknown.returncode == 2 and "no benchmark 'no_such_bench'" in unknown.stderr, unknown.stderr
    bad = _bench("run", "light_culling", "--resolution", "wide", "--out", str(tmp_path / "bad"))
    assert bad.returncode == 2 and "--resolution" in bad.stderr, bad.stderr[-500:]
    assert not (tmp_path / "bad").exists()
    everything = _bench("run", "--all")
    assert everything.returncode == 2 and "--quick" in everything.stderr, everything.stderr
