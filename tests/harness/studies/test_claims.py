"""The paper's claims are stated with numbers, whichever way they fall, and with the
uncertainty of those numbers: a margin within twice it is undecided."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.compare.regions import caustic_region
from harness.studies.claims import (
    check_five_iterations,
    check_one_iteration,
    claim_verdict,
    hit_errors_texels,
    one_iteration_verdict,
    paper_claims,
    percentile_standard_error,
    ratio_standard_error,
)
from harness.studies.convergence_study import convergence_study
from harness.studies.runner import RealtimeRunner
from renderers.mitsuba.reference import estimate_receivers
from scenes import load_scene, with_settings
from tests.conftest import SCENES


def test_five_iterations_both_ways():
    holds, text = check_five_iterations({0: 40.0, 5: 0.4})
    assert holds and text.startswith("holds") and "0.4 texels" in text
    holds, text = check_five_iterations({0: 40.0, 5: 3.0})
    assert not holds and text.startswith("does not hold")
    assert check_five_iterations({0: 1.0})[0] is False


def test_one_iteration_both_ways():
    holds, text = check_one_iteration({0: 0.5, 1: 0.105, 8: 0.1})
    assert holds and "ratio 1.050" in text
    holds, _ = check_one_iteration({0: 0.5, 1: 0.2, 8: 0.1})
    assert not holds


# --- Verdicts with uncertainty (docs/statistics.md) ----------------------------------

@pytest.mark.parametrize(("value", "se", "verdict"), [
    (1.110, 0.012, "undecided at this noise"),  # ratio 1.110: margin -0.010 < 2σ
    (1.110, 0.004, "does not hold"),            # margin -0.010 beyond 2σ = 0.008
    (1.050, 0.020, "holds"),                    # margin 0.050 >= 2σ = 0.040
    (1.050, 0.030, "undecided at this noise"),  # margin 0.050 < 2σ = 0.060
    (1.099, None, "holds"),                     # no uncertainty: the sign decides
    (1.101, float("nan"), "does not hold"),
    (float("nan"), 0.01, "not measured"),
    (float("inf"), 1e9, "does not hold"),
])
def test_verdict_rule_on_hand_computed_margins(value, se, verdict):
    """Regression lock of the rule in harness/studies/claims.py (hand-computed cases
    against the bound 1.10): undecided exactly when |bound - value| < 2σ."""
    assert claim_verdict(value, 1.10, se) == verdict


def test_undecided_claim_sentence_carries_its_uncertainty():
    """Regression lock: the sentence starts with the verdict and states the ratio
    with its standard error, the bound, the margin against 2σ and where σ comes
    from; the boolean of check_one_iteration is False when undecided."""
    v = one_iteration_verdict({0: 0.5, 1: 0.111, 8: 0.1}, standard_error=0.012)
    assert v.verdict == "undecided at this noise" and v.margin == pytest.approx(-0.010)
    assert v.text.startswith("undecided at this noise: receiver relMSE after 1 iteration")
    assert "ratio 1.110 ± 0.012; claim allows 1.10; margin -0.010 against 2σ = 0.024" in v.text
    assert "reference's per-texel variance" in v.text
    assert check_one_iteration({0: 0.5, 1: 0.111, 8: 0.1}, standard_error=0.012)[0] is False


def _delta_method_ratio_se(one, last, mean, variance, epsilon=0.01):
    """σ of relMSE(one, m) / relMSE(last, m) to first order in the reference noise:
    Var R = Σ_i (∂R/∂m_i)² v_i, with ∂relMSE_k/∂m_i = (1/n) [-2 (x_k - m) / (m² + ε)
    - 2 m (x_k - m)² / (m² + ε)²]."""
    n = mean.size
    den = mean**2 + epsilon
    a = ((one - mean) ** 2 / den).mean()
    b = ((last - mean) ** 2 / den).mean()
    da = (-2 * (one - mean) / den - 2 * mean * (one - mean) ** 2 / den**2) / n
    db = (-2 * (last - mean) / den - 2 * mean * (last - mean) ** 2 / den**2) / n
    grad = da / b - a * db / b**2
    return float(np.sqrt((grad**2 * variance).sum()))


def test_ratio_standard_error_is_the_delta_method_one():
    """Physical requirement (an analytic answer): on a synthetic caustic (a Gaussian
    blob, 32 x 32 texels, 0.5 % relative reference noise per texel; method maps off
    by 6 % + 0.02 and 5.5 % + 0.01, so their errors dwarf the noise and first order
    applies) the parametric bootstrap's σ of the relMSE ratio matches the delta
    method's closed form within 10 % (measured 2 %; 400 draws: the bootstrap's own
    spread is ~3.5 %). Drawing the two relMSEs' reference maps independently, which
    ignores the noise they share, gives 4.5x the σ; a σ from the variance instead of
    its square root is off by orders of magnitude: both fail."""
    y, x = np.mgrid[0:32, 0:32]
    blob = 4 * np.exp(-((x - 16) ** 2 + (y - 15) ** 2) / 50.0)[..., None] * np.ones(3)
    mean = blob + 0.2
    variance = (0.005 * mean) ** 2
    one, last = mean * 1.06 + 0.02, mean * 1.055 + 0.01
    mask = np.ones((32, 32), bool)
    boot = ratio_standard_error(one, last, mean, variance, mask, draws=400)
    delta = _delta_method_ratio_se(one, last, mean, variance)
    print(f"bootstrap {boot:.4g}, delta method {delta:.4g}")
    assert boot == pytest.approx(delta, rel=0.10)


def test_percentile_standard_error_is_the_asymptotic_one():
    """Physical requirement (an analytic answer): the bootstrap standard error of
    the 95th percentile of N = 20,000 standard normal values is the asymptotic
    sqrt(p (1 - p) / N) / φ(z_p) = 0.0149 within 20 % (400 draws: ~3.5 % spread, and
    the finite-N quantile's own scatter)."""
    values = np.random.default_rng(7).standard_normal(20_000)
    z = 1.6448536269514722
    expected = np.sqrt(0.95 * 0.05 / values.size) / (np.exp(-z * z / 2) / np.sqrt(2 * np.pi))
    got = percentile_standard_error(values, draws=400)
    print(f"bootstrap {got:.4g}, asymptotic {expected:.4g}")
    assert got == pytest.approx(expected, rel=0.2)


def test_claims_on_a_real_render_use_the_tables_numbers():
    """Regression lock: on a small glass_sphere (grid 48, modified estimator,
    iterations 0..5) with a 4-seed reference, paper_claims' uncertainties are finite
    and positive, and it resamples exactly what the table reports: the p95 of the
    rays it bootstraps is the table's p95_error_texels, and the maps it perturbs give
    the table's relMSE at iterations 1 and 5 (the renders are deterministic)."""
    scene = load_scene(SCENES / "glass_sphere.toml")
    scene = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                  resolution=(16, 16)))
    scene = with_settings(scene, {"grid": 48, "caustic_map": 128, "positions_map": 128,
                                  "shadow_map": 128, "receiver_map": [48, 48]})
    reference = estimate_receivers(scene, photons=200_000, seeds=4, target_noise=1e-9,
                                   caustic_only=True).caustic[0]
    caustic = caustic_region(reference.irradiance)
    with RealtimeRunner(scene, repeats=1) as runner:
        table = convergence_study(runner, reference.irradiance, caustic, max_iterations=5,
                                  configs=(("modified", False),))
        claims, (five, one) = paper_claims(table, runner=runner, reference=reference,
                                           caustic=caustic)
        errors = hit_errors_texels(runner, 5)
    rows = {r["iteration"]: r for r in table.records()}
    print(five.text, one.text, sep="\n")
    assert set(claims) == {five.claim, one.claim}
    assert five.value == rows[5]["p95_error_texels"]
    assert np.percentile(errors, 95) == pytest.approx(five.value, rel=1e-12)
    assert one.value == pytest.approx(rows[1]["relmse"] / rows[5]["relmse"], rel=1e-12)
    for v in (five, one):
        assert v.standard_error is not None and 0 < v.standard_error < np.inf
        assert v.verdict in ("holds", "does not hold", "undecided at this noise")


def test_claims_without_a_caustic_region_are_not_measured():
    """Regression lock (the compare of a scene whose caustic misses every receiver
    must finish, so that it can fail with "no caustic"): NaN relMSEs make the
    one-iteration claim "not measured", and an empty region gives a NaN standard
    error instead of an exception."""
    v = one_iteration_verdict({1: float("nan"), 4: float("nan")}, standard_error=None)
    assert v.verdict == "not measured" and v.text.startswith("not measured")
    empty = np.zeros((4, 4), bool)
    maps = np.ones((4, 4, 3))
    assert np.isnan(ratio_standard_error(maps, maps, maps, maps, empty))
