"""Cycles' rules for a bent normal's light (glsl/bent_normal.glsl) and their numpy twins
(addon/reference/normals.py): the twins against closed forms -- the corrected mirror direction's
height over the surface, the shadowing terms at their published limits and in closed form on
bends laid out in a plane -- and the GLSL against the twins on the GPU (glsl_harness), over random
unit vectors (inputs rounded to float32 for both sides, rows whose branch a float32 rounding could
flip left out)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from glsl_harness import evaluate

from addon.materials.surface import BUMP_SHADOWING
from addon.reference import normals

N = 4096
RNG = np.random.default_rng(11)
Z = np.array([0.0, 0.0, 1.0])


def _unit(v):
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _f32(v):
    return np.asarray(v, np.float32).astype(np.float64)


def _spherical(n):
    return _f32(_unit(RNG.normal(size=(n, 3))))


def _in_plane(angle):
    """Unit vectors in the xz plane at ``angle`` (radians) from +z towards +x."""
    angle = np.asarray(angle, np.float64)
    return np.stack([np.sin(angle), np.zeros_like(angle), np.cos(angle)], axis=-1)


# --- valid_specular_normal against its closed form --------------------------------------------

def _views_and_bent_normals(n):
    """True normal +z, views above the surface (some grazing), normals bent from it by up to 85
    degrees: about half of them mirror the view below the threshold."""
    ng = np.tile(Z, (n, 1))
    i = _around_z(RNG.uniform(0.0, math.radians(89.5), n), RNG.uniform(0.0, 2 * math.pi, n))
    bent = _around_z(RNG.uniform(0.0, math.radians(85.0), n), RNG.uniform(0.0, 2 * math.pi, n))
    return _f32(ng), _f32(i), _f32(_unit(bent))


def _around_z(theta, phi):
    """Unit vectors at theta from +z, at azimuth phi."""
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


def test_valid_specular_normal_lifts_the_mirror_direction_exactly_to_its_threshold():
    """Where the mirror direction of the view about n dips under t = min(0.9 i.ng, 0.01) above the
    surface, the corrected normal is unit, in the plane of n and ng, on n's side, nearer ng than n
    is, and mirrors the view exactly t above the surface (measured: within 3.6e-13); elsewhere it is
    n itself."""
    ng, i, n = _views_and_bent_normals(N)
    out = normals.valid_specular_normal(ng, i, n)
    t = normals.valid_specular_threshold(ng, i)
    height = lambda m, i: np.sum(Z * (2.0 * np.sum(m * i, -1, keepdims=True) * m - i), -1)  # noqa: E731
    fixed = height(n, i) < t
    assert 0.2 < fixed.mean() < 0.8, fixed.mean()
    assert np.array_equal(out[~fixed], n[~fixed])
    o, m = out[fixed], n[fixed]
    assert np.abs(np.linalg.norm(o, axis=-1) - 1.0).max() < 1e-12
    off_plane = np.abs(np.sum(o * np.cross(m, ng[fixed]), -1))
    assert off_plane.max() < 1e-12, off_plane.max()
    along = m - m[:, 2:3] * Z  # n's direction along the surface
    assert np.all(np.sum(o * along, -1) >= 0.0) and np.all(o[:, 2] >= m[:, 2] - 1e-12)
    miss = np.abs(height(o, i[fixed]) - t[fixed]).max()
    print(f"corrected mirror direction's height off its threshold by {miss:.1e}")
    assert miss < 1e-12, miss


def test_valid_specular_normal_keeps_normals_that_mirror_above_the_surface():
    """n = ng (no bend), and a view straight along a normal (its mirror is itself), stay."""
    ng, i, _n = _views_and_bent_normals(64)
    assert np.array_equal(normals.valid_specular_normal(ng, i, ng), ng)
    bent = _unit(np.array([[0.3, 0.1, 1.0]] * 64))
    assert np.array_equal(normals.valid_specular_normal(ng, bent, bent), bent)


# --- the shadowing terms at their published limits and in closed form ------------------------

def _bend(d_degrees, theta_degrees):
    """ns = +z, n bent from it by d, l at theta from +z, all in the xz plane."""
    d = np.radians(np.asarray(d_degrees, np.float64))
    theta = np.radians(np.asarray(theta_degrees, np.float64))
    shape = np.broadcast(d, theta).shape
    return np.broadcast_to(Z, shape + (3,)), _in_plane(np.broadcast_to(d, shape)), \
        _in_plane(np.broadcast_to(theta, shape))


def test_chiang_term_at_its_limits():
    """Chiang et al. 2019: g = cos(theta) / (cos(theta - d) cos(d)) here; a light along the smooth
    normal sees the bent surface unshadowed (g >= 1: 1), one at the smooth surface's horizon none
    of it (g = 0: 0), one below it nothing; between, -g^3 + g^2 + g, which meets 1 with slope 0 at
    g = 1 (no kink)."""
    ns, n, l = _bend([30.0, 30.0, 30.0, 30.0], [0.0, 90.0, 100.0, 60.0])
    w = normals.bump_terminator_chiang(ns, n, l)
    g = math.cos(math.radians(60)) / (math.cos(math.radians(30)) * math.cos(math.radians(30)))
    expected = -g ** 3 + g * g + g
    assert np.allclose(w[:, 0], [1.0, 0.0, 0.0, expected], atol=1e-12), w[:, 0]
    assert np.array_equal(w[:, 1], [1.0, 1.0, 0.0, 1.0])  # the specular lobe: light above ns
    smooth = lambda g: -g ** 3 + g * g + g  # noqa: E731
    eps = 1e-6
    assert abs(smooth(1.0) - 1.0) < 1e-15 and abs((smooth(1.0) - smooth(1.0 - eps)) / eps) < 1e-5


def test_conty_term_at_its_limits_and_in_closed_form():
    """Conty Estevez et al. 2019: no bend, no shadowing (1); a light grazing the smooth surface, none
    of the diffuse lobe (0); from the other side of ns than n sees it (here 5 degrees under the smooth
    surface, 65 from n), nothing (both lobes); and
    Smith's GGX G1 = 2 / (1 + sqrt(1 + alpha^2 tan^2 i)) with alpha^2 = tan^2(d) / 8, at most 1:
    d = 45, i = 60 degrees gives 2 / (1 + sqrt(1 + 3/8)); d = 80 degrees clamps alpha^2 to 1."""
    ns, n, l = _bend([0.0, 30.0, 30.0, 45.0, 80.0, 30.0], [70.0, 90.0 - 1e-5, 20.0, 60.0, 60.0, 95.0])
    w = normals.bump_terminator_conty(ns, n, l)
    g45 = 2.0 / (1.0 + math.sqrt(1.0 + 3.0 / 8.0))
    g80 = 2.0 / (1.0 + math.sqrt(1.0 + 3.0))
    tan2_20 = math.tan(math.radians(20.0)) ** 2
    g30 = 2.0 / (1.0 + math.sqrt(1.0 + 0.125 * math.tan(math.radians(30.0)) ** 2 * tan2_20))
    assert np.allclose(w[:, 0], [1.0, 0.0, g30, g45, g80, 0.0], atol=1e-12), w[:, 0]
    assert np.array_equal(w[:, 1], [1.0, 1.0, 1.0, 1.0, 1.0, 0.0])


# --- the GLSL against the twins ------------------------------------------------------------------

def _safe_rows(ns, n, l):
    """Rows whose branches a float32 rounding cannot flip (each test's quantity away from its
    threshold), for both rules."""
    cos_nl, cos_nsl, cos_nsn = (np.sum(a * b, -1) for a, b in ((n, l), (ns, l), (ns, n)))
    s = np.where((cos_nl < 0.0)[:, None], -ns, ns)
    den = cos_nl * np.sum(s * n, -1)
    g = np.sum(s * l, -1) / np.where(den != 0.0, den, 1.0)
    far = (np.abs(cos_nl) > 1e-3) & (np.abs(cos_nsl) > 1e-3) & (np.abs(cos_nsn) > 1e-3)
    return far & (np.abs(g - 1.0) > 1e-3) & (np.abs(g) > 1e-3) & (np.abs(cos_nsn) < 1.0 - 1e-6)


#: The largest difference of the GLSL's weights from the twin's (float32 against float64), measured
MEASURED = {"CHIANG_2019": 8.3e-7, "CONTY_2019": 2.8e-6}


@pytest.mark.parametrize("rule", BUMP_SHADOWING)
def test_bump_terminator_glsl_matches_its_twin(rule):
    ns = _spherical(N)
    n = _f32(_unit(ns + 0.8 * RNG.normal(size=(N, 3))))  # bent by up to ~90 degrees
    l = _spherical(N)
    rows = lambda v: np.column_stack([v, np.zeros(N)])  # noqa: E731
    gpu = evaluate("result = vec4(bump_terminator(ns.xyz, n.xyz, l.xyz), 0.0, 0.0);",
                   {"ns": rows(ns), "n": rows(n), "l": rows(l)},
                   defines={"SL_GRAPH_BENT_NORMAL": "1", f"SL_BUMP_SHADOWING_{rule}": "1"},
                   extra=("bent_normal.glsl",))[:, :2].astype(np.float64)
    twin = normals.bump_terminator(ns, n, l, rule)
    safe = _safe_rows(ns, n, l)
    assert safe.mean() > 0.95
    worst = float(np.abs(gpu - twin)[safe].max())
    print(f"{rule}: largest difference {worst:.1e} over {safe.sum()} rows")
    assert worst <= 3.0 * MEASURED[rule], f"{rule}: {worst:.1e} (measured {MEASURED[rule]:.1e})"


def test_valid_specular_normal_glsl_matches_its_twin():
    """Measured: 7.7e-5 (float32's b - sqrt(b^2 - 4ac) where the root is small)."""
    ng, i, n = _views_and_bent_normals(N)
    t = normals.valid_specular_threshold(ng, i)
    h = np.sum(ng * (2.0 * np.sum(n * i, -1, keepdims=True) * n - i), -1)
    safe = np.abs(h - t) > 1e-4  # the validity test itself not flipped by float32
    rows = lambda v: np.column_stack([v, np.zeros(N)])  # noqa: E731
    gpu = evaluate("result = vec4(valid_specular_normal(ng.xyz, i.xyz, n.xyz), 0.0);",
                   {"ng": rows(ng), "i": rows(i), "n": rows(n)},
                   defines={"SL_GRAPH_BENT_NORMAL": "1"}, extra=("bent_normal.glsl",))
    gpu = gpu[:, :3].astype(np.float64)
    twin = normals.valid_specular_normal(ng, i, n)
    worst = float(np.abs(gpu - twin)[safe].max())
    print(f"valid_specular_normal: largest difference {worst:.1e} over {safe.sum()} rows")
    assert worst <= 3.0 * 7.7e-5, f"{worst:.1e} (measured 7.7e-5)"
