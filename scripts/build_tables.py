"""Regenerate the lookup tables the add-on ships (``addon/reference/tables.npz``).

    .venv/bin/python scripts/build_tables.py [--out addon/reference/tables.npz]

The directional-albedo and split-sum tables of every distribution and masking-shadowing pair,
the average albedo and the Principled set's S table, computed by ``addon/reference/multiscatter.py``'s
``compute_*`` functions, and the area lights' linearly-transformed-cosine fits ("ltc_GGX",
"ltc_BECKMANN") and horizon-clipping sphere table ("ltc_sphere") by ``addon/reference/ltc.py``'s (pure
numpy, deterministic; the LTC fits take about two minutes), saved compressed. The engine loads
them instead of computing them at its first render; tests/test_tables.py checks that the shipped
file equals what this computes (tests/test_ltc.py refits sample LTC cells). Run it after changing
a table's definition or size.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from addon.reference import ltc, multiscatter  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=multiscatter.SHIPPED)
    args = parser.parse_args()
    start = time.perf_counter()
    tables = multiscatter.compute_all()
    tables.update(ltc.compute_all())
    partial = args.out.with_name(f".{args.out.stem}.partial.npz")
    np.savez_compressed(partial, **tables)
    partial.replace(args.out)
    kib = args.out.stat().st_size / 1024
    print(f"wrote {len(tables)} tables ({kib:.0f} KiB) to {args.out} in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
