"""The numpy twin of ``glsl/bent_normal.glsl``: Cycles' rules for the light a normal bent by a node
graph (a Normal Map, a Bump) takes, function for function.

- ``bump_terminator_chiang`` / ``bump_terminator_conty``: a light's (diffuse, specular) weights
  where the shading normal n was bent from the smooth normal ns (Cycles' bump_shadowing_term,
  kernel/closure/bsdf.h): Blender 4.2's after Chiang, Li and Burley 2019, "Taming the Shadow
  Terminator"; 4.3's and later after Conty Estevez, Lecocq and Stein 2019, "A Microfacet-Based
  Shadowing Function to Solve the Bump Terminator Problem" (``bump_terminator`` picks by
  ``materials.surface.BUMP_SHADOWING``'s name).
- ``valid_specular_normal``: Cycles' ensure_valid_specular_reflection (kernel/closure/
  bsdf_util.h): n turned towards the true normal just enough that the view's mirror direction
  leaves the surface.

Inputs are arrays ((..., 3) unit vectors), evaluated in float64; the guards are the GLSL's. Pure
numpy: no ``bpy``, no ``gpu``.
"""

from __future__ import annotations

import numpy as np


def _dot(a, b):
    return np.sum(np.asarray(a, np.float64) * np.asarray(b, np.float64), axis=-1)


def bump_terminator_chiang(ns, n, l):
    """(..., 2): Blender 4.2's weights. Diffuse: g = (ns.l) / ((n.l)(ns.n)) with ns turned to n's
    side of l; 0 below the smooth surface (g < 0), 1 where g >= 1, -g^3 + g^2 + g between.
    Specular: 0 where l lies on the other side of ns than of n (the microfacet eval's hemisphere
    test), else 1."""
    ns, n, l = (np.asarray(x, np.float64) for x in (ns, n, l))
    cos_nl = _dot(n, l)
    specular = np.where(_dot(ns, l) * cos_nl < 0.0, 0.0, 1.0)
    s = np.where((cos_nl < 0.0)[..., None], -ns, ns)
    den = cos_nl * _dot(s, n)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(den != 0.0, _dot(s, l) / np.where(den != 0.0, den, 1.0), 0.0)  # Cycles' safe_divide
    diffuse = np.where(g >= 1.0, 1.0, np.where(g < 0.0, 0.0, g * (1.0 + g - g * g)))
    return np.stack([diffuse, specular], axis=-1)


def bump_terminator_conty(ns, n, l):
    """(..., 2): Blender 4.3's and later weights. Both 0 where l lies on the other side of ns than
    n sees it (cos(ns, l) cos(ns, n) cos(n, l) < 0); else the diffuse lobe shadowed by Smith's GGX
    G1 = 2 / (1 + sqrt(1 + alpha^2 tan^2 i)) at the light's angle i to ns, alpha^2 = tan^2(d) / 8
    (at most 1) of the bend d between ns and n (1 without a bend, 0 grazing the smooth surface),
    the specular lobe 1."""
    ns, n, l = (np.asarray(x, np.float64) for x in (ns, n, l))
    cos_nsl, cos_nsn = _dot(ns, l), _dot(ns, n)
    rejected = cos_nsl * cos_nsn * _dot(n, l) < 0.0
    cos_i, cos_d = np.abs(cos_nsl), np.abs(cos_nsn)
    unbent = (cos_d >= 1.0) | (cos_i >= 1.0)
    grazing = cos_i < 1e-6
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha2 = np.clip(0.125 * (1.0 / (cos_d * cos_d) - 1.0), 0.0, 1.0)
        tan2_i = 1.0 / (cos_i * cos_i) - 1.0
        g1 = 2.0 / (1.0 + np.sqrt(1.0 + alpha2 * tan2_i))
    diffuse = np.where(unbent, 1.0, np.where(grazing, 0.0, g1))
    diffuse = np.where(rejected, 0.0, diffuse)
    specular = np.where(rejected, 0.0, 1.0)
    return np.stack([diffuse, specular], axis=-1)


#: ``materials.surface.BUMP_SHADOWING``'s rules, by name
BUMP_TERMINATORS = {"CHIANG_2019": bump_terminator_chiang, "CONTY_2019": bump_terminator_conty}


def bump_terminator(ns, n, l, rule: str = "CONTY_2019"):
    """(..., 2): the (diffuse, specular) weights of Cycles' ``rule``."""
    return BUMP_TERMINATORS[rule](ns, n, l)


def valid_specular_threshold(ng, i):
    """How far above the surface the view's mirror direction must leave: min(0.9 i.ng, 0.01)."""
    return np.minimum(0.9 * _dot(i, ng), 0.01)


def valid_specular_normal(ng, i, n):
    """(..., 3): n where the mirror direction 2 (n.i) n - i leaves the surface at least
    ``valid_specular_threshold`` above it (ng the true normal, facing the viewer; i towards the
    viewer); else n turned towards ng in their common plane until it does exactly: its height z
    over the surface the root of 4 a z^4 - 2 b z^2 + c = 0 (a = (i.x)^2 + (i.ng)^2, b = 2 (a +
    (i.ng) t), c = ((i.ng) + t)^2, x the unit direction of n along the surface) on the side i.x
    has."""
    ng, i, n = (np.asarray(x, np.float64) for x in (ng, i, n))
    iz = _dot(i, ng)
    t = valid_specular_threshold(ng, i)
    valid = _dot(ng, 2.0 * _dot(n, i)[..., None] * n - i) >= t
    x = n - _dot(n, ng)[..., None] * ng
    length = np.sqrt(_dot(x, x))[..., None]
    x = np.where(length > 0.0, x / np.where(length > 0.0, length, 1.0), n)  # n along ng: Cycles' fallback
    ix = _dot(i, x)
    a = ix * ix + iz * iz
    b = 2.0 * (a + iz * t)
    c = (t + iz) * (t + iz)
    root = np.sqrt(np.maximum(b * b - 4.0 * a * c, 0.0))  # safe_sqrtf: rounding below 0
    with np.errstate(divide="ignore", invalid="ignore"):
        z2 = 0.25 * np.where(ix < 0.0, b + root, b - root) / a
    turned = np.sqrt(np.maximum(1.0 - z2, 0.0))[..., None] * x + np.sqrt(np.maximum(z2, 0.0))[..., None] * ng
    keep = valid | (a <= 0.0)  # a view along no direction of the plane (i = 0): nothing to mirror
    return np.where(keep[..., None], n, turned)
