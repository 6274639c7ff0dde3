"""The reference's rounds: the starting budget, then whole launches until the noise
target, within the time cap.

A small glass sphere (32 x 32 caustic map, 4 seeds) traced in launches of 4096
photons, so each round takes a fraction of a second.
"""

from __future__ import annotations

import numpy as np
import pytest

from renderers.mitsuba.reference import ReceiverRounds, estimate_receivers, stop_reason
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


def _round(factors: np.ndarray, photons: int, *, shape=(4, 4)):
    """Per seed, one receiver's caustic sums: photons x (1, 2, 4) W/m² x factor[k, c]
    in every texel (a uniform map, so its whole area is the caustic region)."""
    base = np.array([1.0, 2.0, 4.0])
    return [[np.broadcast_to(photons * base * f, (*shape, 3)).copy()] for f in factors]


def test_rounds_noise_stop_and_cut_fraction_from_per_seed_sums():
    """Regression lock on the shared bookkeeping (the single process and the sweep's
    merge both feed it): two seeds whose estimates are (1 - d_c) and (1 + d_c) times
    the mean have a variance of the mean s^2 / 2 = (d_c m_c)^2, so each channel's
    relative noise is d_c = (0.1, 0.2, 0.05), the largest 0.2, over all 16 texels.
    A budget of 5 in launches of 2 is rounds of 2, 2, 1 photons: the first two go on
    (budget phase), the last stops at the budget (a 1e-3 target needs 40 000 x the
    photons, far past the 1 s cap). The cut fraction is over both seeds' flux: 1 cut
    of 10 emitted per seed per round, three rounds, is 1 / 60 (the last seed's alone,
    1 / 30). A round after the stop is refused."""
    d = np.array([0.1, 0.2, 0.05])
    factors = np.stack([1 - d, 1 + d])
    rounds = ReceiverRounds(extents=[(0.0, 1.0, 0.0, 1.0)], seeds=2, seed=3, budget=5,
                            batch=2, target=1e-3, cap=1.0, channel_passes=1,
                            caustic_only=True)
    assert rounds.plan == (2, 2, 1)
    emitted, cut = [np.full(3, 10.0)] * 2, [np.zeros(3), np.array([1.0, 0.0, 0.0])]
    reasons = []
    for step in range(3):
        n = rounds.lanes
        reasons.append(rounds.add(_round(factors, n), photons=n, emitted=emitted,
                                  cut=cut if step == 0 else [np.zeros(3)] * 2,
                                  elapsed=0.1 * (step + 1), seconds=0.1))
    assert reasons == [None, None, "budget"]
    est = rounds.estimate()
    assert est.photons == 5 and est.stopped_by == "budget" and est.seed == 3
    np.testing.assert_allclose(est.relative_noise_per_channel, d, rtol=1e-12)
    assert est.relative_noise == pytest.approx(0.2, rel=1e-12)
    assert est.region_texels == (16,)
    np.testing.assert_allclose(est.caustic[0].irradiance, np.broadcast_to([1, 2, 4], (4, 4, 3)))
    assert [h[0] for h in est.history] == [2, 4, 5]
    assert est.cut_fraction == pytest.approx(1 / 60, rel=1e-12)
    with pytest.raises(ValueError, match="stopped"):
        rounds.add(_round(factors, 2), photons=2, emitted=emitted, cut=cut, elapsed=1.0,
                   seconds=0.1)
