"""The reference's relative noise: per RGB channel, over the region the comparison
scores.

Synthetic K-seed estimates with known statistics; no tracing.
"""

from __future__ import annotations

import numpy as np

from harness.compare.regions import caustic_region as scored_region
from renderers.mitsuba.noise import (
    caustic_region,
    relative_noise,
    relative_noise_per_channel,
    seed_statistics,
)

K = 4


def _seeds(rng, *, channels=(1.0, 1.0, 1.0), shape=(24, 24)) -> np.ndarray:
    """K seed estimates of a caustic blob (texel means 0.05 .. 5), each channel the
    same photons' value times ``channels`` (one emitter: the channels of a texel are
    perfectly correlated), with 10 % relative noise per seed."""
    y, x = np.mgrid[: shape[0], : shape[1]]
    blob = 0.05 + 5.0 * np.exp(-((x - 12) ** 2 + (y - 12) ** 2) / 20.0)
    draws = blob * (1.0 + 0.1 * rng.standard_normal((K, *shape)))
    return draws[..., None] * np.asarray(channels, float)


def _summed_noise(mean, variance, region) -> float:
    """The old measure: sqrt(mean_i (sum_c var_ic) / (sum_c mean_ic)^2), the channel
    sum's variances added as if the channels were independent."""
    m, v = mean.sum(axis=-1)[region], variance.sum(axis=-1)[region]
    return float(np.sqrt(np.mean(v / m**2)))


def test_a_white_lights_channel_noise_is_sqrt3_times_the_summed_measure():
    """Derivation: a white light's channels carry the same photons, x_ic = x_i for
    every c, so var_ic = v_i and mean_ic = m_i. The summed measure divides
    sqrt(sum_c var_ic) = sqrt(3 v_i) by sum_c mean_ic = 3 m_i: sqrt(v_i) / (sqrt(3) m_i),
    while each channel's own relative error is sqrt(v_i) / m_i; the RMS over the region
    keeps the factor. So per channel = sqrt(3) x summed (to float rounding), and the
    scalar is that same value (all channels equal)."""
    mean, variance = seed_statistics(_seeds(np.random.default_rng(1)))
    region = caustic_region(mean)
    assert 20 < region.sum() < mean.shape[0] * mean.shape[1]
    per_channel = relative_noise_per_channel(mean, variance, region)
    np.testing.assert_allclose(per_channel, np.sqrt(3) * _summed_noise(mean, variance, region),
                               rtol=1e-12)
    assert relative_noise(mean, variance, region) == per_channel.max()


def test_the_scalar_noise_is_the_noisiest_channel():
    """Channels with independent noise (a dispersion pass per channel): the scalar is
    the largest channel's RMS relative error, so a target on it holds for every
    channel; a channel lit nowhere in the region (a red light's green and blue) is nan
    and left out of the maximum."""
    rng = np.random.default_rng(2)
    seeds = np.concatenate([_seeds(rng, channels=(1.0,)) for _ in range(3)], axis=-1)
    seeds[..., 2] = seeds[..., 0] + 3.0 * (seeds[..., 2] - seeds[..., 0])  # blue noisier
    mean, variance = seed_statistics(seeds)
    region = caustic_region(mean)
    per_channel = relative_noise_per_channel(mean, variance, region)
    assert per_channel[2] > 2 * per_channel[0]
    assert relative_noise(mean, variance, region) == per_channel[2]
    red_mean, red_var = seed_statistics(_seeds(rng, channels=(1.0, 0.0, 0.0)))
    red = relative_noise_per_channel(red_mean, red_var, caustic_region(red_mean))
    assert np.isfinite(red[0]) and np.isnan(red[1:]).all()
    assert relative_noise(red_mean, red_var, caustic_region(red_mean)) == red[0]


def test_the_noise_region_is_the_scored_caustic_region():
    """The reference measures its noise over the texels the comparison scores:
    luminance above 0.1 x its 99.5th percentile, the same mask as
    ``harness.compare.regions.caustic_region``, not the old rule (channel sum above
    its mean over lit texels), which on this blob keeps a different set of texels."""
    mean = seed_statistics(_seeds(np.random.default_rng(3), channels=(1.0, 0.8, 0.3)))[0]
    region = caustic_region(mean)
    np.testing.assert_array_equal(region, scored_region(mean))
    total = mean.sum(axis=-1)
    old = total > total[total > 0].mean()
    assert region.sum() != old.sum()
