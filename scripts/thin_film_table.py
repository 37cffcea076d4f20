"""Tabulate the thin film's spectral sensitivity (``addon/reference/thin_film_cmf.npz``).

    .venv/bin/python scripts/thin_film_table.py [--out addon/reference/thin_film_cmf.npz]

Belcour & Barla 2017 ("A Practical Extension to Microfacet Theory for the Modeling of Varying
Iridescence", section 4) integrate a film's reflectance over wavelengths in Fourier space: the
Airy series' m-th term oscillates as cos(2 pi m D / lambda) in the optical path difference D, so
its colour is the Fourier transform of the colour matching functions taken as functions of the
wavenumber nu = 1 / lambda (with the Jacobian d lambda = d nu / nu^2), at m D. Cycles 5.0 holds that
transform of the CIE 1931 2-degree XYZ functions in a table of 512 complex values for D from 0 to
60 um (its scene/shader.tables' table_thin_film_cmf, made by its doc/precompute/thin_film_table.py),
which its host turns into the scene linear space's RGB and normalises (scene/shader.cpp's
compute_thin_film_table: addon/reference/thin_film.py's ``sensitivity_table``).

This script makes the same table from colour-science's CIE 1931 2-degree functions (1 nm steps,
360 .. 830 nm, zero one step beyond each end), interpolated by cubic splines at 1022 wavenumbers
evenly spaced from 0 to pi 1021 / 60 per um (lambda = 1000 / nu nm), each value over nu^2, and
transformed by a real FFT: row i holds the transform at the path difference D where
x = 2 pi D / 60 um = i / 511, as glsl/thin_film.glsl's thin_film_sensitivity reads it.
Columns: Re X, Re Y, Re Z, Im X, Im Y, Im Z (float32). Needs colour-science and scipy (tests and
scripts only: the add-on reads the shipped table).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

#: Wavenumbers sampled and the path differences covered (Cycles' precompute: 1022 real samples give
#: 512 complex values; 0 .. 60 um).
SAMPLES = 1022
END_UM = 60.0


def cmf_table() -> np.ndarray:
    """(512, 6) float32: the real then imaginary parts of the CIE XYZ functions' transform."""
    import colour
    from scipy.interpolate import CubicSpline

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    lam = np.concatenate([[cmfs.wavelengths[0] - 1.0], cmfs.wavelengths, [cmfs.wavelengths[-1] + 1.0]])
    xyz = np.concatenate([np.zeros((1, 3)), cmfs.values, np.zeros((1, 3))])
    nu = np.maximum(np.linspace(0.0, np.pi * (SAMPLES - 1) / END_UM, SAMPLES), 1e-40)  # 1 / um
    columns = []
    for c in range(3):
        spline = CubicSpline(lam, xyz[:, c], extrapolate=False)
        with np.errstate(over="ignore", invalid="ignore"):
            columns.append(np.fft.rfft(np.nan_to_num(spline(1000.0 / nu) / (nu * nu))))
    spectrum = np.stack(columns, axis=-1)
    return np.concatenate([spectrum.real, spectrum.imag], axis=-1).astype(np.float32)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    shipped = Path(__file__).resolve().parents[1] / "addon" / "reference" / "thin_film_cmf.npz"
    parser.add_argument("--out", type=Path, default=shipped)
    args = parser.parse_args(argv)
    table = cmf_table()
    np.savez_compressed(args.out, cmf=table)
    print(f"{args.out}: {table.shape}, DC {table[0, :3]}")


if __name__ == "__main__":
    main()
