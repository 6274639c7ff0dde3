"""The photon tracer's launch plan: whole launches, every launch stratified, the
photons actually traced recorded.

Regression locks on the plan (:func:`renderers.mitsuba.photons.launch_plan`) and on
``PhotonTracer.trace``, which follows it, and what the default launch size must give
the default budget; that each launch size is stratified at its own size is checked
lane by lane in ``test_emission.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from renderers.mitsuba.emission import MAX_STRATIFIED_LANES, stratified_square
from renderers.mitsuba.photons import DEFAULT_BATCH, PhotonTracer, lane_rng, launch_plan
from scenes.model import Settings
from tests.renderers.mitsuba.scenes import glass_sphere, make_scene

POINT = 'type = "point"\nposition = [0.0, 0.0, 6.0]\nintensity = [30.0, 30.0, 30.0]'


def test_the_default_budget_traces_whole_square_stratified_launches():
    """What the default launch size must give the default budget per seed: launches
    that sum to the budget exactly, all of one size (no partial launch with coarser
    strata than the others), and each launch's strata the cells of a square grid:
    tracing one launch of that size puts exactly one lane's (u1, u2) in each cell of
    the sqrt(n) x sqrt(n) grid (which needs n a power of four; with any other size
    some cells hold two lanes and some none)."""
    budget = Settings().photons
    plan = launch_plan(budget)
    assert sum(plan) == budget
    assert len(set(plan)) == 1, plan
    n = plan[0]
    side = math.isqrt(n)
    u, v = stratified_square(lane_rng(n, 7), n)
    u, v = np.asarray(u, np.float64), np.asarray(v, np.float64)
    cells = np.floor(v * side).astype(np.int64) * side + np.floor(u * side).astype(np.int64)
    counts = np.bincount(cells, minlength=side * side)
    assert counts.size == n and counts.min() == 1 and counts.max() == 1, (
        f"{n} lanes over a {side} x {side} grid: {np.count_nonzero(counts == 0)} "
        f"cells empty, {np.count_nonzero(counts > 1)} with more than one lane")


def test_a_budget_off_whole_launches_ends_with_one_smaller_launch():
    """2,000,000 photons (the old default): one whole launch and one of 951,424 lanes
    (stratified at its own size), summing to the budget exactly; a budget below one
    launch is a single launch of that size."""
    assert launch_plan(2_000_000) == (DEFAULT_BATCH, 2_000_000 - DEFAULT_BATCH)
    assert launch_plan(1000) == (1000,)
    assert launch_plan(12_000, 4_000) == (4_000, 4_000, 4_000)
    for bad in ({"photons": 0}, {"photons": 10, "batch": MAX_STRATIFIED_LANES + 1}):
        with pytest.raises(ValueError):
            launch_plan(**bad)


def test_trace_records_the_photons_it_traced_launch_by_launch():
    """``trace(1000, batch=300)`` traces launches of 300, 300, 300 and 100 lanes and
    reports 1000 photons (it no longer rounds up to whole batches: 1200); the flux
    budget has one row per launch, each launch's emitted weight is its lanes' share
    of the whole (every photon toward one target carries I Omega, so the weight per
    lane is the same: 300 / 1000 and 100 / 1000 of the total, to float32 rounding)."""
    scene = make_scene(light=POINT, objects=glass_sphere(),
                       settings="receiver_map = [16, 16]\nseeds = 1")
    sums = PhotonTracer(scene, caustic_only=True, budget=True).trace(1000, seed=3, batch=300)
    assert sums.photons == 1000
    assert sums.budget.shape[0] == 4
    shares = sums.launch_emitted.sum(axis=1) / sums.launch_emitted.sum()
    np.testing.assert_allclose(shares, [0.3, 0.3, 0.3, 0.1], rtol=1e-5)
