"""Automatic exposure: the source report's dynamic exposure ("computed dynamically by
statistically analysing the brightness levels of previous frames"), metered on the GPU and
adapted from frame to frame.

The GPU reduces a frame to a histogram (``glsl/exposure.frag.glsl``, ``passes.ExposurePass``):
BINS bins of log2 luminance over [LOG_MIN, LOG_MAX], each holding the sum of log2 L and the number
of the pixels in it. The frame is first cut into at most BLOCKS x BLOCKS blocks; a block's pixels
fall into the bin of the block's mean log2 L (a 1280 x 720 frame: 5 x 5 pixel blocks; frames up to
256 pixels a side: one pixel per block). The sums stay exact, so the log-average is the frame's
own; the percentiles are those of the blocks. Everything after the read-back of those BINS
pairs is here, with ``histogram()``, the numpy twin of the GPU reduction:

* ``meter``: the exposure (stops) that brings the frame's key to ``key`` - Reinhard et al. 2002's
  a / L_w, with L_w the log-average luminance (their eq. 1) of all pixels or, for HISTOGRAM, of
  the pixels between the ``low`` and ``high`` percentiles (the darkest and brightest ignored, as
  production engines do); plus compensation, within [min_stops, max_stops].
* ``adapt``: eye adaptation between frames, exponential in stops with one time constant for a
  scene that gets brighter and another for one that gets darker.
* ``Track``: the exposure carried from frame to frame of an animation (a render job, or a frame
  sequence the CLI holds open): deterministic - the same frame range renders the same images.
"""

from __future__ import annotations

import contextlib
import math
import threading
from dataclasses import dataclass

import numpy as np

#: Rec. 709 luminance of scene-linear RGB.
LUMA = (0.2126, 0.7152, 0.0722)
BINS = 64
LOG_MIN, LOG_MAX = -16.0, 16.0  # log2 luminance range; luminance outside it counts as its end
BLOCKS = 256  # blocks per side at most


@dataclass(frozen=True)
class AutoExposure:
    """How a frame's exposure is chosen (Render panel, Exposure: Automatic)."""

    method: str = "HISTOGRAM"  # or LOG_AVERAGE
    key: float = 0.18  # the luminance the frame's average is brought to (Reinhard's middle grey)
    low: float = 0.10  # HISTOGRAM: fraction of the darkest pixels ignored
    high: float = 0.90  # HISTOGRAM: pixels above this fraction (the brightest) ignored
    compensation: float = 0.0  # stops added to the metered exposure
    min_stops: float = -16.0
    max_stops: float = 16.0
    brighter: float = 0.5  # s: time constant when the scene gets brighter (exposure goes down)
    darker: float = 2.0  # s: time constant when it gets darker (exposure goes up)


def block_size(width: int, height: int) -> int:
    """Pixels per block side: the frame in at most BLOCKS x BLOCKS blocks."""
    return max(math.ceil(max(width, height) / BLOCKS), 1)


