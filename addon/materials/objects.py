"""What the compiled graphs read of an object or a mesh that the engine computes once: Object
Info's Random, as Cycles computes it for an object that is not an instance (learnt from Cycles'
blender/object.cpp ``set_random_id(hash_uint2(hash_string(name), 0))`` and scene/object.cpp's
``random_number = random_id * (1 / 0xFFFFFFFF)``), and the hashes of util/hash.h (Bob Jenkins'
lookup3) that addon/materials/mesh_attributes.py's Random Per Island reads too."""

from __future__ import annotations

import numpy as np

_MASK = 0xFFFFFFFF


def hash_string(text: str) -> int:
    """Cycles' hash_string: i = i * 37 + c over the name's bytes (C chars: signed)."""
    i = 0
    for byte in text.encode("utf-8"):
        c = byte - 256 if byte > 127 else byte  # a signed char widened to uint
        i = (i * 37 + c) & _MASK
    return i


def _rot(x: np.ndarray, k: int) -> np.ndarray:
    return (x << np.uint32(k)) | (x >> np.uint32(32 - k))


#: lookup3's final mix: word t ^= word s, then t -= word s rotated left by k, for each (t, s, k).
_FINAL = ((2, 1, 14), (0, 2, 11), (1, 0, 25), (2, 1, 16), (0, 2, 4), (1, 0, 14), (2, 1, 24))


def _final(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """lookup3's final mix of three words (uint32 arrays, wrapping as C's uint): its c."""
    words = [a, b, c]
    with np.errstate(over="ignore"):
        for t, s, k in _FINAL:
            words[t] = (words[t] ^ words[s]) - _rot(words[s], k)
    return words[2]


def _start(words: int, shape) -> np.ndarray:
    return np.full(shape, (0xDEADBEEF + (words << 2) + 13) & _MASK, np.uint32)


def hash_uint(kx) -> np.ndarray:
    """Cycles' hash_uint of each of ``kx`` (uint32 values): lookup3's final mix of one word."""
    kx = np.asarray(kx, np.uint32)
    a, b, c = (_start(1, kx.shape) for _ in range(3))
    with np.errstate(over="ignore"):
        a += kx
    return _final(a, b, c)


def hash_uint2(kx: int, ky: int) -> int:
    """Cycles' hash_uint2: lookup3's final mix of two words."""
    a, b, c = (_start(2, ()) for _ in range(3))
    with np.errstate(over="ignore"):
        b += np.uint32(ky)
        a += np.uint32(kx)
    return int(_final(a, b, c))


def uint_to_float(n) -> np.ndarray:
    """Cycles' uint_to_float_incl: a uint32 hash in [0, 1], float32 (n x (1 / 0xFFFFFFFF))."""
    return np.asarray(n, np.uint32).astype(np.float32) * (np.float32(1.0) / np.float32(_MASK))


def object_random(name: str) -> float:
    """Object Info > Random of the object ``name`` (its name in the file, not an instance), in
    float32 as Cycles computes it."""
    return float(uint_to_float(hash_uint2(hash_string(name), 0)))
