"""Photon-like reference noise for the statistics' calibration tests.

A reference of K seeds is simulated the way the photon tracer makes one: each seed
deposits photons in the texel they land in (nearest texel), and its estimate of a
texel is the photons' summed weight over the expected weight per unit of the image,
so every seed estimates the truth T without bias. Three noise models:

* ``poisson``: independent texels, a Poisson count of mean λ_i = photons · T_i per
  seed, each photon of weight 1 / photons (relative noise 1 / √(K λ_i) of the mean,
  third central moment of the mean T_i / (K λ_i)² · T_i, i.e. skew 1 / √(K λ_i));
* ``compound``: the same counts, each photon's weight drawn from a gamma distribution
  of mean 1 and shape ``shape`` (weighted photons: Fresnel, absorption, a mixture pdf
  over targets), so the variance per photon is E[w²] = 1 + 1 / shape times the
  Poisson one and the third moment E[w³] = (1 + 1/shape)(1 + 2/shape) times;
* ``stratified``: a fixed number N = ⌊photons · ΣT⌋ of photons per seed, emitted from
  an m × m jittered grid of strata of the unit square (m² = N, as
  ``renderers.mitsuba.emission`` stratifies one launch) and placed by the inverse of
  the image's own cumulative distribution (rows, then the column within the row), so
  neighbouring strata land in neighbouring texels: the counts of neighbouring texels
  anticorrelate, and the image's total is nearly exact.

All channels share the photons (white light): the seed images are the luminance-like
map times the channel ratios 1 : 0.8 : 0.6.
"""

from __future__ import annotations

import numpy as np

#: Channel ratios of the simulated light (one photon carries all three).
CHANNELS = np.array([1.0, 0.8, 0.6])


def caustic_truth(n: int = 48) -> np.ndarray:
    """A caustic-like (n, n) map: a floor of 1 with a bright ring up to 3 and a
    gradient, so that texels carry between 1 and about 3.4 units (relative noise within
    a factor √3.4 of the dimmest texel's)."""
    y, x = (np.mgrid[0:n, 0:n] + 0.5) / n
    radius = np.hypot(x - 0.5, y - 0.47)
    ring = 2.0 * np.exp(-((radius - 0.28) / 0.06) ** 2)
    return 1.0 + ring + 0.4 * x


def seed_images(rng, truth: np.ndarray, *, seeds: int, photons: float, model: str,
                shape: float = 2.0) -> np.ndarray:
    """(K, H, W, 3) per-seed estimates of ``truth`` (H, W) under ``model`` (module
    docstring); ``photons``: expected photons per seed per unit of the truth."""
    out = np.empty((seeds, *truth.shape))
    for k in range(seeds):
        if model in ("poisson", "compound"):
            counts = rng.poisson(photons * truth)
            if model == "poisson":
                out[k] = counts / photons
            else:
                # A sum of n gamma(shape, 1/shape) weights is gamma(n·shape, 1/shape).
                out[k] = rng.gamma(np.maximum(counts * shape, 1e-300), 1.0 / shape) / photons
                out[k][counts == 0] = 0.0
        elif model == "gaussian":
            out[k] = truth + np.sqrt(truth / photons) * rng.standard_normal(truth.shape)
        elif model == "stratified":
            out[k] = _stratified(rng, truth, photons)
        else:
            raise ValueError(f"unknown noise model {model!r}")
    return out[..., None] * CHANNELS


def _stratified(rng, truth: np.ndarray, photons: float) -> np.ndarray:
    """One seed's estimate from jittered-grid strata placed by the inverse CDF."""
    h, w = truth.shape
    total = truth.sum()
    m = int(np.sqrt(photons * total))
    n = m * m
    i, j = np.divmod(np.arange(n), m)
    u1 = (i + rng.random(n)) / m
    u2 = (j + rng.random(n)) / m
    rows = np.concatenate([[0.0], np.cumsum(truth.sum(axis=1))]) / total
    row = np.clip(np.searchsorted(rows, u1, side="right") - 1, 0, h - 1)
    within = np.cumsum(truth, axis=1) / truth.sum(axis=1, keepdims=True)  # (H, W)
    # Row r's conditional CDF shifted to (r, r + 1]: one increasing array, so the column
    # is the count of row r's CDF values at or below u2, by one binary search.
    shifted = (np.arange(h)[:, None] + within).ravel()
    col = np.minimum(np.searchsorted(shifted, row + u2, side="right") - row * w, w - 1)
    counts = np.bincount(row * w + col, minlength=h * w).reshape(h, w)
    return counts * (total / n)


def reference_of(seed_maps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The K-seed reference: mean and unbiased variance of the mean."""
    k = seed_maps.shape[0]
    return seed_maps.mean(axis=0), seed_maps.var(axis=0, ddof=1) / k
