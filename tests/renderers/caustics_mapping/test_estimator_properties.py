"""Property-based tests of the NumPy estimators (the mirror the shader is held to) on
synthetic positions atlases: an orthographic light looking down −z on a heightfield
over [−1, 1]², rays from above in random directions."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from harness.studies.convergence import classify
from renderers.caustics_mapping.estimators import DIVERGED, HIT, LOST, MapLookup, estimate_distances

SIZE = 64
#: World -> clip of the orthographic view: x and y map to NDC unchanged.
VIEW = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, -0.1, 0], [0, 0, 0, 1.0]])


def _atlas(height) -> MapLookup:
    """Row 0 at the bottom: texel (i, j) holds the receiver point under its centre."""
    c = (np.arange(SIZE) + 0.5) / SIZE * 2 - 1
    x, y = np.meshgrid(c, c)
    atlas = np.stack([x, y, height(x, y), np.ones_like(x)], -1).astype(np.float32)
    return MapLookup(atlas, VIEW[None], SIZE, False, np.zeros(3))


heights = st.one_of(
    st.tuples(st.just("plane"), st.floats(-0.5, 0.5), st.floats(-0.5, 0.5),
              st.floats(-0.5, 0.0)),
    st.tuples(st.just("steps"), st.floats(0.05, 0.4), st.floats(0.1, 0.5), st.just(0.0)),
    st.tuples(st.just("sines"), st.floats(0.01, 0.3), st.floats(0.1, 1.0), st.just(0.0)),
)


def _height(spec):
    kind, a, b, c = spec
    if kind == "plane":
        return lambda x, y: a * x + b * y + c
    if kind == "steps":
        return lambda x, y: a * np.floor(x / b) - 1.0
    return lambda x, y: a * np.sin(2 * np.pi * x / b) - 1.0


rays = st.tuples(st.floats(-0.7, 0.7), st.floats(-0.7, 0.7), st.floats(0.5, 2.0),
                 st.floats(-0.6, 0.6), st.floats(-0.6, 0.6))


def _rays(samples):
    v = np.array([[x, y, z] for x, y, z, _, _ in samples], np.float32)
    r = np.array([[dx, dy, -1.0] for _, _, _, dx, dy in samples], np.float64)
    return v, (r / np.linalg.norm(r, axis=1, keepdims=True)).astype(np.float32)


def _cell_centre(a):
    """Centre of the atlas texel holding coordinate ``a`` in [-1, 1)."""
    index = np.floor((np.clip(a, -1, 1 - 1e-9) + 1) / 2 * SIZE)
    return (index + 0.5) / SIZE * 2 - 1


def _exact_distances(height, v, r, *, reach=8.0, steps=8000):
    """Distance along each ray to the first point under the surface the atlas holds
    (each texel's height at its centre), marched in steps of 1 mm; inf where the ray
    leaves [-1, 1]² first. Independent of the estimators."""
    d = np.linspace(0.0, reach, steps)
    p = v[:, None, :].astype(np.float64) + d[None, :, None] * r[:, None, :]
    inside = (np.abs(p[..., 0]) < 1) & (np.abs(p[..., 1]) < 1)
    below = inside & (p[..., 2] <= height(_cell_centre(p[..., 0]), _cell_centre(p[..., 1])))
    return np.where(below.any(axis=1), d[np.argmax(below, axis=1)], np.inf)


def _outcomes(spec, v, r, result):
    """Outcome of each ray from the history of its estimates against the exact
    distance (harness.studies.convergence.classify: diverged = the last estimate not
    finite, negative or over 10x the exact distance; oscillating = the last two steps
    change sign, the last at least 3/4 of the one before and over one texel)."""
    exact = _exact_distances(_height(spec), v, r)
    return classify(result.history, result.status == LOST, exact, 2.0 / SIZE)


@settings(max_examples=150, deadline=None)
@given(spec=heights, samples=st.lists(rays, min_size=1, max_size=16),
       estimator=st.sampled_from(["modified", "newton", "secant"]),
       safeguarded=st.booleans(), iterations=st.integers(0, 16),
       eps=st.floats(1e-4, 0.1))
def test_estimates_are_finite_and_statuses_valid(*, spec, samples, estimator, safeguarded,
                                                 iterations, eps):
    """Any receiver, any ray, any estimator: finite history, a valid status; the
    safeguarded forms never go behind the ray origin, and never diverge or oscillate
    judged from the history of their estimates against the exact distance (not from
    the status they assign themselves, which is never DIVERGED when safeguarded).
    With zero iterations the history is the start estimate alone (the distance to the
    receiver's plane along the ray, no step of the estimator taken), which can exceed
    10x a tiny exact distance: there is no iterate to judge, so only the history's
    finiteness is checked (hypothesis found such a ray at iterations=0, eps=0.0625).
    A ray that starts on the surface the atlas holds (exact distance 0: hypothesis
    found an origin at a step's top, z = 1) has nothing to converge to and is not
    judged either."""
    v, r = _rays(samples)
    result = estimate_distances(_atlas(_height(spec)), v, r, estimator=estimator,
                                iterations=iterations, eps=eps, safeguarded=safeguarded)
    assert result.history.shape == (len(v), iterations + 1)
    assert np.isfinite(result.history).all() and np.isfinite(result.distance).all()
    assert set(np.unique(result.status)) <= {HIT, LOST, DIVERGED}
    if safeguarded:
        assert np.all(result.distance >= 0)
    if safeguarded and iterations > 0:
        outcomes = _outcomes(spec, v, r, result)
        judged = _exact_distances(_height(spec), v, r) > 0
        assert not np.any(np.isin(outcomes[judged], ["diverged", "oscillating"])), outcomes


def test_history_judgement_catches_plain_newton():
    """The judgement above can fail: plain Newton on a staircase (steps 0.3 high,
    0.2 wide) with a small finite-difference step oscillates or runs away on some of
    64 fixed rays (seeded; measured 9, asserted at least 3), and its safeguarded form
    on the same rays does neither."""
    rng = np.random.default_rng(7)
    samples = [(rng.uniform(-.7, .7), rng.uniform(-.7, .7), rng.uniform(.5, 2),
                rng.uniform(-.6, .6), rng.uniform(-.6, .6)) for _ in range(64)]
    v, r = _rays(samples)
    spec = ("steps", 0.3, 0.2, 0.0)
    bad = {}
    for safeguarded in (False, True):
        result = estimate_distances(_atlas(_height(spec)), v, r, estimator="newton",
                                    iterations=8, eps=1e-3, safeguarded=safeguarded)
        outcomes = _outcomes(spec, v, r, result)
        bad[safeguarded] = int(np.isin(outcomes, ["diverged", "oscillating"]).sum())
    print(f"plain Newton: {bad[False]} of 64 rays diverged or oscillating; "
          f"safeguarded: {bad[True]}")
    assert bad[False] >= 3 and bad[True] == 0, bad


@settings(max_examples=100, deadline=None)
@given(spec=heights, samples=st.lists(st.tuples(st.floats(-0.7, 0.7), st.floats(-0.7, 0.7),
                                                st.floats(0.5, 2.0)), min_size=1, max_size=8),
       estimator=st.sampled_from(["modified", "newton", "secant"]),
       safeguarded=st.booleans(), iterations=st.integers(0, 8))
def test_ray_along_the_light_is_exact_from_the_start(spec, samples, estimator, safeguarded,
                                                     iterations):
    """A ray parallel to the light (r = −z, the ior-1 case): the start estimate g(0)
    is already the receiver under v, h(d) = 0, and no estimator moves it."""
    v = np.array(samples, np.float32)
    r = np.tile(np.array([0, 0, -1], np.float32), (len(v), 1))
    lookup = _atlas(_height(spec))
    result = estimate_distances(lookup, v, r, estimator=estimator, iterations=iterations,
                                eps=1e-3, safeguarded=safeguarded)
    t, ok = lookup.receiver_at(v)
    expected = np.linalg.norm(t - v, axis=1)
    assert np.all(result.status[ok] == HIT) and np.all(result.status[~ok] == LOST)
    np.testing.assert_allclose(result.distance[ok], expected[ok], rtol=1e-6)
