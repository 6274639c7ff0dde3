"""Reference noise from K independent seeds.

With K seed estimates x_1..x_K of a texel, the reference is their mean and its
variance is the variance *of the mean*, s^2 / K with s^2 the unbiased sample
variance (K - 1 in the denominator).

Caustic region: texels whose chain-only irradiance (no direct light) exceeds its
mean over the texels it reaches at all -- where the object concentrates light
(concentration > 1). Relative noise: the root mean square, over that region, of
each texel's standard error divided by its value, on the channel sum:
sqrt(mean_i (sum_c var_ic) / (sum_c mean_ic)^2).
"""

from __future__ import annotations

import numpy as np

__all__ = ["caustic_region", "relative_noise", "seed_statistics"]


def seed_statistics(estimates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and variance of the mean over axis 0 (K >= 1 seeds; K = 1 gives inf)."""
    estimates = np.asarray(estimates, dtype=np.float64)
    k = estimates.shape[0]
    mean = estimates.mean(axis=0)
    if k < 2:
        return mean, np.full_like(mean, np.inf)
    return mean, estimates.var(axis=0, ddof=1) / k


def caustic_region(caustic_mean: np.ndarray) -> np.ndarray:
    """Boolean (H, W) mask of concentrated caustic light (see module docstring)."""
    c = np.asarray(caustic_mean, dtype=np.float64).sum(axis=-1)
    lit = c > 0
    if not lit.any():
        return lit
    return c > c[lit].mean()


def relative_noise(mean: np.ndarray, variance: np.ndarray, region: np.ndarray) -> float:
    """RMS relative standard error over ``region`` (nan when the region is empty)."""
    if not region.any():
        return float("nan")
    m = np.asarray(mean, dtype=np.float64).sum(axis=-1)[region]
    v = np.asarray(variance, dtype=np.float64).sum(axis=-1)[region]
    return float(np.sqrt(np.mean(v / np.maximum(m, 1e-300) ** 2)))
