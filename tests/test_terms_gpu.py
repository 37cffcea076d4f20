"""Every GLSL term against its numpy twin, evaluated on the GPU in isolation (glsl_harness),
over random inputs and the extremes of their domains. Agreement to float32 precision: relative
1e-4 where the function is well conditioned, and an absolute floor of 1e-6 of the value range
near zero (float32 carries ~7 digits; the twin runs in float64)."""

from __future__ import annotations

import numpy as np
import pytest
from glsl_harness import evaluate

from addon.reference import brdf as S
from addon.reference import tonemap as T

N = 4096
RNG = np.random.default_rng(7)


def f32(x):
    """Inputs rounded to float32 for both sides: the GPU cannot hold 1 - 1e-7, and comparing
    the twin on unrounded inputs would measure the rounding, not the shader."""
    return np.asarray(x, np.float32).astype(np.float64)


def _u(lo, hi, shape):
    return f32(RNG.uniform(lo, hi, shape))


def _cosines(n):
    """Cosines in [0, 1], with the ends and near-ends included."""
    c = RNG.uniform(0.0, 1.0, n)
    c[:8] = [0.0, 1e-7, 1e-4, 0.01, 0.5, 0.999, 1.0 - 1e-7, 1.0]
    return f32(c)


def _alphas(n):
    a = RNG.uniform(0.002, 1.0, n)
    a[:6] = [0.045 ** 2, 0.01, 0.1, 0.5, 0.9, 1.0]
    return f32(a)


def _rows(*cols):
    cols = [np.asarray(c, np.float64) for c in cols] + [np.zeros(N)] * (4 - len(cols))
    return np.stack(cols, axis=-1)


def _check(gpu, twin, rtol=1e-4, atol=1e-6, label=""):
    gpu = np.asarray(gpu, np.float64)
    twin = np.asarray(twin, np.float64)
    assert np.all(np.isfinite(twin)), "the twin itself must be finite on this domain"
    assert np.all(np.isfinite(gpu))
    scale = max(np.abs(twin).max(), 1e-12)
    err = np.abs(gpu - twin)
    bad = err > rtol * np.abs(twin) + atol * scale
    worst = np.max(err / np.maximum(np.abs(twin), atol * scale))
    assert not bad.any(), f"{label}: {bad.sum()} of {bad.size} disagree; worst relative {worst:.3g}"
    return worst


SCALAR_TERMS = {
    # name: (GLSL call on vec4 a, twin on columns, input columns)
    "D_GGX": ("D_GGX(a.x, a.y, a.z)", lambda c, s2, al: S.D_GGX(c, s2, al)),
    "D_Beckmann": ("D_Beckmann(a.x, a.y, a.z)", lambda c, s2, al: S.D_Beckmann(c, s2, al)),
}


@pytest.mark.parametrize("name", ["D_GGX", "D_Beckmann"])
def test_distributions(name):
    c = _cosines(N)
    c[c < 0.05] += 0.05  # NDFs at n.h -> 0 are exp(-1/x) tiny or 0: checked in the stability sweep
    c = f32(np.minimum(c, 1.0))
    al = _alphas(N)
    s2 = f32(1.0 - c * c)
    a = _rows(c, s2, al)
    call, twin = SCALAR_TERMS[name]
    got = evaluate(f"result = vec4({call});", {"a": a})[:, 0]
    _check(got, twin(c, s2, al), rtol=2e-4)


VISIBILITY = {
    "V_SmithGGXCorrelated": S.V_SmithGGXCorrelated,
    "V_SmithGGXSeparable": S.V_SmithGGXSeparable,
    "V_SmithBeckmannCorrelated": S.V_SmithBeckmannCorrelated,
    "V_SmithBeckmannSeparable": S.V_SmithBeckmannSeparable,
    "V_SmithGGXHammon": S.V_SmithGGXHammon,
    "V_SchlickBeckmann": S.V_SchlickBeckmann,
}


@pytest.mark.parametrize("name", sorted(VISIBILITY))
def test_visibility(name):
    nv, nl, al = np.maximum(_cosines(N), 1e-4), np.maximum(_cosines(N)[::-1], 1e-4), _alphas(N)
    got = evaluate(f"result = vec4({name}(a.x, a.y, a.z));", {"a": _rows(nv, nl, al)})[:, 0]
    _check(got, VISIBILITY[name](nv, nl, al))


def test_v_cavity_and_lambda():
    nv, nl, nh, vh = (np.maximum(_cosines(N), 1e-4) for _ in range(4))
    got = evaluate("result = vec4(V_CookTorrance(a.x, a.y, a.z, a.w));", {"a": _rows(nv, nl, nh, vh)})[:, 0]
    _check(got, S.V_CookTorrance(nv, nl, nh, vh))
    c, al = _cosines(N), _alphas(N)
    got = evaluate("result = vec4(Lambda_Beckmann(a.x, a.y));", {"a": _rows(c, al)})[:, 0]
    _check(got, S.Lambda_Beckmann(c, al), rtol=2e-4)


