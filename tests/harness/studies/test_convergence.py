"""Convergence statistics on constructed histories with known outcomes."""

from __future__ import annotations

import numpy as np
import pytest

from harness.studies.convergence import classify, iteration_stats, lookups_per_vertex


def test_each_outcome():
    """Exact distance 2 m, texel 0.01 m (τ = 1 texel = 0.01 m):
    v0 converges (1.5 → 1.95 → 2.001); v1 oscillates (2.5 → 1.5 → 2.5); v2 stalls
    on a wrong root (2.3 → 2.3); v3 runs away (3 → 30 > 10·2); v4 is lost; v5's ray
    misses every receiver (excluded); v6 still converging (1.5 → 1.7 → 1.8)."""
    exact = np.array([2.0, 2.0, 2.0, 2.0, 2.0, np.inf, 2.0])
    history = np.array([
        [1.5, 1.95, 2.001],
        [1.5, 2.5, 1.5],
        [2.0, 2.3, 2.3],
        [1.0, 3.0, 30.0],
        [0.0, 0.0, 0.0],
        [1.0, 1.0, 1.0],
        [1.5, 1.7, 1.8],
    ])
    lost = np.array([False, False, False, False, True, False, False])
    outcome = classify(history, lost, exact, 0.01)
    assert outcome.tolist() == ["converged", "oscillating", "stalled", "diverged", "lost", "",
                                "converging"]
    stats = iteration_stats(history, lost, exact, 0.01)
    assert stats.iteration == 2
    for name in ("converged", "oscillating", "stalled", "diverged", "lost", "converging"):
        assert getattr(stats, name) == pytest.approx(1 / 6)
    # Errors over the non-lost vertices with an exact hit: 0.001, 0.5, 0.3, 28, 0.2.
    assert stats.max_error_m == pytest.approx(28.0)
    assert stats.mean_error_m == pytest.approx((0.001 + 0.5 + 0.3 + 28 + 0.2) / 5)
    assert stats.max_error_texels == pytest.approx(2800.0)


def test_non_finite_estimate_is_diverged():
    stats = iteration_stats([[1.0, np.nan]], [False], [2.0], 0.01)
    assert stats.diverged == 1.0 and np.isnan(stats.mean_error_m)


def test_shape_mismatch_is_an_error():
    with pytest.raises(ValueError, match="N, k\\+1"):
        iteration_stats([[1.0, 2.0]], [False, False], [2.0, 2.0], 0.01)


def test_lookup_counts():
    """Newton needs two lookups per iteration (f(d) and f(d + ε)); the modified
    estimator one (the paper's point)."""
    assert lookups_per_vertex("newton", 3) == 7
    assert lookups_per_vertex("modified", 3) == 4
    assert lookups_per_vertex("secant", 0) == 1
