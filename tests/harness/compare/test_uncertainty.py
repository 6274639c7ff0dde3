"""The per-metric intervals of a comparison (``harness.compare.uncertainty``) with the
reference's per-seed images, on simulated photon noise (``photon_noise``).

Kind: **physical requirement** of the statistics: the flux ratio's interval, the
perceptual baselines' noise and where they are scored follow from the noise model,
not from any method's output."""

from __future__ import annotations

import numpy as np
import pytest

from harness.compare.uncertainty import ExcessInputs, metric_excess
from harness.metrics.baselines import WELL_SAMPLED, _seed_noise, photons_per_texel
from harness.metrics.excess import noise_structure
from harness.metrics.scores import structural_similarity
from tests.harness.metrics.photon_noise import (
    CHANNELS,
    caustic_truth,
    reference_of,
    seed_images,
)

SEEDS = 4


def _inputs(maps, *, with_seeds=True, independent_texels=True):
    _, variance = reference_of(maps)
    return ExcessInputs(variance, maps.shape[0], 1.0, 3.0, -3.0, 3.0,
                        seed_estimates=maps if with_seeds else None,
                        independent_texels=independent_texels)


@pytest.mark.physical_requirement
def test_flux_ratio_interval_from_the_seeds_totals():
    """Stratified emission: a region's total is far less noisy than the sum of its
    texels' variances says. A perfect method's flux ratio over the caustic ring (the
    texels above 1.8, about a fifth of the map: over the whole map each seed's total is
    exact, every photon landing in it), 300 trials: with the seeds' region totals the
    interval (t, 3 dof) covers 1 in 93–97.5 % of trials (binomial sd 1.3 %) and the
    mean SE is within 15 % of the ratios' scatter (E[s]/σ = 0.92 at 3 dof, and 300
    trials leave 2.4 % of scatter); the independent-texel SE is more than 1.5× the
    scatter."""
    rng = np.random.default_rng(0)
    plain = caustic_truth(32)
    truth = plain[..., None] * CHANNELS
    mask = plain > 1.8
    ratios, seeds_se, texel_se, covered = [], [], [], []
    for _ in range(300):
        maps = seed_images(rng, plain, seeds=SEEDS, photons=25, model="stratified")
        reference, _ = reference_of(maps)
        with_seeds = metric_excess("flux_ratio", truth, reference, mask, _inputs(maps), maps={})
        plain_texels = metric_excess("flux_ratio", truth, reference, mask,
                                     _inputs(maps, with_seeds=False), maps={})
        ratios.append(with_seeds["excess"])
        seeds_se.append(with_seeds["excess_stderr"])
        texel_se.append(plain_texels["excess_stderr"])
        low, high = with_seeds["excess_ci95"]
        covered.append(low <= 0.0 <= high)
    scatter = np.std(ratios, ddof=1)
    print({"coverage": np.mean(covered), "seeds_se": np.mean(seeds_se) / scatter,
           "texel_se": np.mean(texel_se) / scatter})
    assert 0.93 <= np.mean(covered) <= 0.975
    assert abs(np.mean(seeds_se) / scatter - 1.0) < 0.15
    assert np.mean(texel_se) > 1.5 * scatter


def test_photons_per_texel_recovers_the_count():
    """Known answer: Poisson counts of mean 25 T per seed over 4 seeds: the mean holds
    100 T photons; the estimate's median ratio to it is within 5 % of 1 (its per-texel
    scatter is that of a smoothed 3-dof variance, about 1/√(3 × 28) = 11 %)."""
    rng = np.random.default_rng(1)
    plain = caustic_truth(48)
    reference, variance = reference_of(seed_images(rng, plain, seeds=SEEDS, photons=25,
                                                   model="poisson"))
    n = photons_per_texel(reference, variance)
    assert np.median(n[..., 0] / (100.0 * plain)) == pytest.approx(1.0, abs=0.05)
    # The three channels are carried by the same photons: the same count in each.
    np.testing.assert_allclose(n[..., 1], n[..., 0], rtol=1e-6)


def test_seed_noise_keeps_the_seeds_covariance():
    """The seeds' own noise (noise="seeds"): over 400 draws its per-texel variance is
    the variance of the mean (ratio within 5 %: 400 draws of 6 sign patterns) and its
    lag-1 correlation the seeds' (stratified: −0.25, within 0.05)."""
    rng = np.random.default_rng(2)
    plain = caustic_truth(32)
    maps = seed_images(rng, plain, seeds=SEEDS, photons=25, model="stratified")
    _, variance = reference_of(maps)
    draws = np.stack([_seed_noise(rng, maps) for _ in range(400)])
    assert draws.var(axis=0).sum() / variance.sum() == pytest.approx(1.0, abs=0.05)
    lag1 = noise_structure(draws).correlation[(0, 1)]
    seeds = noise_structure(maps).correlation[(0, 1)]
    assert seeds < -0.15 and lag1 == pytest.approx(seeds, abs=0.05)


def test_perceptual_excess_only_where_texels_are_well_sampled():
    """SSIM over a caustic with about one photon per texel per seed (n ≈ 1.2–4 < 25 in
    the mean): no interval; at 25 per seed and unit (n ≥ 100): an interval."""
    rng = np.random.default_rng(3)
    plain = caustic_truth(32)
    truth = plain[..., None] * CHANNELS
    mask = np.ones(plain.shape, bool)
    for photons, expect in ((1.0 / 3.4, False), (25.0, True)):
        maps = seed_images(rng, plain, seeds=SEEDS, photons=photons, model="poisson")
        reference, variance = reference_of(maps)
        sampled = photons_per_texel(reference, variance).min(axis=-1) >= WELL_SAMPLED
        _, smap = structural_similarity(truth, reference, white=3.0, return_map=True)
        out = metric_excess("ssim", truth, reference, mask, _inputs(maps),
                            maps={"ssim": smap})
        assert bool(out) == expect == bool(sampled.any()), (photons, out)
        if expect:
            assert out["excess_stderr"] > 0 and np.isfinite(out["excess"])


def test_camera_like_view_without_seeds_gets_no_interval():
    """A view whose pixels share noise (independent_texels=False) and no per-seed
    images: no excess for any metric; with the per-seed images, relMSE has one."""
    rng = np.random.default_rng(4)
    plain = caustic_truth(16)
    maps = seed_images(rng, plain, seeds=SEEDS, photons=25, model="poisson")
    reference, _ = reference_of(maps)
    mask = np.ones(plain.shape, bool)
    shared = _inputs(maps, with_seeds=False, independent_texels=False)
    for metric in ("relmse", "flux_ratio"):
        assert metric_excess(metric, reference, reference, mask, shared, maps={}) == {}
    measured = _inputs(maps, independent_texels=False)
    assert "excess" in metric_excess("relmse", reference, reference, mask, measured, maps={})
