"""Fresh processes: one per measured case where a first use is what is measured (nothing cached
in memory: compiled programs, tables, the world's maps), and one per benchmark for ``run --all``."""

from __future__ import annotations

import importlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

MAIN = Path(__file__).resolve().parents[1]  # scripts/bench: ``python scripts/bench ...``
RESULT = "RESULT "


def run_case(benchmark: str, function: str, *args, env: dict | None = None, timeout: float = 900) -> dict:
    """``bench.<benchmark>.<function>(*args)`` in a fresh Python process; its returned dict (JSON).
    ``env``: variables to set, or to remove where the value is None."""
    environ = dict(os.environ)
    for key, value in (env or {}).items():
        if value is None:
            environ.pop(key, None)
        else:
            environ[key] = str(value)
    proc = subprocess.run([sys.executable, str(MAIN), "_case", benchmark, function, json.dumps(args)],
                          capture_output=True, text=True, env=environ, timeout=timeout, check=False,
                          stdin=subprocess.DEVNULL)
    for line in proc.stdout.splitlines():
        if line.startswith(RESULT):
            return json.loads(line[len(RESULT):])
    raise RuntimeError(f"{benchmark}.{function}{tuple(args)}: no result (exit {proc.returncode})\n"
                       f"{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")


def case_main(argv: list[str]) -> int:
    """The child's side of ``run_case``: ``_case BENCHMARK FUNCTION JSON-ARGS``."""
    benchmark, function, args = argv
    module = importlib.import_module(f"bench.{benchmark}")
    result = getattr(module, function)(*json.loads(args))
    print(RESULT + json.dumps(result), flush=True)
    return 0


def run_each(names: list[str], argv: list[str]) -> int:
    """``run NAME *argv`` for each name, one after another, each in a fresh process; prints each
    one's wall time and exit status."""
    done = []
    for name in names:
        print(f"=== {name}", file=sys.stderr, flush=True)
        start = time.perf_counter()
        code = subprocess.run([sys.executable, str(MAIN), "run", name, *argv], check=False,
                              stdin=subprocess.DEVNULL).returncode
        done.append((name, time.perf_counter() - start, code))
        print(f"=== {name}: {done[-1][1]:.1f} s, exit {code}", file=sys.stderr, flush=True)
    print("\n| benchmark | wall s | exit |\n|---|---:|---:|")
    for name, seconds, code in done:
        print(f"| {name} | {seconds:.1f} | {code} |")
    return 1 if any(code for *_, code in done) else 0
