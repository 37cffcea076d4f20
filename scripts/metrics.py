"""Image error metrics for comparisons against a reference (pure numpy + flip-evaluator).

Images are (H, W, 3+) float arrays of scene-linear radiance. FLIP (Andersson et al. 2020, NVIDIA's
flip-evaluator) in its HDR mode judges what a viewer would notice; the relative and absolute
errors are the plain numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Reference pixels dimmer than this fraction of the frame's maximum are not "lit": relative
#: errors there are noise over darkness, not shading.
LIT_FRACTION = 0.02


@dataclass(frozen=True)
class Errors:
    flip: float  # mean HDR-FLIP
    mean_relative: float  # mean |test - ref| / ref over lit pixels (luminance)
    max_abs: float  # max |test - ref| over all pixels and channels
    lit_pixels: int


def luminance(image: np.ndarray) -> np.ndarray:
    rgb = np.asarray(image, np.float64)[..., :3]
    return rgb @ np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 / sRGB primaries


def lit_mask(reference: np.ndarray) -> np.ndarray:
    lum = luminance(reference)
    return lum > LIT_FRACTION * max(float(lum.max()), 1e-30)


def flip_error(reference: np.ndarray, test: np.ndarray) -> tuple[float, np.ndarray]:
    """(mean HDR-FLIP, per-pixel error map in [0, 1]) of ``test`` against ``reference``."""
    import flip_evaluator

    ref = np.ascontiguousarray(np.maximum(np.asarray(reference, np.float32)[..., :3], 0.0))
    tst = np.ascontiguousarray(np.maximum(np.asarray(test, np.float32)[..., :3], 0.0))
    error_map, mean, _ = flip_evaluator.evaluate(ref, tst, "HDR", applyMagma=False)
    return float(mean), np.asarray(error_map, np.float32)


def errors(reference: np.ndarray, test: np.ndarray, with_flip: bool = True) -> Errors:
    ref = np.asarray(reference, np.float64)[..., :3]
    tst = np.asarray(test, np.float64)[..., :3]
    if ref.shape != tst.shape:
        raise ValueError(f"image sizes differ: reference {ref.shape[:2]}, test {tst.shape[:2]}")
    lit = lit_mask(ref)
    ref_l, tst_l = luminance(ref), luminance(tst)
    rel = np.abs(tst_l[lit] - ref_l[lit]) / ref_l[lit] if lit.any() else np.zeros(1)
    flip = flip_error(ref, tst)[0] if with_flip else float("nan")
    return Errors(flip=flip, mean_relative=float(rel.mean()), max_abs=float(np.abs(tst - ref).max()),
                  lit_pixels=int(lit.sum()))