def histogram(radiance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Numpy twin of the GPU reduction: (sum of log2 L, pixel count) per bin of an (h, w, 4)
    scene-linear RGBA frame. Pixels with alpha 0 (a transparent film's background) count not."""
    h, w = radiance.shape[:2]
    k = block_size(w, h)
    lum = np.asarray(radiance[..., :3], np.float64) @ np.array(LUMA)
    logs = np.log2(np.clip(lum, 2.0 ** LOG_MIN, 2.0 ** LOG_MAX))
    weight = (radiance[..., 3] > 0.0).astype(np.float64)
    bh, bw = math.ceil(h / k), math.ceil(w / k)
    pad = ((0, bh * k - h), (0, bw * k - w))
    block_sum = np.pad(logs * weight, pad).reshape(bh, k, bw, k).sum(axis=(1, 3))
    block_count = np.pad(weight, pad).reshape(bh, k, bw, k).sum(axis=(1, 3))
    filled = block_count > 0
    mean = np.where(filled, block_sum / np.maximum(block_count, 1.0), LOG_MIN)
    bins = bin_of(mean)
    sums = np.bincount(bins[filled], block_sum[filled], BINS)
    counts = np.bincount(bins[filled], block_count[filled], BINS)
    return sums, counts


def bin_of(log_luminance):
    """The bin of log2 luminance values (as exposure.frag.glsl computes it)."""
    scaled = (np.asarray(log_luminance) - LOG_MIN) * (BINS / (LOG_MAX - LOG_MIN))
    return np.clip(np.floor(scaled), 0, BINS - 1).astype(np.int64)


def mean_log(sums: np.ndarray, counts: np.ndarray, auto: AutoExposure) -> float | None:
    """The frame's mean log2 luminance as ``auto.method`` measures it; None for an empty frame."""
    sums, counts = np.asarray(sums, np.float64), np.asarray(counts, np.float64)
    total = counts.sum()
    if total <= 0.0:
        return None
    if auto.method == "LOG_AVERAGE":
        return float(sums.sum() / total)
    # the pixels ranked from dark to bright; keep those between the low and high fractions
    lo, hi = sorted((min(max(auto.low, 0.0), 1.0), min(max(auto.high, 0.0), 1.0)))
    before = np.concatenate([[0.0], np.cumsum(counts)[:-1]])
    kept = np.clip(np.minimum(before + counts, hi * total) - np.maximum(before, lo * total), 0.0, None)
    if kept.sum() <= 0.0:  # low == high: the pixel at that rank
        kept = ((before <= lo * total) & (lo * total <= before + counts) & (counts > 0)).astype(float)
    bin_mean = np.divide(sums, counts, out=np.zeros_like(sums), where=counts > 0)
    return float((kept * bin_mean).sum() / kept.sum())


def meter(sums: np.ndarray, counts: np.ndarray, auto: AutoExposure) -> float | None:
    """The exposure in stops (radiance x 2^stops) that brings the frame's average to ``auto.key``
    (Reinhard et al. 2002: a / L_w), compensated and limited; None for an empty frame."""
    mean = mean_log(sums, counts, auto)
    if mean is None:
        return None
    stops = math.log2(auto.key) - mean + auto.compensation
    return min(max(stops, auto.min_stops), auto.max_stops)


def adapt(previous: float | None, target: float, dt: float, auto: AutoExposure) -> float:
    """The exposure ``dt`` seconds after ``previous`` towards ``target``: the difference decays
    as exp(-dt / tau), tau = ``auto.brighter`` when the scene got brighter (target below the
    previous exposure), ``auto.darker`` when it got darker. No previous frame: the target."""
    if previous is None or dt <= 0.0:
        return target if previous is None else previous
    tau = auto.brighter if target < previous else auto.darker
    if tau <= 0.0:
        return target
    return target + (previous - target) * math.exp(-dt / tau)


class Track:
    """Exposures carried from frame to frame: one per key (scene, view layer, view, model).

    Blender renders an animation as one job of many frames: within it, frame f adapts from the
    frame rendered before it (dt = frames apart / fps); a job's first frame, and every still,
    uses the converged (metered) value. ``sequence()`` makes consecutive single-frame renders
    (the CLI's ``--frames``) one sequence in the same way."""

    def __init__(self):
        self._lock = threading.Lock()
        self._state: dict[tuple, tuple[float, float]] = {}  # key -> (frame, stops)
        self._held = 0

    def job_started(self) -> None:
        with self._lock:
            if not self._held:
                self._state.clear()

    @property
    def held(self) -> bool:
        return self._held > 0

    @contextlib.contextmanager
    def sequence(self):
        with self._lock:
            self._held += 1
            self._state.clear()
        try:
            yield self
        finally:
            with self._lock:
                self._held -= 1
                self._state.clear()

    def step(self, key: tuple, frame: float, fps: float, target: float, auto: AutoExposure,
             animating: bool) -> float:
        """The exposure of ``frame`` for ``key`` given its metered ``target``."""
        with self._lock:
            previous = self._state.get(key) if animating else None
            if previous is not None and frame > previous[0]:
                stops = adapt(previous[1], target, (frame - previous[0]) / fps, auto)
            else:
                stops = target
            if animating:
                self._state[key] = (frame, stops)
            return stops


TRACK = Track()
