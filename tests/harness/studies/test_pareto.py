"""Pareto front and equal-error speedup on cases with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from harness.studies.pareto import equal_error_speedup, pareto_front


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


def test_bound_when_the_cheapest_reference_is_better():
    result = equal_error_speedup(0.5, 2.0, [1.0, 10.0], [1.0, 0.1])
    assert result.kind == "bound" and result.speedup == pytest.approx(2.0)


def test_rejects_non_positive():
    with pytest.raises(ValueError, match="positive"):
        equal_error_speedup(0.0, 0.1, [1.0], [0.1])