def test_fresnel_terms():
    f0 = _u(0, 1, (N, 3))
    f0[:3] = [0, 0, 0], [1, 1, 1], [0.04, 0.04, 0.04]
    f90, loh, p = _u(0, 1, N), _cosines(N), _u(0.05, 2.0, N)
    a, b = np.column_stack([f0, f90]), _rows(loh, p)
    for call, twin in [
        ("F_Schlick(a.xyz, a.w, b.x)", S.F_Schlick(f0, f90, loh)),
        ("F_SchlickSG(a.xyz, a.w, b.x)", S.F_SchlickSG(f0, f90, loh)),
        ("F_SchlickGeneral(a.xyz, a.w, b.y, b.x)", S.F_SchlickGeneral(f0, f90, p, loh)),
    ]:
        got = evaluate(f"result = vec4({call}, 0.0);", {"a": a, "b": b})[:, :3]
        _check(got, twin, label=call)
    eta = _u(1.0, 3.0, N)
    eta[:4] = [1.0, 1.0001, 1.33, 1.5]
    got = evaluate("result = vec4(F_Dielectric(a.x, a.y));", {"a": _rows(eta, loh)})[:, 0]
    _check(got, S.F_Dielectric(eta, loh), rtol=3e-4)
    n, k = _u(0.05, 3.0, (N, 3)), _u(0.0, 8.0, (N, 3))
    got = evaluate("result = vec4(F_Conductor(a.xyz, b.xyz, c.x), 0.0);",
                   {"a": np.column_stack([n, np.zeros(N)]), "b": np.column_stack([k, np.zeros(N)]),
                    "c": _rows(loh)})[:, :3]
    # rs and rp are differences t1 - t2 of nearly equal float32 sums near their minima: an
    # absolute floor of 1e-5 of the [0, 1] range (float32 epsilon x the cancellation)
    _check(got, S.F_Conductor(n, k, loh), rtol=1e-4, atol=1e-5)


def test_atan2_accurate():
    """common.glsl's atan2_accurate against float64 in every quadrant, over 60 decades of scale:
    to float precision (measured 2.2e-7 relative; Mesa llvmpipe's own atan(y, x): 2.1e-5)."""
    theta, r = RNG.uniform(-np.pi, np.pi, N), 10.0 ** RNG.uniform(-30, 30, N)
    y, x = f32(np.sin(theta) * r), f32(np.cos(theta) * r)
    y[:6], x[:6] = [0.0, 0.0, 1.0, -1.0, 0.0, 1e-30], [1.0, -1.0, 0.0, 0.0, 0.0, 0.0]
    got = evaluate("result = vec4(atan2_accurate(a.x, a.y));", {"a": _rows(y, x)})[:, 0]
    _check(got, np.arctan2(y, x), rtol=6e-7, atol=1e-12, label="atan2_accurate")


def test_diffuse_terms():
    nv, nl, loh, nh = (np.maximum(_cosines(N), 1e-4) for _ in range(4))
    r = _u(0, 1, N)
    r[:3] = [0.0, 0.045, 1.0]
    lov = _u(-1, 1, N)
    cos_phi = _u(-1, 1, N)
    rho = _u(0, 1, (N, 3))
    for name in ("Fd_Burley", "Fd_BurleyRenormalized"):
        got = evaluate(f"result = vec4({name}(a.x, a.y, a.z, a.w));", {"a": _rows(nv, nl, loh, r)})[:, 0]
        _check(got, getattr(S, name)(nv, nl, loh, r), label=name)
    got = evaluate("result = vec4(Fd_OrenNayar(c.xyz, a.x, a.y, a.z, a.w), 0.0);",
                   {"a": _rows(nv, nl, cos_phi, r), "c": np.column_stack([rho, np.zeros(N)])})[:, :3]
    _check(got, S.Fd_OrenNayar(rho, nv, nl, cos_phi, r), rtol=3e-4)
    got = evaluate("result = vec4(Fd_GGXHammon(c.xyz, a.x, a.y, a.z, a.w, b.x), 0.0);",
                   {"a": _rows(nv, nl, nh, lov), "b": _rows(r * r), "c": np.column_stack([rho, np.zeros(N)])})
    _check(got[:, :3], S.Fd_GGXHammon(rho, nv, nl, nh, lov, r * r))


def test_empirical_lobes():
    nh = _cosines(N)
    s = _u(0, 1e4, N)
    s[:4] = [1e-4, 1.0, 1e4, 1e6]
    got = evaluate("result = vec4(S_BlinnPhong(a.x, a.y), S_BlinnPhongNormalized(a.x, a.y), 0.0, 0.0);",
                   {"a": _rows(nh, s)})
    _check(got[:, 0], S.S_BlinnPhong(nh, s), rtol=2e-3)  # pow() of float32 near 1 with s ~ 1e4
    _check(got[:, 1], S.S_BlinnPhongNormalized(nh, s), rtol=2e-3)


def test_tone_curves():
    x = np.concatenate([np.linspace(0, 4, N // 2), np.geomspace(4, 1e5, N - N // 2)])
    rgb = np.column_stack([x, x * 0.3, x * 0.05])
    a = np.column_stack([rgb, np.zeros(N)])
    for glsl, twin in [("tonemap_reinhard", T.tonemap_reinhard), ("tonemap_hable", T.tonemap_hable),
                       ("tonemap_aces", T.tonemap_aces), ("transfer_gamma22", T.transfer_gamma22)]:
        arg = "min(a.xyz, vec3(1.0))" if glsl == "transfer_gamma22" else "a.xyz"
        got = evaluate(f"result = vec4({glsl}({arg}), 0.0);", {"a": a})[:, :3]
        ref = twin(np.minimum(rgb, 1.0)) if glsl == "transfer_gamma22" else twin(rgb)
        _check(got, ref, rtol=3e-4)
