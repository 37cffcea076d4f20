"""The numpy twin of ``glsl/node_tex_gabor.glsl``: the Gabor Texture as Cycles' svm_node_tex_gabor
(kernel/svm/gabor.h) computes it, in float32, operation for operation (the same hashes of the same
keys, the impulses and cells summed in the same order). Vectorised over points: coordinates
(N, 3), the node's values scalars; every impulse of every neighbouring cell at once, (N, cells,
impulses). Pure numpy."""

from __future__ import annotations

import numpy as np

from .hashing import hash_float, hash_float2, hash_float3

_F32 = np.float32
IMPULSES = 8  # per cell (Cycles' IMPULSES_COUNT)
_PI = _F32(np.pi)  # M_PI_F
_TWO_PI = _F32(2.0) * _PI


def _offsets(dims: int) -> np.ndarray:
    """The neighbourhood's cell offsets in Cycles' loop order (the last axis slowest), (3^dims, dims)."""
    grid = np.stack(np.meshgrid(*([np.arange(-1, 2)] * dims), indexing="ij"), -1).reshape(-1, dims)
    return grid[:, ::-1].astype(_F32)


def _keys(cells: np.ndarray, k: int) -> np.ndarray:
    """The hash keys (cell, 3i + k) of every impulse i: (N, cells, impulses, dims + 1)."""
    seeds = (np.arange(IMPULSES) * 3 + k).astype(_F32)
    shape = cells.shape[:2] + (IMPULSES,)
    cell = np.broadcast_to(cells[:, :, None, :], shape + cells.shape[-1:])
    return np.concatenate([cell, np.broadcast_to(seeds[None, None, :, None], shape + (1,))], -1)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cycles' dot: the products summed from x on."""
    out = a[..., 0] * b[..., 0]
    for i in range(1, a.shape[-1]):
        out = out + a[..., i] * b[..., i]
    return out


def _kernel(distance_squared: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Cycles' compute_*_gabor_kernel: the Hann-windowed unit Gaussian times the phasor, (..., 2)."""
    hann = _F32(0.5) + _F32(0.5) * np.cos(_PI * distance_squared)
    windowed = np.exp(-_PI * distance_squared) * hann
    return np.stack([windowed * np.cos(angle), windowed * np.sin(angle)], -1)


def _orientation_3d(base: np.ndarray, isotropy: np.float32, keys: np.ndarray) -> np.ndarray:
    """Cycles' compute_3d_orientation: the base's spherical angles turned by random ones."""
    if isotropy == 0.0:
        return np.broadcast_to(base, keys.shape[:-1] + (3,))
    inclination = np.arccos(base[2])
    sign = _F32(-1.0) if base[1] < 0.0 else _F32(1.0)
    xy = np.sqrt(base[0] * base[0] + base[1] * base[1])
    # a base along z: azimuth 0 (guards: Cycles' 0 / 0 there, NaN; as the GLSL)
    azimuth = sign * np.arccos(base[0] / xy) if xy > 0.0 else _F32(0.0)
    angles = hash_float2(keys) * _PI
    inclination = inclination + angles[..., 0] * isotropy
    azimuth = azimuth + angles[..., 1] * isotropy
    sine = np.sin(inclination)
    return np.stack([sine * np.cos(azimuth), sine * np.sin(azimuth), np.cos(inclination)], -1)


def _noise(coordinates: np.ndarray, frequency: np.float32, isotropy: np.float32, orientation) -> np.ndarray:
    """Cycles' compute_2d_gabor_noise / compute_3d_gabor_noise: the summed phasor, (N, 2)."""
    dims = coordinates.shape[-1]
    cell_position = np.floor(coordinates)
    local = coordinates - cell_position
    offsets = _offsets(dims)
    cells = cell_position[:, None, :] + offsets  # (N, cells, dims)
    position = local[:, None, :] - offsets
    center = hash_float2(_keys(cells, 1)) if dims == 2 else hash_float3(_keys(cells, 1))
    in_kernel = position[:, :, None, :] - center  # (N, cells, impulses, dims)
    distance_squared = _dot(in_kernel, in_kernel)
    if dims == 2:  # a random orientation across pi, blended in by the isotropy
        random = (hash_float(_keys(cells, 0)) - _F32(0.5)) * _PI
        angle = orientation + random * isotropy
        frequency_vector = np.stack([frequency * np.cos(angle), frequency * np.sin(angle)], -1)
    else:
        frequency_vector = frequency * _orientation_3d(orientation, isotropy, _keys(cells, 0))
    weight = np.where(hash_float(_keys(cells, 2)) < 0.5, _F32(-1.0), _F32(1.0))
    kernel = _kernel(distance_squared, _TWO_PI * _dot(in_kernel, frequency_vector))
    # impulses beyond the unit radius add nothing (Cycles skips them: the windowed kernel is 0)
    terms = np.where((distance_squared < 1.0)[..., None], weight[..., None] * kernel, _F32(0.0))
    total = np.zeros((len(coordinates), 2), _F32)
    for c in range(terms.shape[1]):  # each cell's impulses summed in order, then the cells in order
        cell_sum = np.zeros((len(coordinates), 2), _F32)
        for i in range(IMPULSES):
            cell_sum = cell_sum + terms[:, c, i]
        total = total + cell_sum
    return total


def gabor(gabor_type: str, co: np.ndarray, scale: float, frequency: float, anisotropy: float,
          orientation) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Gabor Texture's (Value, Phase, Intensity) at ``co`` (N, 3): ``gabor_type`` "2D" (the
    orientation an angle) or "3D" (a vector, normalised here); each (N,)."""
    co = np.asarray(co, _F32).reshape(-1, 3)
    scaled = co * _F32(scale)
    isotropy = _F32(1.0) - np.clip(_F32(anisotropy), _F32(0.0), _F32(1.0))
    frequency = max(_F32(0.001), _F32(frequency))
    if gabor_type == "2D":
        phasor = _noise(scaled[:, :2], frequency, isotropy, _F32(orientation))
        deviation = np.sqrt(_F32(IMPULSES * 0.5) * _F32(0.25))
    else:
        vector = np.asarray(orientation, _F32)
        length = np.sqrt(_dot(vector, vector))
        # a zero orientation: the x axis (guards: Cycles' 0 / 0, NaN; as the GLSL)
        direction = vector / length if length > 0.0 else np.array([1.0, 0.0, 0.0], _F32)
        phasor = _noise(scaled, frequency, isotropy, direction)
        deviation = np.sqrt(_F32(IMPULSES * 0.5) * (_F32(1.0) / (_F32(4.0) * _F32(np.sqrt(2.0)))))
    normalization = _F32(6.0) * deviation
    value = (phasor[:, 1] / normalization) * _F32(0.5) + _F32(0.5)
    phase = (np.arctan2(phasor[:, 1], phasor[:, 0]) + _PI) / _TWO_PI
    intensity = np.sqrt(_dot(phasor, phasor)) / normalization
    return value, phase, intensity
