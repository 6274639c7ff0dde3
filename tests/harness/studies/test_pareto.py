"""Pareto front, the reference curve's log-log fit and the equal-error speedup on
cases with known answers (the interval's coverage: test_speedup.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.studies.pareto import (
    CurveFitError,
    equal_error_speedup,
    fit_cost_curve,
    pareto_front,
    speedup_from_fit,
)


def test_front_drops_dominated_points():
    times = [1.0, 2.0, 3.0, 2.5, 0.5, 4.0]
    errors = [0.5, 0.3, 0.1, 0.4, 0.9, 0.1]
    # (2.5, 0.4) is dominated by (2.0, 0.3); (4.0, 0.1) by (3.0, 0.1).
    assert pareto_front(times, errors).tolist() == [4, 0, 1, 2]


def test_front_ignores_non_finite():
    assert pareto_front([1.0, np.nan, 2.0], [1.0, 0.0, np.inf]).tolist() == [0]


def test_interpolated_speedup_on_a_monte_carlo_curve():
    """A reference with relMSE = 1/t exactly: reaching 0.01 takes 100 s; a real-time
    point at 0.01 s with that error has speedup 10 000."""
    t = np.array([1.0, 10.0, 1000.0])
    result = equal_error_speedup(0.01, 0.01, t, 1 / t)
    assert result.kind == "interpolated"
    assert result.reference_time == pytest.approx(100.0)
    assert result.speedup == pytest.approx(10_000.0)


def test_extrapolated_below_the_measured_errors():
    result = equal_error_speedup(0.01, 1e-4, [1.0, 10.0], [1.0, 0.1])
    assert result.kind == "extrapolated"
    assert result.reference_time == pytest.approx(10.0 * 0.1 / 1e-4)


def test_extrapolation_uses_the_fitted_slope():
    """Points on e = 0.1 t^−1.25 exactly: the fit returns s = −1.25, and reaching
    e = 1e-5 takes (1e-4)^(−1/1.25) = 1585 s, where slope −1 from the last point
    (t = 8, e = 0.1 · 8^−1.25 = 7.43e-3) would say 8 · 7.43e-3 / 1e-5 = 5946 s."""
    t = np.array([1.0, 2.0, 4.0, 8.0])
    e = 0.1 * t**-1.25
    fit = fit_cost_curve(t, e, 0.05 * e)
    assert fit.slope == pytest.approx(-1.25)
    assert fit.chi2 == pytest.approx(0.0, abs=1e-20)
    result = speedup_from_fit(0.01, 1e-5, fit)
    assert result.kind == "extrapolated" and result.bound_kind == "estimate"
    assert result.reference_time == pytest.approx(1e-4 ** (-1 / 1.25))
    assert result.slope == pytest.approx(-1.25)


def test_slope_stderr_of_two_points_with_known_errors():
    """Two points a factor e (in t) apart, each log error with SE 0.1: the slope is a
    difference of the two over log-distance 1, so its SE is sqrt(2) · 0.1."""
    t = np.array([1.0, math.e])
    e = np.array([1.0, 1.0 / math.e])
    fit = fit_cost_curve(t, e, 0.1 * e)
    assert fit.slope == pytest.approx(-1.0)
    assert fit.slope_stderr == pytest.approx(math.sqrt(2) * 0.1)


def test_birge_ratio_widens_a_bent_curve():
    """Points off a straight line by far more than their 1 % errors: χ²/(n − 2) > 1
    scales the covariance, so the slope's SE exceeds the one the errors alone give."""
    t = np.array([1.0, 4.0, 16.0, 64.0])
    e = np.array([1.0, 0.2, 0.07, 0.015])
    tight = fit_cost_curve(t, e, 0.01 * e)
    assert tight.chi2 / tight.dof > 1
    unit = fit_cost_curve(t, e, 0.01 * e * math.sqrt(tight.chi2 / tight.dof))
    assert tight.slope_stderr == pytest.approx(unit.slope_stderr)


def test_cold_speedup_adds_the_reference_one_off_seconds():
    """e = 1/t: reaching 0.01 takes 100 s warm; with 2 s of build and compile the
    reference's cold time is 102 s, against the method's cold 0.5 s: 204 x."""
    t = np.array([1.0, 10.0, 1000.0])
    result = equal_error_speedup(0.5, 0.01, t, 1 / t, overhead_s=2.0)
    assert result.reference_time == pytest.approx(102.0)
    assert result.speedup == pytest.approx(204.0)


def test_bound_when_the_cheapest_reference_is_better():
    result = equal_error_speedup(0.5, 2.0, [1.0, 10.0], [1.0, 0.1])
    assert result.kind == "bound" and result.speedup == pytest.approx(2.0)
    assert result.bound_kind == "upper bound" and result.high == pytest.approx(2.0)


def test_fit_rejects_a_curve_that_does_not_fall():
    with pytest.raises(CurveFitError, match="does not fall"):
        fit_cost_curve([1.0, 2.0, 4.0], [0.1, 0.2, 0.3], [0.01, 0.01, 0.01])
    with pytest.raises(CurveFitError, match="two points"):
        fit_cost_curve([1.0, 2.0], [0.1, -0.01], [0.01, 0.01])


def test_rejects_non_positive():
    with pytest.raises(ValueError, match="positive"):
        equal_error_speedup(0.0, 0.1, [1.0], [0.1])
