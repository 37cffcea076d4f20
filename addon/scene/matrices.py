"""Inverses of 3x3 and 4x4 matrices in closed form (cofactors over the determinant), for the
matrices a render inverts: views, projections, shadow layers, normal matrices; and the cross
product of two 3-vectors (``numpy.cross`` spends ~20 us per call on its arguments, ``cross3``
~2 us: a render's shadow layers took a few dozen).

Not ``numpy.linalg.inv``: numpy hands it to its BLAS library (OpenBLAS in numpy's wheels, which
the bpy module uses), whose LAPACK solve wakes the library's worker threads even for a 4x4, and those
threads then wait for more work by spinning (``sched_yield``) for a while. A render inverted some
thirty matrices while the software rasteriser's threads drew: on a 2-core machine the spinning
thread held 17 % of the CPU samples of a loop of softbox renders and the kernel's scheduling 19 %
(perf); inverting here, 0 % and 4 %, the rasteriser's threads 6 % more samples in the same time.
Pure numpy and Python floats: no library thread is involved.
"""

from __future__ import annotations

import numpy as np


def cross3(a, b) -> np.ndarray:
    """The cross product of two 3-vectors, as a float64 array."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]],
                    np.float64)


def _inverse3(a) -> tuple[list, object]:
    """The adjugate (rows) and determinant of [[a[r][c]]]: its columns are the cross products of
    the other two rows."""
    rows = [[a[1][1] * a[2][2] - a[1][2] * a[2][1], a[0][2] * a[2][1] - a[0][1] * a[2][2],
             a[0][1] * a[1][2] - a[0][2] * a[1][1]],
            [a[1][2] * a[2][0] - a[1][0] * a[2][2], a[0][0] * a[2][2] - a[0][2] * a[2][0],
             a[0][2] * a[1][0] - a[0][0] * a[1][2]],
            [a[1][0] * a[2][1] - a[1][1] * a[2][0], a[0][1] * a[2][0] - a[0][0] * a[2][1],
             a[0][0] * a[1][1] - a[0][1] * a[1][0]]]
    return rows, a[0][0] * rows[0][0] + a[0][1] * rows[1][0] + a[0][2] * rows[2][0]


_PAIRS = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))


def _inverse4(a) -> tuple[list, object]:
    """The adjugate (rows) and determinant of [[a[r][c]]], by Laplace expansion over the 2x2
    minors of the top two rows (s) and of the bottom two (c)."""
    # the 2x2 minors over column pairs (0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)
    s0, s1, s2, s3, s4, s5 = (a[0][i] * a[1][j] - a[1][i] * a[0][j] for i, j in _PAIRS)
    c0, c1, c2, c3, c4, c5 = (a[2][i] * a[3][j] - a[3][i] * a[2][j] for i, j in _PAIRS)
    det = s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0
    rows = [[a[1][1] * c5 - a[1][2] * c4 + a[1][3] * c3, -a[0][1] * c5 + a[0][2] * c4 - a[0][3] * c3,
             a[3][1] * s5 - a[3][2] * s4 + a[3][3] * s3, -a[2][1] * s5 + a[2][2] * s4 - a[2][3] * s3],
            [-a[1][0] * c5 + a[1][2] * c2 - a[1][3] * c1, a[0][0] * c5 - a[0][2] * c2 + a[0][3] * c1,
             -a[3][0] * s5 + a[3][2] * s2 - a[3][3] * s1, a[2][0] * s5 - a[2][2] * s2 + a[2][3] * s1],
            [a[1][0] * c4 - a[1][1] * c2 + a[1][3] * c0, -a[0][0] * c4 + a[0][1] * c2 - a[0][3] * c0,
             a[3][0] * s4 - a[3][1] * s2 + a[3][3] * s0, -a[2][0] * s4 + a[2][1] * s2 - a[2][3] * s0],
            [-a[1][0] * c3 + a[1][1] * c1 - a[1][2] * c0, a[0][0] * c3 - a[0][1] * c1 + a[0][2] * c0,
             -a[3][0] * s3 + a[3][1] * s1 - a[3][2] * s0, a[2][0] * s3 - a[2][1] * s1 + a[2][2] * s0]]
    return rows, det


def determinant3(m) -> np.ndarray | float:
    """The determinant of a (3, 3) matrix, or of each in a (..., 3, 3) stack, in float64, by the
    cofactors of its first row (``_inverse3``'s): numpy.linalg.det's LAPACK call per matrix cost
    ~7 us, a render took two per object."""
    m = np.asarray(m, np.float64)
    if m.ndim < 2 or m.shape[-2:] != (3, 3):
        raise ValueError(f"determinant3 takes 3x3 matrices, not {m.shape}")
    entries = m.tolist() if m.ndim == 2 else [[m[..., r, c] for c in range(3)] for r in range(3)]
    return _inverse3(entries)[1]


def invert(m) -> np.ndarray:
    """The inverse of a (3, 3) or (4, 4) matrix, or of each in a (..., n, n) stack, in float64.
    Raises ``numpy.linalg.LinAlgError`` where one is singular (a zero or non-finite determinant),
    as ``numpy.linalg.inv`` does. One matrix is worked in Python floats (numpy's per-operation
    overhead would make it ten times slower than LAPACK), a stack elementwise in arrays."""
    m = np.asarray(m, np.float64)
    n = m.shape[-1]
    if m.ndim < 2 or m.shape[-2:] not in ((3, 3), (4, 4)):
        raise ValueError(f"invert takes 3x3 or 4x4 matrices, not {m.shape}")
    single = m.ndim == 2
    entries = m.tolist() if single else [[m[..., r, c] for c in range(n)] for r in range(n)]
    rows, det = (_inverse3 if n == 3 else _inverse4)(entries)
    if not np.all(np.isfinite(det) & (np.asarray(det) != 0.0)):
        raise np.linalg.LinAlgError("Singular matrix")
    if single:
        return np.array(rows) / det
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2) / np.asarray(det)[..., None, None]
