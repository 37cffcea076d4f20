"""Tabulate Cycles' random walk subsurface reflectance (``addon/reference/subsurface_walk.npz``).

    .venv/bin/python scripts/subsurface_walk_table.py [--out addon/reference/subsurface_walk.npz]
                                                      [--paths 40000]

R / albedo of Cycles' Random Walk medium in a half-space, for each albedo, Anisotropy and entry cosine
node of ``addon/reference/subsurface.py`` (``compute_walk_table``: a Monte Carlo twin of Cycles'
subsurface_random_walk, pure numpy, seeded per cell: deterministic), which glsl/subsurface.glsl's
subsurface_walk_factor looks up. About half an hour on one core at 40,000 walks per node (their
noise: 0.2-0.5 % of R); tests/test_subsurface_walk.py recomputes sample cells and holds the table to
Cycles' own renders.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from addon.reference import subsurface  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=subsurface.WALK_SHIPPED)
    parser.add_argument("--paths", type=int, default=40000, help="walks per table node")
    parser.add_argument("--moment-paths", type=int, default=subsurface.WALK_MOMENT_PATHS,
                        help="walks per node of the drift's and the convex gain's tables")
    parser.add_argument("--keep-reflectance", type=Path, default=None,
                        help="take R / albedo from this table (walked at --paths: the same seeds give the "
                             "same values) and walk the other tables only")
    args = parser.parse_args()
    start = time.perf_counter()
    reflectance = None
    if args.keep_reflectance is not None:
        with np.load(args.keep_reflectance) as data:
            if int(data["paths"]) != args.paths:
                parser.error(f"{args.keep_reflectance} was walked at {int(data['paths'])} paths, "
                             f"not {args.paths}")
            reflectance = np.asarray(data["walk"], np.float32)
    table, drift, gain = subsurface.compute_walk_table(
        args.paths, log=lambda line: print(f"{time.perf_counter() - start:7.1f} s  {line}", flush=True),
        moment_paths=args.moment_paths, reflectance=reflectance)
    partial = args.out.with_name(f".{args.out.stem}.partial.npz")
    np.savez_compressed(partial, walk=table, drift=drift, gain=gain, paths=np.int64(args.paths),
                        moment_paths=np.int64(args.moment_paths))
    partial.replace(args.out)
    print(f"wrote {table.shape} to {args.out} in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
