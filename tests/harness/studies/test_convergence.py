"""Convergence statistics on constructed estimate sequences with known outcomes."""

from __future__ import annotations

import numpy as np
import pytest

from harness.studies.convergence import iteration_stats, lookups_per_vertex


def test_statistics_and_outcomes():
    """Four vertices, exact distance 2 m, texel 0.01 m:
    v0 converges (error 0.5, 0.05, 0.001), v1 oscillates away (0.5, 0.6, 0.8),
    v2 is lost at iteration 2, v3's ray misses every receiver (excluded)."""
    exact = np.array([2.0, 2.0, 2.0, np.inf])
    estimates = np.array([
        [1.5, 1.5, 1.5, 1.0],
        [1.95, 2.6, 1.9, 1.0],
        [2.001, 1.2, 0.0, 1.0],
    ])
    lost = np.zeros_like(estimates, bool)
    lost[2, 2] = True
    rows = iteration_stats(estimates, lost, exact, 0.01)
    assert [r.iteration for r in rows] == [0, 1, 2]
    last = rows[2]
    assert last.converged == pytest.approx(1 / 3)
    assert last.diverged == pytest.approx(1 / 3)
    assert last.lost == pytest.approx(1 / 3)
    assert last.max_error_m == pytest.approx(0.8)
    assert last.mean_error_m == pytest.approx((0.001 + 0.8) / 2)
    assert last.max_error_texels == pytest.approx(80.0)
    assert rows[0].converged == 0.0 and rows[0].diverged == 0.0


def test_non_finite_estimate_counts_as_diverged():
    rows = iteration_stats([[1.0], [np.nan]], [[False], [False]], [2.0], 0.01)
    assert rows[1].diverged == 1.0 and np.isnan(rows[1].mean_error_m)


def test_shape_mismatch_is_an_error():
    with pytest.raises(ValueError, match="K\\+1, N"):
        iteration_stats([[1.0, 2.0]], [[False]], [2.0, 2.0], 0.01)


def test_lookup_counts():
    """Newton needs two lookups per iteration (f(d) and f(d + ε)); the modified
    estimator one (the paper's point)."""
    assert lookups_per_vertex("newton", 3) == 7
    assert lookups_per_vertex("modified", 3) == 4
    assert lookups_per_vertex("secant", 0) == 1
