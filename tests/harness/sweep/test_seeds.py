"""The reference as one task per seed and a merge equals the single-process reference
with the same seeds (``estimate_receivers``), including where it stops.

Three cases: the target met within the budget, the budget kept (target out of
reach of a tiny time cap), and launches past the budget until the target (traced
by the merge itself). Called directly, in this process (no Dask: the cluster tests
run the same functions on workers). Maps are compared texel by texel within
photons · 2^-24 of their value: Dr.Jit's parallel float32 scatter adds a texel's
photons in an order that differs between any two runs, and a texel sums at most
that many photons per seed.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.sweep.seeds import MergeError, merge_reference, trace_seed
from renderers.mitsuba import mitsuba_versions
from renderers.mitsuba.reference import estimate_receivers
from scenes import load_scene, with_settings

from .conftest import small_scene

BATCH = 4_000
#: The starting budget: two whole launches and a remainder launch of 1500 photons.
PHOTONS = 2 * BATCH + 1_500
ROUNDS = 3


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """The glass sphere: 3 seeds of 2 x 4000 + 1500 photons, a 32 x 32 map."""
    path = small_scene(tmp_path_factory.mktemp("seeds"), "glass_sphere")
    return with_settings(load_scene(path), {"photons": PHOTONS, "seeds": 3, "seed": 5,
                                            "spp": 1, "receiver_map": [32, 32]})


@pytest.fixture(scope="module")
def batches(scene):
    return [trace_seed(scene, i, batch=BATCH) for i in range(scene.settings.seeds)]


@pytest.fixture(scope="module")
def full(scene):
    """The single-process budget: a target of 1e-9 is out of every reach."""
    return estimate_receivers(with_settings(scene, {"target_noise": 1e-9}), batch=BATCH,
                              caustic_only=True)


def _rtol(photons: int) -> float:
    """Float32 rounding of a texel's sum: at most ``photons`` photons (per seed)
    added in some order, each addition within 2^-24 of its result."""
    return photons * 2.0**-24


def _close(a: np.ndarray, b: np.ndarray, rtol: float) -> bool:
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    assert a.shape == b.shape
    return bool(np.all(np.abs(a - b) <= rtol * np.abs(b)))


def _same_estimate(merged, single) -> None:
    """The merged reference is ``single`` (a ReceiverEstimate) up to float32 rounding:
    maps, photons, stop, per-channel noise, caustic region and noise history."""
    m = merged.metadata
    rtol = _rtol(single.photons)
    assert m["photons"] == single.photons
    assert m["photon_budget"] == PHOTONS
    assert m["stopped_by"] == single.stopped_by
    assert m["noise_region_texels"] == list(single.region_texels)
    # Noise: ratios of the maps' variance and mean, each within rtol (x4 for the
    # variance's squared differences and the ratio).
    np.testing.assert_allclose(m["relative_noise_per_channel"],
                               single.relative_noise_per_channel, rtol=4 * rtol)
    assert m["relative_noise"] == pytest.approx(single.relative_noise, rel=4 * rtol)
    history = np.array(m["noise_history"])
    assert history[:, 0].tolist() == [h[0] for h in single.history]
    np.testing.assert_allclose(history[:, 1], [h[1] for h in single.history], rtol=4 * rtol)
    assert m["sweep"]["rounds_used"] == len(single.history)
    for mine, theirs in zip(merged.receivers, single.caustic, strict=True):
        assert mine.extent == theirs.extent
        assert _close(mine.irradiance, theirs.irradiance, rtol)


def test_seed_tasks_merge_to_the_single_process_estimate_at_the_budget(scene, batches, full):
    """Physical requirement (the same estimator): a target in reach (0.7 x the
    budget's noise) but a time cap of 1 ms: the single process stops at the budget
    (``budget``), and so do the three merged seed batches, with estimate_receivers'
    maps for the same seeds 5, 6, 7 (within float32 rounding), photons (the three
    launches of launch_plan, the last of 1500), per-channel noise and history; the
    variance of the mean is finite and positive where light lands. Non-vacuity:
    dropping one seed's batch (seeds 5, 6) moves the map by more."""
    s = scene.settings
    scene = with_settings(scene, {"target_noise": 0.7 * full.relative_noise,
                                  "reference_time_cap": 1e-3})
    single = estimate_receivers(scene, batch=BATCH, caustic_only=True)
    merged = merge_reference(scene, "key", mitsuba_versions(), *reversed(batches))
    assert [b.seed for b in batches] == [5, 6, 7]
    assert [b.photons for b in batches] == [(BATCH, BATCH, 1_500)] * 3
    assert single.stopped_by == "budget" and single.photons == PHOTONS
    _same_estimate(merged, single)
    assert merged.metadata["sweep"]["rounds_traced_by_merge"] == 0
    (mine,), (theirs,) = merged.receivers, single.caustic
    lit = theirs.irradiance > 0
    assert lit.sum() > 100
    assert np.all(np.isfinite(mine.variance)) and np.all(mine.variance[lit] > 0)
    two = dataclasses.replace(scene, settings=dataclasses.replace(s, seeds=2))
    fewer = merge_reference(two, "key", mitsuba_versions(), *batches[:2]).receivers[0]
    assert not _close(fewer.irradiance, theirs.irradiance, _rtol(PHOTONS))


def test_merge_stops_where_the_single_process_reference_stops(scene, batches, full):
    """Physical requirement (same stopping rule): with a target noise between the
    noise after round 1 and after round 2, the single-process reference stops after
    round 2 by ``target_noise``; the merge, given all three traced launches, stops
    there too (photons, maps, per-channel noise) and records that it used 2 of 3
    rounds. Non-vacuity: the budget's map differs from the round-2 map by more than
    the tolerance."""
    n1, n2, n3 = (h[1] for h in full.history)
    assert n1 > n2 > n3
    scene = with_settings(scene, {"target_noise": (n1 + n2) / 2})
    single = estimate_receivers(scene, batch=BATCH, caustic_only=True)
    merged = merge_reference(scene, "key", mitsuba_versions(), *batches)
    assert single.photons == 2 * BATCH and single.stopped_by == "target_noise"
    _same_estimate(merged, single)
    assert merged.metadata["sweep"] == {**merged.metadata["sweep"], "rounds_used": 2,
                                        "rounds_traced": 3, "seed_tasks": 3}
    assert not _close(full.caustic[0].irradiance, single.caustic[0].irradiance,
                      _rtol(PHOTONS))


def test_merge_traces_past_the_budget_where_the_single_process_does(scene, batches, full):
    """Physical requirement (the target is met, not the budget): with a target of 0.7
    x the budget's noise (about (1 / 0.7)^2 = 2 x the budget's photons needed, noise
    ~ 1 / sqrt(photons)) and the default time cap (120 s, far above this scene's
    rounds), the single process traces whole launches of 4000 past the budget until
    the target; the merge replays the seeds' budget and traces the same further
    launches itself (same seeds, streams 3, 4, ...), giving the same maps, photons,
    per-channel noise and ``target_noise``. Every channel meets the target."""
    target = 0.7 * full.relative_noise
    scene = with_settings(scene, {"target_noise": target})
    single = estimate_receivers(scene, batch=BATCH, caustic_only=True)
    merged = merge_reference(scene, "key", mitsuba_versions(), *batches)
    assert single.stopped_by == "target_noise" and single.photons > PHOTONS
    assert (single.photons - PHOTONS) % BATCH == 0
    _same_estimate(merged, single)
    assert all(x <= target for x in merged.metadata["relative_noise_per_channel"])
    extended = (single.photons - PHOTONS) // BATCH
    assert merged.metadata["sweep"]["rounds_traced_by_merge"] == extended
    assert merged.metadata["sweep"]["rounds_traced"] == ROUNDS + extended
    # Regression lock on the merge's clock: past the budget, the elapsed time counts
    # on from the slowest seed's budget time.
    history = merged.metadata["noise_history"]
    assert history[ROUNDS][2] > max(b.seconds[-1] for b in batches)


def test_batches_that_are_not_one_reference_are_refused(scene, batches):
    """Regression lock: a missing seed, or a seed traced under other Mitsuba versions
    than the cache key names, is a MergeError naming the problem, never a silently
    wrong reference."""
    versions = mitsuba_versions()
    with pytest.raises(MergeError, match=r"seed batches \[0, 2\] are not the seeds 0..2"):
        merge_reference(scene, "key", versions, batches[0], batches[2])
    other = {**versions, "mitsuba": "0.0.1"}
    with pytest.raises(MergeError, match=r"install the same Mitsuba and Dr\.Jit"):
        merge_reference(scene, "key", other, *batches)
