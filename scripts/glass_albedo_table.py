"""Tabulate rough glass's single-scattering albedo (``addon/reference/glass_albedo.npz``).

    .venv/bin/python scripts/glass_albedo_table.py [--out addon/reference/glass_albedo.npz]
                                                   [--strata 128]

The GGX glass lobe's albedo (reflection and transmission together) over roughness, n.v and IOR,
entering glass and leaving it, and its cosine-weighted average: the four tables Cycles'
cycles_precompute makes (ggx_glass_E, ggx_glass_inv_E and their averages), on its 16^3 grid, and the
transmitted part alone (T, T_inv), by ``addon/reference/transmission.py``'s
compute_glass_albedo_tables (pure numpy, a deterministic quadrature over visible normals).
glsl/transmission.glsl's glass_compensation reads them to restore what single scattering loses, as
Cycles' microfacet_ggx_preserve_energy does, and glass_transmitted what of a crossing passes. About
seven minutes on one core at 128 x 128 visible normals per node (within 2.3e-4 of Cycles' own
table); tests/test_transmission.py holds them to Cycles' table and recomputes sample nodes.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from addon.reference import transmission  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=transmission.GLASS_SHIPPED)
    parser.add_argument("--strata", type=int, default=128, help="visible normals per axis per node")
    args = parser.parse_args()
    start = time.perf_counter()

    def log(line):
        print(f"{time.perf_counter() - start:7.1f} s  {line}", flush=True)

    names = transmission.write_glass_albedo_tables(args.out, args.strata, log)
    log(f"wrote {', '.join(names)} to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
