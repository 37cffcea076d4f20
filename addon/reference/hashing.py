"""The numpy twin of ``glsl/node_hash.glsl``: Cycles' integer hashes (util/hash.h, Bob Jenkins'
lookup3) of float keys by their bits, mapped to [0, 1], and the White Noise Texture built on them
(``glsl/node_tex_white_noise.glsl``). Vectorised: keys are float32 arrays (..., n); results
float32, bit for bit what the GLSL computes. Pure numpy."""

from __future__ import annotations

import numpy as np

_U32 = np.uint32


def _rot(x: np.ndarray, k: int) -> np.ndarray:
    return (x << _U32(k)) | (x >> _U32(32 - k))


def _mix(a, b, c):
    """lookup3's mix(a, b, c)."""
    a = a - c; a ^= _rot(c, 4); c = c + b  # noqa: E702 (lookup3's layout: three steps a line)
    b = b - a; b ^= _rot(a, 6); a = a + c  # noqa: E702
    c = c - b; c ^= _rot(b, 8); b = b + a  # noqa: E702
    a = a - c; a ^= _rot(c, 16); c = c + b  # noqa: E702
    b = b - a; b ^= _rot(a, 19); a = a + c  # noqa: E702
    c = c - b; c ^= _rot(b, 4); b = b + a  # noqa: E702
    return a, b, c


def _final(a, b, c) -> np.ndarray:
    """lookup3's final(a, b, c): c."""
    c = c ^ b; c = c - _rot(b, 14)  # noqa: E702
    a = a ^ c; a = a - _rot(c, 11)  # noqa: E702
    b = b ^ a; b = b - _rot(a, 25)  # noqa: E702
    c = c ^ b; c = c - _rot(b, 16)  # noqa: E702
    a = a ^ c; a = a - _rot(c, 4)  # noqa: E702
    b = b ^ a; b = b - _rot(a, 14)  # noqa: E702
    c = c ^ b; c = c - _rot(b, 24)  # noqa: E702
    return c


def hash_uint(*keys: np.ndarray) -> np.ndarray:
    """Cycles' hash_uint .. hash_uint4 of one to four uint32 arrays."""
    keys = [np.asarray(k, dtype=_U32) for k in keys]
    n = len(keys)
    seed = np.full(np.broadcast(*keys).shape, 0xDEADBEEF + (n << 2) + 13, dtype=_U32)
    a, b, c = seed.copy(), seed.copy(), seed.copy()
    if n == 4:
        a, b, c = _mix(a + keys[0], b + keys[1], c + keys[2])
        return _final(a + keys[3], b, c)
    state = [a, b, c]
    for i, k in enumerate(keys):
        state[i] = state[i] + k
    return _final(*state)


def to_unit(n: np.ndarray) -> np.ndarray:
    """[0, 2^32 - 1] -> [0, 1] in single precision, as Cycles' uint_to_float_incl."""
    return np.asarray(n, _U32).astype(np.float32) * np.float32(2.0**-32)


def hash_float(k: np.ndarray) -> np.ndarray:
    """Cycles' hash_float*_to_float of float32 keys (..., n), n = 1 .. 4 (the last axis)."""
    bits = np.ascontiguousarray(k, dtype=np.float32).view(_U32)
    return to_unit(hash_uint(*(bits[..., i] for i in range(bits.shape[-1]))))


def hash_float3(k: np.ndarray) -> np.ndarray:
    """Cycles' hash_float*_to_float3 of keys (..., n), n = 1, 2, 3 or 4: (..., 3)."""
    k = np.asarray(k, dtype=np.float32)
    n = k.shape[-1]
    if n == 4:
        keys = [k, k[..., [2, 0, 3, 1]], k[..., [3, 2, 1, 0]]]  # zxwy, wzyx
    else:
        ones = np.ones(k.shape[:-1] + (1,), np.float32)
        keys = [k, np.concatenate([k, ones], -1), np.concatenate([k, 2 * ones], -1)]
    return np.stack([hash_float(key) for key in keys], -1)


