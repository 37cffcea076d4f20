"""Tabulate rough glass's single-scattering albedo (``addon/reference/glass_albedo.npz``).

    .venv/bin/python scripts/glass_albedo_table.py [--out addon/reference/glass_albedo.npz]
                                                   [--strata 128]

The GGX glass lobe's albedo (reflection and transmission together) over roughness, n.v and IOR,
entering glass and leaving it, and its cosine-weighted average: the four tables Cycles'
cycles_precompute makes (ggx_glass_E, ggx_glass_inv_E and their averages), on its 16^3 grid, by
``addon/reference/transmission.py``'s compute_glass_albedo_tables (pure numpy, a deterministic
quadrature over visible normals). glsl/transmission.glsl's glass_compensation reads them to restore
what single scattering loses, as Cycles' microfacet_ggx_preserve_energy does. About five minutes on
one core at 128 x 128 visible normals per node (their error: below 1e-3 of E but near the critical
angle, 2e-3); tests/test_transmission_paths.py recomputes sample nodes.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from addon.reference import transmission  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=transmission.GLASS_SHIPPED)
    parser.add_argument("--strata", type=int, default=128, help="visible normals per axis per node")
    args = parser.parse_args()
    start = time.perf_counter()
    tables = transmission.compute_glass_albedo_tables(strata=args.strata, log=lambda line: print(
        f"{time.perf_counter() - start:7.1f} s  {line}", flush=True))
    partial = args.out.with_name(f".{args.out.stem}.partial.npz")
    np.savez_compressed(partial, strata=np.int64(args.strata), **tables)
    partial.replace(args.out)
    print(f"wrote {', '.join(tables)} to {args.out} in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
