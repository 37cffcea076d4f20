"""The numpy twin of ``glsl/node_tex_noise.glsl``: Cycles' Perlin noise (kernel/svm/noise.h), its
fractals (fractal_noise.h) and the Noise Texture (noisetex.h: Detail clamp, Distortion, the Color
output's seeds). Vectorised over coordinates (..., d), d = 1 .. 4 (the dimensions), with the
node's settings as scalars; float32 as Cycles computes. The twin keeps Cycles' five fractal
functions apart, where the GLSL runs them as one loop (a shader compiler inlines the noise once).

Cycles' CPU kernel (AVX2, built with -ffast-math and FMA) fuses some a * b + c into one rounding:
the SIMD fade's madd and, as its compiler chose, the lerps, the fractal sums, ``snoise + offset``,
1D and 2D distortion and the 3D/4D coordinate wrap. Which ones was measured against Cycles 5.0
(every dimension and type, coordinates to |x| = 8e10): with them the twin equals Cycles' output bit
for bit; without, it differs by up to 7e-7 (and more at |x| > 5e8). ``fma`` below is that fused
operation (the product exact in float64, rounded once to float32 but for double-rounding ties,
which never showed). Pure numpy.
"""

from __future__ import annotations

import numpy as np

from . import hashing

F32 = np.float32

#: Cycles' output scales per dimension (noise_scale1..4: the OSL developers' measured ranges).
SCALES = {1: F32(0.25), 2: F32(0.6616), 3: F32(0.9820), 4: F32(0.8344)}
#: The Noise Texture's types, each a fractal below.
TYPES = ("FBM", "MULTIFRACTAL", "HYBRID_MULTIFRACTAL", "RIDGED_MULTIFRACTAL", "HETERO_TERRAIN")


def fma(a, b, c) -> np.ndarray:
    """a * b + c rounded once to float32 (a fused multiply-add): the product of two floats is exact
    in double precision, the sum rounded there and then to single (twice: differs from one
    rounding where the double lands on a single-precision midpoint, about 1 case in 2^29)."""
    a, b, c = (np.asarray(x, F32).astype(np.float64) for x in (a, b, c))
    return (a * b + c).astype(F32)


def _hash(*cells: np.ndarray) -> np.ndarray:
    """Cycles' hash_uint..4 of integer lattice cells (as its int -> uint cast), as int64."""
    keys = [np.asarray(c, np.int64).astype(np.uint32) for c in cells]
    return hashing.hash_uint(*keys).astype(np.int64)


def _negate_if(value, condition):
    return np.where(condition != 0, -value, value)


