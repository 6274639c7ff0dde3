"""False-failure rates of the per-texel test (``harness.checks.ztest``) measured by
simulation. Kind: **physical requirement** of the statistics: under pure Gaussian
noise of the stated variance, estimated from K seeds, the family-wise rule must fail
at its nominal level. A family-wise level of 5 % on a 16 x 16 x 3 image makes the
rate measurable: over 2000 seeded trials its binomial sd is 0.5 %, so "within 2x of
nominal" (2.5-10 %) is a 5-sd band; the old normal-quantile rule misses it by far."""

from __future__ import annotations

import numpy as np
import pytest

from harness.checks.ztest import effective_tests, welch_degrees_of_freedom, z_test

SHAPE = (16, 16, 3)
LEVEL = 0.05
TRIALS = 2000
RATIO = 4.0  # reference photons / test photons (the golden's 16 seeds vs 4)


def _draw(rng, sd, seeds, rho):
    """A K-seed mean around 10 with standard error ``sd`` and its variance estimate
    (χ²_{K−1} / (K − 1), independent of the mean); channels identical (ρ = 1) or
    independent (ρ = 0)."""
    shape = SHAPE[:2] + ((1,) if rho == 1.0 else (3,))
    mean = 10.0 + sd * rng.standard_normal(shape)
    var = sd**2 * rng.chisquare(seeds - 1, shape) / (seeds - 1)
    return np.broadcast_to(mean, SHAPE), np.broadcast_to(var, SHAPE)


def _rates(ref_seeds, *, rho, test_seeds=None, rule="max", seeds_known=True, seed=0):
    rng = np.random.default_rng(seed)
    family = glob = 0
    for _ in range(TRIALS):
        reference, var_ref = _draw(rng, 0.1, ref_seeds, rho)
        test, var_test = _draw(rng, 0.1 * np.sqrt(RATIO), test_seeds or ref_seeds, rho)
        r = z_test(test, reference, var_ref, test_photons=1.0, reference_photons=RATIO,
                   test_variance=var_test if test_seeds else None, significance=LEVEL,
                   reference_seeds=ref_seeds if seeds_known else None,
                   test_seeds=test_seeds if seeds_known else None,
                   channel_correlation=rho, variance_rule=rule)
        family += not r.family_wise_passed
        glob += r.global_p_value <= LEVEL
    rates = {"family_wise": family / TRIALS, "global": glob / TRIALS}
    print(ref_seeds, test_seeds, rho, rule, rates)
    return rates


@pytest.mark.physical_requirement
@pytest.mark.parametrize("seeds", [4, 16])
@pytest.mark.parametrize("rho", [1.0, 0.0])
def test_t_quantiles_hold_the_family_wise_level(seeds, rho):
    """The test's variance scaled from the reference's (one estimate, df = K − 1):
    family-wise and global rates within 2x of 5 %, for channels that are one unit
    (ρ = 1, 256 effective tests) or three (ρ = 0, 768)."""
    rates = _rates(seeds, rho=rho)
    assert LEVEL / 2 <= rates["family_wise"] <= 2 * LEVEL, rates
    assert LEVEL / 2 <= rates["global"] <= 2 * LEVEL, rates


@pytest.mark.physical_requirement
def test_normal_quantiles_fail_noise_far_above_the_level():
    """Without the seed counts (normal quantiles) K = 4 noise fails the family-wise
    rule in most trials: the failure the t quantiles remove."""
    assert _rates(4, rho=1.0, seeds_known=False)["family_wise"] > 0.5


@pytest.mark.physical_requirement
@pytest.mark.parametrize(("ref_seeds", "test_seeds"), [(16, 4), (4, 4)])
def test_pooled_variance_rule_holds_the_level(ref_seeds, test_seeds):
    """A fresh render with its own variance against the golden: pooling both into one
    per-photon variance (df = K_test + K_ref − 2) is Student's exact test."""
    rates = _rates(ref_seeds, test_seeds=test_seeds, rho=1.0, rule="pooled")
    assert LEVEL / 2 <= rates["family_wise"] <= 2 * LEVEL, rates
    assert LEVEL / 2 <= rates["global"] <= 2 * LEVEL, rates


@pytest.mark.physical_requirement
def test_max_variance_rule_is_conservative():
    """The default heavy-photon guard (the larger of the two variances) never fails
    noise more often than nominal; measured ~1 % at 5 % for K_ref = 16, K_test = 4."""
    rates = _rates(16, test_seeds=4, rho=1.0, rule="max")
    assert rates["family_wise"] <= LEVEL, rates


def test_effective_tests_and_welch_degrees_of_freedom():
    """m = 1 + (C − 1)(1 − ρ²); Welch–Satterthwaite reduces to the single estimate's
    df when the other variance is 0, and to the sum for two equal ones."""
    assert effective_tests(3, 1.0) == 1.0 and effective_tests(3, 0.0) == 3.0
    assert welch_degrees_of_freedom(1.0, 0.0, 3.0, 15.0) == pytest.approx(3.0)
    assert welch_degrees_of_freedom(1.0, 1.0, 15.0, 15.0) == pytest.approx(30.0)
    with pytest.raises(ValueError, match="variance_rule"):
        z_test(np.ones(SHAPE), np.ones(SHAPE), np.ones(SHAPE), test_photons=1,
               reference_photons=1, test_variance=np.ones(SHAPE), variance_rule="min")