def hash_float2(k: np.ndarray) -> np.ndarray:
    """Cycles' hash_float3_to_float2 and hash_float4_to_float2 of keys (..., 3) or (..., 4): the
    key's hash and that of its components rotated (zxy; zxwy), (..., 2)."""
    k = np.asarray(k, dtype=np.float32)
    rotated = k[..., [2, 0, 1]] if k.shape[-1] == 3 else k[..., [2, 0, 3, 1]]
    return np.stack([hash_float(k), hash_float(rotated)], -1)


def hash_float_n(k: np.ndarray) -> np.ndarray:
    """Cycles' hash_float2_to_float2, hash_float3_to_float3, hash_float4_to_float4 of keys
    (..., n): n hashes, the key with 1 (and 2) appended, or the 4D key's components rotated."""
    k = np.asarray(k, dtype=np.float32)
    n = k.shape[-1]
    if n == 3:
        return hash_float3(k)
    if n == 4:
        keys = [k, k[..., [3, 0, 1, 2]], k[..., [2, 3, 0, 1]], k[..., [1, 2, 3, 0]]]  # wxyz, zwxy, yzwx
    else:
        keys = [k, np.concatenate([k, np.ones(k.shape[:-1] + (1,), np.float32)], -1)]
    return np.stack([hash_float(key) for key in keys], -1)


# Cycles 5.0's hashes of integer keys (util/hash.h hash_pcg*d_i, PCG after Jarzynski and Olano,
# "Hash Functions for GPU Rendering", JCGT 2020), which its Voronoi hashes cells by.

#: PCG's multiplier and increment (Cycles' hash_pcg*d_i).
_PCG_MUL, _PCG_ADD = np.int32(1664525), np.int32(1013904223)


def _pcg(v: list[np.ndarray]) -> list[np.ndarray]:
    """Cycles' hash_pcg2d_i / 3d_i / 4d_i of int32 components (wrapping, arithmetic shift)."""
    v = [x * _PCG_MUL + _PCG_ADD for x in v]
    n = len(v)
    # which components stir each one: 2D by the multiplier, 3D and 4D by products of two others
    pairs = {3: ((1, 2), (2, 0), (0, 1)), 4: ((1, 3), (2, 0), (0, 1), (1, 2))}.get(n)
    for half in range(2):
        for i in range(n):
            if n == 2:
                v[i] = v[i] + v[1 - i] * _PCG_MUL
            else:
                a, b = pairs[i]
                v[i] = v[i] + v[a] * v[b]
        if half == 0:
            v = [x ^ (x >> np.int32(16)) for x in v]
    return [x & np.int32(0x7FFFFFFF) for x in v]


def hash_int_n(k: np.ndarray) -> np.ndarray:
    """Cycles' hash_int2_to_float2, hash_int3_to_float3, hash_int4_to_float4 of int keys (..., n):
    (..., n) in [0, 1), the PCG hash's 31 bits times 2^-31."""
    k = np.asarray(k, dtype=np.int32)
    with np.errstate(over="ignore"):
        h = _pcg([k[..., i] for i in range(k.shape[-1])])
    return np.stack(h, -1).astype(np.float32) * np.float32(2.0**-31)


def hash_int3(k: np.ndarray) -> np.ndarray:
    """Cycles' hash_int2_to_float3 (the 3D hash of (x, y, 0)), hash_int3_to_float3 and
    hash_int4_to_float3 (the first three of the 4D hash) of int keys (..., n): (..., 3)."""
    k = np.asarray(k, dtype=np.int32)
    if k.shape[-1] == 2:
        k = np.concatenate([k, np.zeros(k.shape[:-1] + (1,), np.int32)], -1)
    return hash_int_n(k)[..., :3]


def white_noise(dimensions: int, co: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The White Noise Texture's (Value, Color) at coordinates ``co`` (..., 3) and ``w`` (...)."""
    co, w = np.asarray(co, np.float32), np.asarray(w, np.float32)
    key = {1: w[..., None], 2: co[..., :2], 3: co, 4: np.concatenate([co, w[..., None]], -1)}[dimensions]
    return hash_float(key), hash_float3(key)
