"""The ``stray_flux`` record (``harness.compare.stray``): hand-derived values, and its
interval's coverage under photon-like noise by simulation. Kind: physical requirement
on the estimator (an interval must cover the truth as often as it says)."""

from __future__ import annotations

import numpy as np
import pytest

from harness.compare.stray import stray_flux_value


def _maps():
    """A 16 × 16 grey truth: a bright 4 × 4 caustic on a dim floor (W/m²)."""
    truth = np.full((16, 16, 3), 0.5)
    truth[6:10, 6:10] = 20.0
    region = np.zeros((16, 16), bool)
    region[6:10, 6:10] = True
    return truth, region


def test_hand_derived_values():
    """Grey maps: the luminance is the channel value. Truth outside: 240 texels × 0.5 =
    120; inside 16 × 20 = 320; total 440. A method with 1.5× the light outside puts
    180 there: value 180 / 440, baseline 120 / 440, excess 60 / 440."""
    truth, region = _maps()
    method = truth.copy()
    method[~region] *= 1.5
    record = stray_flux_value("receiver0", method, truth, region)
    assert (record.view, record.region, record.metric) == ("receiver0", "outside", "stray_flux")
    assert record.pixels == 240
    assert record.value == pytest.approx(180 / 440)
    assert record.baseline == pytest.approx(120 / 440)
    assert record.excess == pytest.approx(60 / 440)
    assert record.excess_ci95 is None  # no variance given


def test_interval_covers_the_truth_under_poisson_noise():
    """K = 4 seeds of Poisson photon counts (about 25 photons per dim texel and seed,
    1,000 per caustic texel), the reference their mean, the variance of the mean from
    the seeds; the method puts 1.5× the light outside. The 95 % interval covers the
    true excess in 93–97 % of 2,000 repetitions (binomial standard error of the
    coverage 0.49 %: the window is ±4 SE)."""
    truth, region = _maps()
    method = truth.copy()
    method[~region] *= 1.5
    true_excess = 60 / 440
    rng = np.random.default_rng(7)
    photon = 0.02                          # W/m² per photon and texel
    seeds, trials, covered = 4, 2000, 0
    for _ in range(trials):
        counts = rng.poisson(truth[..., :1] / photon, size=(seeds, 16, 16, 1))
        per_seed = np.repeat(counts * photon, 3, axis=-1)
        reference = per_seed.mean(axis=0)
        variance = per_seed.var(axis=0, ddof=1) / seeds
        record = stray_flux_value("receiver0", method, reference, region,
                                  variance=variance, seeds=seeds)
        low, high = record.excess_ci95
        covered += low <= true_excess <= high
    coverage = covered / trials
    print(f"coverage {coverage:.4f}")
    assert 0.93 <= coverage <= 0.97, coverage
