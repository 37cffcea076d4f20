"""The attributes Cycles makes of a mesh for the Geometry node, computed by the engine where a
compiled graph reads them (``codegen.ATTRIBUTE_KINDS``' POINTINESS and RANDOM_PER_ISLAND), from
the arrays the Blender layer reads (addon/blender/extract.py): plain numpy, no ``bpy``.

- ``pointiness``: Cycles' attr_create_pointiness (intern/cycles/blender/mesh.cpp): vertices at one
  place welded, the angle between a vertex's normal and the mean direction of its edges over pi,
  blurred once over the edges' neighbours; per vertex (the triangle interpolates it).
- ``random_per_island``: Cycles' attr_create_random_per_island: the vertices joined along the
  edges (util/disjoint_set.h's union by rank, in the edges' order), each triangle's value the
  hash of its island's root vertex (util/hash.h's hash_uint_to_float); per face.
"""

from __future__ import annotations

import numpy as np

from .objects import hash_uint, uint_to_float

_EPSILON = np.float32(np.finfo(np.float32).eps)  # C's FLT_EPSILON


def weld(positions: np.ndarray) -> np.ndarray:
    """Each vertex's original (Cycles' vert_orig_index): vertices sorted by the sum of their
    coordinates (float32; equal positions by index, descending), each points to the first later one
    whose sum is within 3 FLT_EPSILON and whose squared distance is under FLT_EPSILON, chains
    followed to their end: duplicates point to one vertex, an exact duplicate's the lowest index."""
    co = np.asarray(positions, np.float32).reshape(-1, 3)
    n = len(co)
    sums = (co[:, 0] + co[:, 1]) + co[:, 2]
    order = np.lexsort((-np.arange(n), sums))
    s, c = sums[order], co[order]
    target = np.arange(n)  # in sorted places
    open_ = np.ones(n, bool)  # still looking
    k = 1
    while True:
        i = np.nonzero(open_[: n - k])[0] if k < n else np.empty(0, np.int64)
        if not len(i):
            break
        near = (s[i + k] - s[i]) <= np.float32(3.0) * _EPSILON
        open_[i[~near]] = False  # past the window: no duplicate
        i = i[near]
        d = c[i + k] - c[i]
        same = ((d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) + d[:, 2] * d[:, 2]) < _EPSILON
        target[i[same]] = i[same] + k
        open_[i[same]] = False
        k += 1
    orig = np.empty(n, np.int64)
    orig[order] = order[target]
    while True:  # the very first original of each chain
        nxt = orig[orig]
        if np.array_equal(nxt, orig):
            return orig
        orig = nxt


def _edges(edges: np.ndarray, orig: np.ndarray) -> np.ndarray:
    """The edges between originals, each once (Cycles' EdgeMap: the pair sorted), (m, 2)."""
    e = orig[np.asarray(edges, np.int64).reshape(-1, 2)]
    low, high = e.min(axis=1), e.max(axis=1)
    keys = np.unique(low * len(orig) + high)  # one integer per pair: 30x faster than rows
    return np.stack([keys // len(orig), keys % len(orig)], axis=1)


def pointiness(positions: np.ndarray, vertex_normals: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Geometry > Pointiness per vertex, float32 (Cycles' attr_create_pointiness): 0.5 on a flat
    surface, above on convex corners, below in concave ones."""
    co = np.asarray(positions, np.float32).reshape(-1, 3)
    n = len(co)
    if n == 0:
        return np.zeros(0, np.float32)
    orig = weld(co)
    normal = np.zeros((n, 3), np.float32)
    np.add.at(normal, orig, np.asarray(vertex_normals, np.float32).reshape(-1, 3))
    length = np.sqrt(np.sum(normal * normal, axis=1))
    normal /= np.where(length > 0.0, length, 1.0)[:, None]  # guards: normals summing to nothing
    e = _edges(edges, orig)
    v0, v1 = e[:, 0], e[:, 1]
    direction = co[v1] - co[v0]
    length = np.sqrt(np.sum(direction * direction, axis=1))
    direction /= np.where(length > 0.0, length, 1.0)[:, None]  # safe_normalize: an edge of no length adds 0
    accum = np.zeros((n, 3), np.float32)
    np.add.at(accum, v0, direction)
    np.add.at(accum, v1, -direction)
    counter = np.bincount(v0, minlength=n) + np.bincount(v1, minlength=n)
    raw = np.zeros(n, np.float32)
    roots = np.nonzero((orig == np.arange(n)) & (counter > 0))[0]
    mean = accum[roots] / counter[roots, None].astype(np.float32)
    cosine = np.clip(np.sum(normal[roots] * mean, axis=1), -1.0, 1.0)  # safe_acosf
    raw[roots] = np.arccos(cosine) * np.float32(1.0 / np.pi)
    data = raw.copy()  # one blur over the neighbours (the edges again, each once)
    np.add.at(data, v0, raw[v1])
    np.add.at(data, v1, raw[v0])
    data /= (counter + 1).astype(np.float32)
    return data[orig]


def random_per_island(edges: np.ndarray, vertex_count: int, face_first_vertex: np.ndarray) -> np.ndarray:
    """Geometry > Random Per Island per face, float32 (Cycles' attr_create_random_per_island): the
    vertices joined along ``edges`` in their order as Cycles' DisjointSet joins them (union by rank,
    a tie rooted at the first vertex's root), each face's value the hash of the root of its first
    corner's vertex (``face_first_vertex``). The joining runs edge by edge in Python: ~0.5 s for a
    million edges."""
    parent = list(range(vertex_count))
    rank = [0] * vertex_count
    pairs = np.asarray(edges, np.int64).reshape(-1, 2)
    for a, b in zip(pairs[:, 0].tolist(), pairs[:, 1].tolist()):
        # each root found by halving its path (the roots and ranks are the same however a root
        # is found; Cycles compresses whole paths)
        while parent[a] != a:
            parent[a] = a = parent[parent[a]]
        while parent[b] != b:
            parent[b] = b = parent[parent[b]]
        if a == b:
            continue
        if rank[a] < rank[b]:
            a, b = b, a
        parent[b] = a
        if rank[a] == rank[b]:
            rank[a] += 1
    roots = np.asarray(parent, np.int64)
    while True:  # every vertex's root
        up = roots[roots]
        if np.array_equal(up, roots):
            break
        roots = up
    return uint_to_float(hash_uint(roots[np.asarray(face_first_vertex, np.int64)].astype(np.uint32)))
