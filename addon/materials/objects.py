"""What the compiled graphs read of an object that the engine computes once per object: Object
Info's Random, as Cycles computes it for an object that is not an instance (learnt from Cycles'
blender/object.cpp ``set_random_id(hash_uint2(hash_string(name), 0))`` and scene/object.cpp's
``random_number = random_id * (1 / 0xFFFFFFFF)``, util/hash.h's hashes: Bob Jenkins' lookup3)."""

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


def _rot(x: int, k: int) -> int:
    return ((x << k) | (x >> (32 - k))) & _MASK


def hash_uint2(kx: int, ky: int) -> int:
    """Cycles' hash_uint2: lookup3's final mix of two words."""
    a = b = c = (0xDEADBEEF + (2 << 2) + 13) & _MASK
    b = (b + ky) & _MASK
    a = (a + kx) & _MASK
    c ^= b
    c = (c - _rot(b, 14)) & _MASK
    a ^= c
    a = (a - _rot(c, 11)) & _MASK
    b ^= a
    b = (b - _rot(a, 25)) & _MASK
    c ^= b
    c = (c - _rot(b, 16)) & _MASK
    a ^= c
    a = (a - _rot(c, 4)) & _MASK
    b ^= a
    b = (b - _rot(a, 14)) & _MASK
    c ^= b
    c = (c - _rot(b, 24)) & _MASK
    return c


def object_random(name: str) -> float:
    """Object Info > Random of the object ``name`` (its name in the file, not an instance), in
    float32 as Cycles computes it."""
    random_id = np.float32(hash_uint2(hash_string(name), 0))
    return float(random_id * (np.float32(1.0) / np.float32(_MASK)))
