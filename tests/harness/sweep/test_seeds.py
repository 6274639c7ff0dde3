"""The reference as one task per seed and a merge equals the single-process reference
with the same seeds (``estimate_receivers``), including where it stops.

Called directly, in this process (no Dask: the cluster tests run the same functions
on workers). Maps are compared texel by texel within PHOTONS · 2^-24 of their
value: Dr.Jit's parallel float32 scatter adds a texel's photons in an order that
differs between any two runs, and a texel sums at most PHOTONS photons per seed.
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
ROUNDS = 3
PHOTONS = BATCH * ROUNDS
RTOL = PHOTONS * 2.0**-24


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """The glass sphere: 3 seeds of 3 rounds of 4000 photons, a 32 x 32 map."""
    path = small_scene(tmp_path_factory.mktemp("seeds"), "glass_sphere")
    return with_settings(load_scene(path), {"photons": PHOTONS, "seeds": 3, "seed": 5,
                                            "spp": 1, "receiver_map": [32, 32]})


@pytest.fixture(scope="module")
def batches(scene):
    return [trace_seed(scene, i, batch=BATCH) for i in range(scene.settings.seeds)]


def _close(a: np.ndarray, b: np.ndarray) -> None:
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    assert a.shape == b.shape
    assert np.all(np.abs(a - b) <= RTOL * np.abs(b))


def test_seed_tasks_merge_to_the_single_process_estimate(scene, batches):
    """Physical requirement (the same estimator): three seed batches of three rounds,
    merged, give estimate_receivers' maps for the same seeds 5, 6, 7 (within float32
    rounding), the same photon count, stop and noise history; each batch traced its
    own seed; the variance of the mean is finite and positive where light lands.
    Non-vacuity: dropping one seed's batch (seeds 5, 6) moves the map by more."""
    s = scene.settings
    target = 1e-9  # never reached: both trace the whole budget
    scene = with_settings(scene, {"target_noise": target})
    single = estimate_receivers(scene, batch=BATCH, caustic_only=True)
    merged = merge_reference(scene, "key", mitsuba_versions(), *reversed(batches))
    assert [b.seed for b in batches] == [5, 6, 7]
    assert merged.metadata["photons"] == single.photons == PHOTONS
    assert merged.metadata["stopped_by"] == single.stopped_by == "budget"
    assert merged.metadata["sweep"]["rounds_used"] == ROUNDS
    history = np.array(merged.metadata["noise_history"])
    assert history[:, 0].tolist() == [h[0] for h in single.history]
    np.testing.assert_allclose(history[:, 1], [h[1] for h in single.history], rtol=4 * RTOL)
    (mine,), (theirs,) = merged.receivers, single.caustic
    _close(mine.irradiance, theirs.irradiance)
    lit = theirs.irradiance > 0
    assert lit.sum() > 100
    assert np.all(np.isfinite(mine.variance)) and np.all(mine.variance[lit] > 0)
    assert mine.extent == theirs.extent
    two = dataclasses.replace(scene, settings=dataclasses.replace(s, seeds=2))
    fewer = merge_reference(two, "key", mitsuba_versions(), *batches[:2]).receivers[0]
    assert not np.all(np.abs(fewer.irradiance - theirs.irradiance)
                      <= RTOL * np.abs(theirs.irradiance))


def test_merge_stops_where_the_single_process_reference_stops(scene, batches):
    """Physical requirement (same stopping rule): with a target noise between the
    noise after round 1 and after round 2, the single-process reference stops after
    round 2; the merge, given all three traced rounds, stops there too (photons,
    maps, ``stopped_by``) and records that it used 2 of 3 rounds. Non-vacuity: the
    round-3 map differs from the round-2 map by more than the tolerance."""
    full = estimate_receivers(with_settings(scene, {"target_noise": 1e-9}), batch=BATCH,
                              caustic_only=True)
    n1, n2, n3 = (h[1] for h in full.history)
    assert n1 > n2 > n3
    scene = with_settings(scene, {"target_noise": (n1 + n2) / 2})
    single = estimate_receivers(scene, batch=BATCH, caustic_only=True)
    merged = merge_reference(scene, "key", mitsuba_versions(), *batches)
    assert single.photons == merged.metadata["photons"] == 2 * BATCH
    assert single.stopped_by == merged.metadata["stopped_by"] == "target_noise"
    assert merged.metadata["sweep"] == {**merged.metadata["sweep"], "rounds_used": 2,
                                        "rounds_traced": 3, "seed_tasks": 3}
    _close(merged.receivers[0].irradiance, single.caustic[0].irradiance)
    third = full.caustic[0].irradiance
    assert not np.all(np.abs(third - single.caustic[0].irradiance)
                      <= RTOL * np.abs(single.caustic[0].irradiance))


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
