"""Reference noise from K independent seeds.

With K seed estimates x_1..x_K of a texel, the reference is their mean and its
variance is the variance *of the mean*, s^2 / K with s^2 the unbiased sample
variance (K - 1 in the denominator).

Caustic region: :func:`renderers.results.caustic_region` of this reference's caustic
map (luminance above 0.1 x its 99.5th percentile), the rule of the region a comparison
scores; the comparison applies it to the independent reference instead
(``harness.compare.regions.scene_caustic_region``), which is not traced yet when this
reference's noise decides when to stop.

Relative noise, per RGB channel c: the root mean square, over the region's texels i
where channel c is lit (mean_ic > 0), of the texel's standard error over its value,

    noise_c = sqrt(mean_i var_ic / mean_ic^2),

the relative error a per-channel comparison sees in the reference. The scalar
relative noise is the largest channel's, so a target on it holds for every channel.
Each channel is measured on its own: a white light's three channels are carried by
the same photons and are perfectly correlated, so a noise of the channel sum,
sqrt(sum_c var_ic) / sum_c mean_ic = sqrt(3 v) / (3 m), would report 1 / sqrt(3) of
each channel's sqrt(v) / m.
"""

from __future__ import annotations

import numpy as np

from renderers.results import caustic_region

__all__ = ["caustic_region", "relative_noise", "relative_noise_per_channel",
           "seed_statistics"]


def seed_statistics(estimates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and variance of the mean over axis 0 (K >= 1 seeds; K = 1 gives inf)."""
    estimates = np.asarray(estimates, dtype=np.float64)
    k = estimates.shape[0]
    mean = estimates.mean(axis=0)
    if k < 2:
        return mean, np.full_like(mean, np.inf)
    return mean, estimates.var(axis=0, ddof=1) / k


def relative_noise_per_channel(mean: np.ndarray, variance: np.ndarray,
                               region: np.ndarray) -> np.ndarray:
    """(3,) RMS relative standard error of each channel over ``region`` (see the module
    docstring); ``mean`` and ``variance`` (H, W, 3), ``region`` (H, W) bool. A channel
    lit nowhere in the region (or an empty region) gives nan."""
    m = np.asarray(mean, dtype=np.float64)[region]
    v = np.asarray(variance, dtype=np.float64)[region]
    out = np.full(3, np.nan)
    for c in range(3):
        lit = m[:, c] > 0
        if lit.any():
            out[c] = float(np.sqrt(np.mean(v[lit, c] / m[lit, c] ** 2)))
    return out


def relative_noise(mean: np.ndarray, variance: np.ndarray, region: np.ndarray) -> float:
    """The largest channel's RMS relative standard error over ``region``
    (:func:`relative_noise_per_channel`); nan when no channel is lit there."""
    per_channel = relative_noise_per_channel(mean, variance, region)
    known = per_channel[~np.isnan(per_channel)]
    return float(known.max()) if known.size else float("nan")
