"""The Principled BSDF's sheen as linearly transformed cosines (glsl/principled.glsl's sheen_at):
Zeltner, Burley & Chiang 2022, "Practical Multiple-Scattering Sheen Using Linearly Transformed
Cosines", as Cycles 4.x / 5.0 draw it (kernel/closure/bsdf_sheen.h). Per (n.v, roughness), the lobe
is a clamped cosine moved by M^-1 = [[a, 0, b], [0, a, 0], [0, 0, 1]] in the frame (the tangent
towards v, n x it, n) and scaled by its directional albedo.

The table (``SHIPPED``: a, b and the albedo on a SIZE x SIZE grid, n.v = i / (SIZE - 1) across,
roughness j / (SIZE - 1) down) is fitted to Cycles' own Sheen BSDF by ``scripts/fit_sheen.py``:
Cycles renders the lobe under suns from several directions, and at every pixel the lobe's
reflectance is linear in (a^2 R, a^2, a b, b^2) once its measured value is inverted, so each pixel
gives its (a, b, R) exactly; the grid's values follow by least squares over the pixels, as Cycles
interpolates them bilinearly. Pure numpy: no ``bpy``, no ``gpu``.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

#: Cells per side of the table (its nodes at i / (SIZE - 1), both ends included).
SIZE = 32
SHIPPED = Path(__file__).with_name("sheen_ltc.npz")


@lru_cache(maxsize=1)
def table() -> np.ndarray:
    """(SIZE, SIZE, 3) float32: (a, b, albedo) by [roughness index, n.v index]."""
    if not SHIPPED.exists():
        raise FileNotFoundError(f"the sheen table {SHIPPED.name} is missing: run scripts/fit_sheen.py")
    with np.load(SHIPPED) as data:
        out = np.asarray(data["sheen_ltc"], np.float32)
    if out.shape != (SIZE, SIZE, 3):
        raise ValueError(f"{SHIPPED.name}: a table of {out.shape}, expected {(SIZE, SIZE, 3)}")
    return out


def lookup(NoV, roughness) -> np.ndarray:
    """(..., 3): (a, b, albedo) at each (n.v, roughness), bilinear between the nodes as Cycles'
    lookup_table_read_2D (and glsl/principled.glsl's sheen_lookup), both clamped to [0, 1]."""
    t = table().astype(np.float64)
    n = SIZE - 1
    x = np.clip(np.asarray(NoV, np.float64), 0.0, 1.0) * n
    y = np.clip(np.asarray(roughness, np.float64), 0.0, 1.0) * n
    x, y = np.broadcast_arrays(x, y)
    i0, j0 = np.floor(x).astype(int), np.floor(y).astype(int)
    i1, j1 = np.minimum(i0 + 1, n), np.minimum(j0 + 1, n)
    fx, fy = (x - i0)[..., None], (y - j0)[..., None]
    top = t[j0, i0] + (t[j0, i1] - t[j0, i0]) * fx
    bottom = t[j1, i0] + (t[j1, i1] - t[j1, i0]) * fx
    return top + (bottom - top) * fy
