"""Stratified emission lanes: every launch is stratified at its own size.

Physical requirement (unbiased stratified sampling): lane i of an n-lane launch draws
its (u1, u2) uniformly inside stratum i of n equal strata, the n consecutive pieces of
a Morton curve through the 2^15 x 2^15 grid of fine cells (M = 2^30 cells; stratum i
holds the cells c with i M / n <= c + (fraction) < (i + 1) M / n). The check recomputes
each point's fine cell from (u1, u2) and its position on the curve, so it fails for
any lane drawn outside its stratum (an unstratified lane lands in its own stratum
with probability 1 / n).
"""

from __future__ import annotations

import numpy as np
import pytest

from renderers.mitsuba.emission import MAX_STRATIFIED_LANES, stratified_square
from renderers.mitsuba.photons import DEFAULT_BATCH, lane_rng

#: Fine cells per axis of the curve (2^15) and in all (M).
SIDE, CELLS = 1 << 15, 1 << 30


def _curve_cell(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Morton index of the fine cell holding each (u, v): x bits even, y bits odd."""
    x = np.floor(u * SIDE).astype(np.int64)
    y = np.floor(v * SIDE).astype(np.int64)
    cell = np.zeros_like(x)
    for b in range(15):
        cell |= ((x >> b) & 1) << (2 * b) | ((y >> b) & 1) << (2 * b + 1)
    return cell


def _square(n: int, key: int = 11) -> tuple[np.ndarray, np.ndarray]:
    u, v = stratified_square(lane_rng(n, key), n)
    return np.asarray(u, np.float64), np.asarray(v, np.float64)


#: A whole launch (2^20, the default), the partial launch a 2,000,000 budget leaves
#: (951,424 lanes: the old rule left 165,000 of them unstratified), and small odd sizes.
@pytest.mark.parametrize("n", [DEFAULT_BATCH, 2_000_000 - DEFAULT_BATCH, 1000, 3])
def test_every_lane_draws_inside_its_own_stratum(n):
    u, v = _square(n)
    assert u.min() >= 0.0 and v.min() >= 0.0 and u.max() < 1.0 and v.max() < 1.0
    cell = _curve_cell(u, v)
    lane = np.arange(n)
    # A fine cell belongs to stratum i when it meets [i M / n, (i + 1) M / n).
    lower = np.floor(lane * (CELLS / n))
    upper = (lane + 1) * (CELLS / n)
    assert np.all((cell >= lower) & (cell < upper))


def test_a_power_of_four_launch_is_one_lane_per_grid_cell():
    """For n = 4^k the strata are the cells of a 2^k x 2^k grid in Morton order: with
    n = 4^5 every one of the 32 x 32 cells holds exactly one lane's point, and the
    points are uniform inside the cells (mean offset within a cell 0.5 +- 4 standard
    errors of 1 / sqrt(12 n))."""
    n, side = 1 << 10, 32
    u, v = _square(n, key=5)
    ix, iy = np.floor(u * side).astype(int), np.floor(v * side).astype(int)
    counts = np.zeros((side, side), int)
    np.add.at(counts, (iy, ix), 1)
    assert np.all(counts == 1)
    offset = np.concatenate([u * side - ix, v * side - iy])
    assert abs(offset.mean() - 0.5) < 4 / np.sqrt(12 * offset.size)


def test_the_expectation_of_a_sum_over_lanes_is_the_integral():
    """Unbiased: the mean over lanes of f(u, v) = u^2 + sin(3 v) estimates its integral
    1/3 + (1 - cos 3) / 3 = 0.6633; over 200 launches of an odd size (777 lanes) the
    mean of the launch estimates is within 4 standard errors of the integral."""
    exact = 1 / 3 + (1 - np.cos(3.0)) / 3
    estimates = []
    for key in range(200):
        u, v = _square(777, key=key)
        estimates.append(np.mean(u**2 + np.sin(3 * v)))
    estimates = np.asarray(estimates)
    assert abs(estimates.mean() - exact) < 4 * estimates.std(ddof=1) / np.sqrt(estimates.size)


def test_launch_sizes_outside_the_strata_are_refused():
    """A launch of no lane, or of more lanes than fine cells (a stratum would be
    smaller than a cell), is a ValueError before any number is drawn."""
    for n in (0, MAX_STRATIFIED_LANES + 1):
        with pytest.raises(ValueError, match="a stratified launch has 1 to"):
            stratified_square(None, n)
