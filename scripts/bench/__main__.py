"""``.venv/bin/python scripts/bench list | run NAME [options]`` (or ``-m scripts.bench`` from the
repository's root): see README.md beside this file."""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
if sys.path and Path(sys.path[0]).resolve() == HERE:
    del sys.path[0]  # run as a folder: its modules are the bench package's, not top-level names
sys.path[:0] = [str(ROOT), str(ROOT / "scripts"), str(ROOT / "tests")]

from bench.harness import main  # noqa: E402

code = main(sys.argv[1:])
sys.stdout.flush()
sys.exit(code)