def _floorfrac(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cycles' floorfrac: (x - floor(x), the cell) (exact in float)."""
    cell = np.floor(x)
    return x - cell, cell.astype(np.int64)


def _lerp(a, b, t):
    """Cycles' mix a + t (b - a), fused as its SIMD kernel's."""
    return fma(t, b - a, a)


def _fade(t):
    """Cycles' SIMD fade (float4, madd): t^3 (t (6 t - 15) + 10), the brackets fused."""
    return (t * t) * (t * fma(t, fma(t, F32(6), F32(-15)), F32(10)))


def _grad(h, f):
    """Cycles' grad1..grad4: the gradient the hash picks, dotted with the offsets ``f``."""
    n = len(f)
    if n == 1:
        h = h & 15
        return _negate_if(F32(1) + (h & 7).astype(F32), h & 8) * f[0]
    if n == 2:
        h = h & 7
        u, v = np.where(h < 4, f[0], f[1]), F32(2) * np.where(h < 4, f[1], f[0])
        return _negate_if(u, h & 1) + _negate_if(v, h & 2)
    if n == 3:
        h = h & 15
        u = np.where(h < 8, f[0], f[1])
        v = np.where(h < 4, f[1], np.where((h == 12) | (h == 14), f[0], f[2]))
        return _negate_if(u, h & 1) + _negate_if(v, h & 2)
    h = h & 31
    u, v, s = np.where(h < 24, f[0], f[1]), np.where(h < 16, f[1], f[2]), np.where(h < 8, f[2], f[3])
    return _negate_if(u, h & 1) + _negate_if(v, h & 2) + _negate_if(s, h & 4)


def perlin(p: np.ndarray) -> np.ndarray:
    """Cycles' perlin_1d..4d of coordinates (..., d): the 1D one scalar (its fade and lerp as its
    compiler fused them), 2D to 4D its SIMD ones: lerps along x, then y, then z; 4D first along w
    (the AVX2 kernel's quad_mix)."""
    p = np.asarray(p, F32)
    d = p.shape[-1]
    parts = [_floorfrac(p[..., i]) for i in range(d)]
    f = [frac for frac, _ in parts]
    cells = [cell for _, cell in parts]
    if d == 1:
        t = f[0]
        u = ((t * t) * t) * fma(t, fma(t, F32(6), F32(-15)), F32(10))
        h = _hash(cells[0]) & 15
        g = _negate_if(F32(1) + (h & 7).astype(F32), h & 8)  # grad1's slope: a = g t
        b = _grad(_hash(cells[0] + 1), [t - F32(1)])
        return fma(g, t, u * fma(-g, t, b))  # mix(a, b, u), a's product fused into both its uses
    fades = [_fade(x) for x in f]

    def corner(*o):
        return _grad(_hash(*(cells[i] + o[i] for i in range(d))), [f[i] - F32(o[i]) for i in range(d)])

    def along_x(*rest):
        if d == 4:  # the AVX2 kernel lerps each x corner pair's two w corners first
            return (_lerp(corner(0, *rest, 0), corner(0, *rest, 1), fades[3]),
                    _lerp(corner(1, *rest, 0), corner(1, *rest, 1), fades[3]))
        return corner(0, *rest), corner(1, *rest)

    def xy(*rest):
        return _lerp(_lerp(*along_x(0, *rest), fades[0]), _lerp(*along_x(1, *rest), fades[0]), fades[1])

    if d == 2:
        return xy()
    return _lerp(xy(0), xy(1), fades[2])


def _wrap(p: np.ndarray) -> np.ndarray:
    """Cycles' snoise_* coordinate wrap: the noise repeats every 1e5 (against float precision),
    and components |p| >= 1e6 (a float's spacing there is 0.0625 .. 1) move half a cell. 1D and
    2D: C's fmodf (exact); 3D and 4D: Cycles' SSE fmod, p - trunc(p x 1e-5) x 1e5 with the
    division compiled as a product by the reciprocal and the last product fused (measured: only
    this matches Cycles beyond |p| = 5e8)."""
    correction = F32(0.5) * (np.abs(p) >= F32(1.0e6)).astype(F32)
    if p.shape[-1] <= 2:
        return np.fmod(p, F32(1.0e5)) + correction
    return fma(-np.trunc(p * F32(1.0e-5)), F32(1.0e5), p) + correction


def snoise(p: np.ndarray) -> np.ndarray:
    """Cycles' snoise_1d..4d: signed noise, about [-1, 1], of coordinates (..., d)."""
    p = np.asarray(p, F32)
    return SCALES[p.shape[-1]] * perlin(_wrap(p))


def _snoise_plus(p: np.ndarray, offset) -> np.ndarray:
    """snoise(p) + offset, its scale fused with the sum (as Cycles' kernel computes it)."""
    p = np.asarray(p, F32)
    return fma(SCALES[p.shape[-1]], perlin(_wrap(p)), offset)


def _octaves(detail) -> tuple[int, np.float32]:
    """The whole octaves after the first (Cycles' float_to_int: truncation) and the fraction left."""
    detail = F32(detail)
    return int(detail), detail - np.floor(detail)


def fbm(p, detail, roughness, lacunarity, normalize: bool) -> np.ndarray:
    """Cycles' noise_fbm: octaves of snoise summed, the last one by Detail's fraction; normalised
    to [0, 1] by the amplitudes' sum where ``normalize``."""
    p = np.asarray(p, F32)
    whole, rmd = _octaves(detail)
    roughness, lacunarity = F32(roughness), F32(lacunarity)
    fscale, amp, maxamp = F32(1), F32(1), F32(0)
    total = np.zeros(p.shape[:-1], F32)
    for _ in range(whole + 1):
        total = fma(snoise(fscale * p), amp, total)
        maxamp = maxamp + amp
        amp = amp * roughness
        fscale = fscale * lacunarity

    def normal(s, m):
        return F32(0.5) * s / m + F32(0.5)

    if rmd != 0:
        total2 = fma(snoise(fscale * p), amp, total)
        if normalize:
            return _lerp(normal(total, maxamp), normal(total2, maxamp + amp), rmd)
        return _lerp(total, total2, rmd)
    return normal(total, maxamp) if normalize else total


def multi_fractal(p, detail, roughness, lacunarity) -> np.ndarray:
    """Cycles' noise_multi_fractal: the product of (1 + amplitude x snoise) over the octaves."""
    p = np.asarray(p, F32)
    whole, rmd = _octaves(detail)
    value, pwr = np.ones(p.shape[:-1], F32), F32(1)
    for _ in range(whole + 1):
        value = value * fma(pwr, snoise(p), F32(1))
        pwr = pwr * F32(roughness)
        p = p * F32(lacunarity)
    if rmd != 0:
        value = value * fma(rmd * pwr, snoise(p), F32(1))
    return value


def hetero_terrain(p, detail, roughness, lacunarity, offset) -> np.ndarray:
    """Cycles' noise_hetero_terrain: each octave's (snoise + Offset) scaled by the value so far."""
    p = np.asarray(p, F32)
    whole, rmd = _octaves(detail)
    offset, pwr = F32(offset), F32(roughness)
    value = _snoise_plus(p, offset)
    p = p * F32(lacunarity)
    for _ in range(whole):
        value = fma(_snoise_plus(p, offset) * pwr, value, value)
        pwr = pwr * F32(roughness)
        p = p * F32(lacunarity)
    if rmd != 0:
        value = fma(rmd, (_snoise_plus(p, offset) * pwr) * value, value)
    return value


def hybrid_multi_fractal(p, detail, roughness, lacunarity, offset, gain) -> np.ndarray:
    """Cycles' noise_hybrid_multi_fractal: octaves weighted by the previous ones (x Gain), while
    the weight stays above 0.001."""
    p = np.asarray(p, F32)
    whole, rmd = _octaves(detail)
    offset, gain, pwr = F32(offset), F32(gain), F32(1)
    value, weight = np.zeros(p.shape[:-1], F32), np.ones(p.shape[:-1], F32)
    for _ in range(whole + 1):
        live = weight > F32(0.001)  # Cycles' loop ends where the weight falls to 0.001
        weight = np.where(live, np.minimum(weight, F32(1)), weight)
        signal = _snoise_plus(p, offset) * pwr
        pwr = pwr * F32(roughness)
        value = np.where(live, fma(weight, signal, value), value)
        weight = np.where(live, weight * (gain * signal), weight)
        p = p * F32(lacunarity)
    if rmd != 0:
        live = weight > F32(0.001)
        signal = _snoise_plus(p, offset) * pwr
        value = np.where(live, fma(rmd * np.minimum(weight, F32(1)), signal, value), value)
    return value


def ridged_multi_fractal(p, detail, roughness, lacunarity, offset, gain) -> np.ndarray:
    """Cycles' noise_ridged_multi_fractal: (Offset - |snoise|)^2 octaves, each weighted by the
    previous signal x Gain (clamped to [0, 1]); Detail's fraction unused, as Cycles'."""
    p = np.asarray(p, F32)
    whole, _ = _octaves(detail)
    offset, gain, pwr = F32(offset), F32(gain), F32(roughness)
    signal = offset - np.abs(snoise(p))
    signal = signal * signal
    value = signal
    for _ in range(whole):
        p = p * F32(lacunarity)
        weight = np.clip(signal * gain, F32(0), F32(1))
        signal = offset - np.abs(snoise(p))
        signal = (signal * signal) * weight
        value = fma(signal, pwr, value)
        pwr = pwr * F32(roughness)
    return value


def fractal(kind: str, p, detail, roughness, lacunarity, offset, gain, normalize: bool) -> np.ndarray:
    """Cycles' noise_select: the fractal of the Noise Texture's type ``kind`` (of ``TYPES``)."""
    if kind == "FBM":
        return fbm(p, detail, roughness, lacunarity, normalize)
    if kind == "MULTIFRACTAL":
        return multi_fractal(p, detail, roughness, lacunarity)
    if kind == "HYBRID_MULTIFRACTAL":
        return hybrid_multi_fractal(p, detail, roughness, lacunarity, offset, gain)
    if kind == "RIDGED_MULTIFRACTAL":
        return ridged_multi_fractal(p, detail, roughness, lacunarity, offset, gain)
    if kind == "HETERO_TERRAIN":
        return hetero_terrain(p, detail, roughness, lacunarity, offset)
    raise ValueError(f"unknown Noise Texture type {kind!r} (one of {', '.join(TYPES)})")


def random_offset(seed: float, dimensions: int) -> np.ndarray:
    """Cycles' random_float*_offset: a seed's offset, each component in [100, 200] (d,)."""
    if dimensions == 1:
        keys = np.array([[seed]], F32)
    else:
        keys = np.array([[seed, float(i)] for i in range(dimensions)], F32)
    return F32(100) + hashing.hash_float(keys) * F32(100)


#: Distortion's sums fused per component as Cycles' kernel computes them (1D: fused; 2D: x only).
_DISTORTION_FUSED = {1: (True,), 2: (True, False), 3: (False,) * 3, 4: (False,) * 4}


def coordinates(dimensions: int, co, w, scale, distortion) -> np.ndarray:
    """The Noise Texture's coordinates (..., d): the Vector and W (Cycles' svm_node_tex_noise
    scales both) of the dimension, displaced by snoise at d seeded offsets x Distortion."""
    co, w, scale = np.asarray(co, F32), np.asarray(w, F32), F32(scale)
    co, w = co * scale, w * scale
    p = {1: w[..., None], 2: co[..., :2], 3: co, 4: np.concatenate([co, w[..., None]], -1)}[dimensions]
    distortion = F32(distortion)
    if distortion == 0:
        return p
    moved = []
    for i, fused in enumerate(_DISTORTION_FUSED[dimensions]):
        s = snoise(p + random_offset(float(i), dimensions))
        moved.append(fma(s, distortion, p[..., i]) if fused else p[..., i] + s * distortion)
    return np.stack(moved, -1)


def noise_texture(dimensions: int, kind: str, co, w, scale=5.0, detail=2.0, roughness=0.5, lacunarity=2.0,
                  offset=0.0, gain=1.0, distortion=0.0,
                  normalize: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The Noise Texture's (Fac, Color) at ``co`` (..., 3) and ``w`` (...): Detail clamped to
    [0, 15] and Roughness to >= 0 (as Cycles' svm_node_tex_noise, by comparisons: NaN gives 0);
    Color (..., 3) is Fac and the fractal at the seeds d and d + 1 (the lower ones distort)."""
    detail, roughness = F32(detail), F32(roughness)
    detail = (detail if detail < 15 else F32(15)) if detail > 0 else F32(0)
    roughness = roughness if roughness > 0 else F32(0)
    p = coordinates(dimensions, co, w, scale, distortion)
    args = (detail, roughness, lacunarity, offset, gain, normalize)
    value = fractal(kind, p, *args)
    channels = [fractal(kind, p + random_offset(float(seed), dimensions), *args)
                for seed in (dimensions, dimensions + 1)]
    return value, np.stack([value, *channels], -1)
