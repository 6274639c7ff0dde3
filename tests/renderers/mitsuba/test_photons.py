"""The photon tracer's launch plan: whole launches, every launch stratified, the
photons actually traced recorded.

Regression locks on the plan (:func:`renderers.mitsuba.photons.launch_plan`) and on
``PhotonTracer.trace``, which follows it; that each launch size is stratified at its
own size is checked lane by lane in ``test_emission.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from renderers.mitsuba.emission import MAX_STRATIFIED_LANES
from renderers.mitsuba.photons import DEFAULT_BATCH, PhotonTracer, launch_plan
from scenes.model import Settings
from tests.renderers.mitsuba.scenes import glass_sphere, make_scene

POINT = 'type = "point"\nposition = [0.0, 0.0, 6.0]\nintensity = [30.0, 30.0, 30.0]'


def test_the_default_budget_is_whole_launches():
    """The default budget per seed is two whole launches of 2^20 photons: no partial
    launch, each launch a power of four (one lane per cell of a 1024 x 1024 grid)."""
    budget = Settings().photons
    plan = launch_plan(budget)
    assert plan == (DEFAULT_BATCH, DEFAULT_BATCH)
    assert sum(plan) == budget
    assert DEFAULT_BATCH == 4**10 and DEFAULT_BATCH <= MAX_STRATIFIED_LANES


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
