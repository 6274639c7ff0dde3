"""The reference's rounds: the starting budget, then whole launches until the noise
target, within the time cap.

A small glass sphere (32 x 32 caustic map, 4 seeds) traced in launches of 4096
photons, so each round takes a fraction of a second.
"""

from __future__ import annotations

import numpy as np
import pytest

from renderers.mitsuba.reference import estimate_receivers, stop_reason
from tests.renderers.mitsuba.scenes import glass_sphere, make_scene

POINT = 'type = "point"\nposition = [0.3, 0.0, 6.0]\nintensity = [30.0, 30.0, 30.0]'
BATCH = 4096
#: The starting budget: two whole launches per seed.
BUDGET = 2 * BATCH


@pytest.fixture(scope="module")
def scene():
    return make_scene(light=POINT, objects=glass_sphere(), direct=False,
                      settings=f"photons = {BUDGET}\nseeds = 4\nreceiver_map = [32, 32]")


@pytest.fixture(scope="module")
def at_budget(scene):
    """The budget alone: a target no budget reaches (1e-9) stops it there."""
    return estimate_receivers(scene, batch=BATCH, caustic_only=True, target_noise=1e-9)


def test_an_unreachable_target_stops_at_the_budget(at_budget):
    """Regression lock: with a target out of reach within the time cap, the reference
    traces its starting budget exactly (two rounds of one launch per seed) and stops
    by ``budget``; the noise it records is the last round's and falls from round to
    round (more photons)."""
    assert at_budget.photons == BUDGET and at_budget.budget == BUDGET
    assert at_budget.stopped_by == "budget"
    (n1, e1, _), (n2, e2, _) = at_budget.history
    assert (n1, n2) == (BATCH, BUDGET)
    assert e2 < e1 and at_budget.relative_noise == e2
    assert max(at_budget.relative_noise_per_channel) == at_budget.relative_noise
    assert at_budget.region_texels[0] > 20


def test_a_reachable_target_is_met_with_whole_launches_past_the_budget(scene, at_budget):
    """Physical requirement (the target is met, not the budget): with a target 0.7 x the
    budget's noise (about 2 x the photons needed, since noise ~ 1 / sqrt(photons)),
    the reference goes on past the budget in whole launches until its noise is at
    most the target, and says ``target_noise``. Every channel meets it."""
    target = 0.7 * at_budget.relative_noise
    est = estimate_receivers(scene, batch=BATCH, caustic_only=True, target_noise=target)
    assert est.stopped_by == "target_noise"
    assert est.relative_noise <= target
    assert all(x <= target for x in est.relative_noise_per_channel)
    assert est.photons > BUDGET and (est.photons - BUDGET) % BATCH == 0
    # The first rounds are the budget's, traced as without a target.
    assert est.history[1][0] == BUDGET
    assert est.history[1][1] == pytest.approx(at_budget.history[1][1], rel=1e-6)


def test_a_target_out_of_reach_of_the_time_cap_keeps_the_budget(scene, at_budget):
    """The same reachable target with a time cap of 1 ms: the projected time is over
    the cap, so no launch past the budget is traced (``budget``)."""
    target = 0.7 * at_budget.relative_noise
    est = estimate_receivers(scene, batch=BATCH, caustic_only=True, target_noise=target,
                             time_cap=1e-3)
    assert est.stopped_by == "budget" and est.photons == BUDGET and est.time_cap == 1e-3


@pytest.mark.parametrize(("phase", "elapsed", "expected"), [
    ("budget", 50.0, None),          # the budget's launches are always traced
    ("spent", 10.0, None),           # 4x photons: 30 s more at the rate, 40 s < 60 s
    ("spent", 40.0, "budget"),       # 40 + 30 s > 60 s: out of reach, no extension
    ("extended", 10.0, None),
    ("extended", 40.0, "time_cap"),  # extended, then out of reach within the cap
    ("extended", 61.0, "time_cap"),  # past the cap
])
def test_the_stop_rule(phase, elapsed, expected):
    """Regression lock on the rule: noise 0.02 against a target of 0.01 needs
    (0.02 / 0.01)^2 = 4 x the 1e6 photons traced, 3e6 more at 1e5 photons/s = 30 s;
    the cap is 60 s. A noise at the target stops by ``target_noise`` in any phase; a
    non-finite noise, or a target of 0 (the whole budget, never more), past the budget
    by the phase's reason."""
    args = {"target": 0.01, "rate": 1e5, "traced": 10**6, "cap": 60.0}
    assert stop_reason(noise=0.02, phase=phase, elapsed=elapsed, **args) == expected
    assert stop_reason(noise=0.01, phase=phase, elapsed=elapsed, **args) == "target_noise"
    if phase != "budget":
        reason = "budget" if phase == "spent" else "time_cap"
        assert stop_reason(noise=np.nan, phase=phase, elapsed=1.0, **args) == reason
        assert stop_reason(noise=0.02, phase=phase, elapsed=1.0,
                           **{**args, "target": 0.0}) == reason
