"""The reference of an animation (``renderers.mitsuba.sequence``): common random
numbers make a still scene's frames the same estimate and shrink the noise of a moving
scene's frame differences; each frame is cached under a key that holds its seed; the
cache key of a single reference ignores ``[animation]``.

Renders are small: a glass sphere under a point light, 64 × 64 receiver map,
100 000 photons per seed, 4 seeds, 3 frames (about 2 s a sequence on 2 CPU cores)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from renderers.mitsuba import mitsuba_versions
from renderers.mitsuba.cache import InvalidCacheEntryWarning, cache_key
from renderers.mitsuba.sequence import SUBFOLDER, frame_seeds, render_reference_frames
from scenes import parse_scene
from scenes.animation import animation_frames
from tests.conftest import MINIMAL_SCENE

SETTINGS = "\n[settings]\nphotons = 100000\nseeds = 4\nreceiver_map = [64, 64]\n"
STILL = MINIMAL_SCENE + SETTINGS + "[animation]\nframes = 3\n"
# 3 mm per frame at 30 fps: the caustic moves by a few per cent of a texel (12.5 cm).
MOVING = STILL + "[[animation.objects]]\nindex = 0\nvelocity = [0.09, 0.0, 0.0]\n"


def _frames(text: str):
    return [f.scene for f in animation_frames(parse_scene(text))]


def _maps(sequence) -> np.ndarray:
    return np.stack([f.receivers[0].irradiance.astype(np.float64) for f in sequence])


def _variance(sequence) -> np.ndarray:
    return np.stack([f.receivers[0].variance.astype(np.float64) for f in sequence])


def test_frame_seeds_are_shared_or_disjoint():
    """Common random numbers: every frame starts at the sequence's seed; without
    them, frame i takes the K seeds after frame i − 1's."""
    assert [frame_seeds(7, 4, i, common_random_numbers=True) for i in range(3)] == [7, 7, 7]
    assert [frame_seeds(7, 4, i, common_random_numbers=False) for i in range(3)] == [7, 11, 15]


@pytest.mark.physical_requirement
def test_a_still_scene_has_no_reference_flicker_with_common_random_numbers():
    """Physical requirement: a still scene's frames must not differ by more than the
    estimate itself allows. With common random numbers they are the same estimate up
    to the float atomics' summation order (mean ΔR² below 1e-6 of the frames' noise
    variance var_0 + var_1); with independent seeds they differ by exactly that noise:
    E[ΔR²] = var_0 + var_1, measured 0.998 at 4 seeds (the mean is carried by a few
    hundred bright texels, so ±25 %)."""
    frames = _frames(STILL)
    shared = render_reference_frames(frames, use_cache=False)
    independent = render_reference_frames(frames, use_cache=False,
                                          common_random_numbers=False, seed=10)
    assert [f.seed for f in shared] == [0, 0, 0]
    assert [f.seed for f in independent] == [10, 14, 18]
    for sequence, bound in ((shared, (0.0, 1e-6)), (independent, (0.75, 1.33))):
        maps, variance = _maps(sequence), _variance(sequence)
        ratio = float((np.diff(maps, axis=0) ** 2).mean()
                      / (variance[1:] + variance[:-1]).mean())
        assert bound[0] <= ratio <= bound[1], (sequence[0].seed, ratio)


@pytest.mark.physical_requirement
def test_common_random_numbers_shrink_the_noise_of_frame_differences():
    """Where the scene moves little between frames, photon j takes nearly the same path
    in both, so the noise of ΔR (the spread of ΔR between two sequences of disjoint
    seeds, whose true ΔR is the same) falls: measured 9.7e-6 against 9.0e-5 W²/m⁴ with
    independent frames (9×); the bound asks for 3×."""
    frames = _frames(MOVING)[:2]

    def difference_noise(common: bool) -> float:
        a = render_reference_frames(frames, use_cache=False, seed=0,
                                    common_random_numbers=common)
        b = render_reference_frames(frames, use_cache=False, seed=40,
                                    common_random_numbers=common)
        return float(((np.diff(_maps(a), axis=0) - np.diff(_maps(b), axis=0)) ** 2).mean())

    shared, independent = difference_noise(True), difference_noise(False)
    assert shared < independent / 3, (shared, independent)


@pytest.mark.regression_lock
def test_frames_are_cached_under_their_seed(tmp_path):
    """Regression lock of the frame cache: a second call hits and returns the same
    arrays; another seed (the independent twin) is another entry, a still scene's
    frames one entry; a damaged entry warns once and is rendered again in place."""
    frames = _frames(MOVING)[:2]
    first = render_reference_frames(frames, cache=tmp_path)
    assert [f.cache for f in first] == ["miss (absent)", "miss (absent)"]
    again = render_reference_frames(frames, cache=tmp_path)
    assert [f.cache for f in again] == ["hit", "hit"]
    np.testing.assert_array_equal(_maps(again), _maps(first))
    np.testing.assert_array_equal(_variance(again), _variance(first))
    assert again[0].photons == first[0].photons == 100_000
    twin = render_reference_frames(frames[:1], cache=tmp_path, seed=4)
    assert twin[0].cache == "miss (absent)" and twin[0].seed == 4
    # A still scene's frames are one physics and one seed: one entry, the same estimate.
    still = render_reference_frames(_frames(STILL)[1:3], cache=tmp_path, seed=8)
    assert [f.cache for f in still] == ["miss (absent)", "hit"]
    entries = sorted((tmp_path / SUBFOLDER).glob("*.npz"))
    assert len(entries) == 4

    for entry in entries:
        entry.write_bytes(entry.read_bytes()[:200])
    with pytest.warns(InvalidCacheEntryWarning, match="invalid cached reference frame"):
        repaired = render_reference_frames(frames, cache=tmp_path)
    assert all(f.cache.startswith("miss (invalid: ") for f in repaired)
    np.testing.assert_allclose(_maps(repaired), _maps(first), rtol=1e-5, atol=1e-4)
    assert len(sorted((tmp_path / SUBFOLDER).glob("*.npz"))) == 4


def test_the_cache_key_of_a_reference_ignores_the_animation():
    """``[animation]`` says how a scene moves, not what one frame is: adding it keeps
    every cached reference of the scene (the key of frame 0 is the still scene's)."""
    versions = mitsuba_versions()
    animated = parse_scene(MOVING)
    still = dataclasses.replace(animated, animation=None)
    assert cache_key(animated, versions) == cache_key(still, versions)
    moved = animation_frames(animated)[1].scene
    assert cache_key(moved, versions) != cache_key(still, versions)
