"""Property-based tests of the NumPy estimators (the mirror the shader is held to) on
synthetic positions atlases: an orthographic light looking down −z on a heightfield
over [−1, 1]², rays from above in random directions."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

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


@settings(max_examples=150, deadline=None)
@given(spec=heights, samples=st.lists(rays, min_size=1, max_size=16),
       estimator=st.sampled_from(["modified", "newton", "secant"]),
       safeguarded=st.booleans(), iterations=st.integers(0, 16),
       eps=st.floats(1e-4, 0.1))
def test_estimates_are_finite_and_statuses_valid(*, spec, samples, estimator, safeguarded,
                                                 iterations, eps):
    """Any receiver, any ray, any estimator: finite history, a valid status; the
    safeguarded forms never diverge and never go behind the ray origin."""
    v, r = _rays(samples)
    result = estimate_distances(_atlas(_height(spec)), v, r, estimator=estimator,
                                iterations=iterations, eps=eps, safeguarded=safeguarded)
    assert result.history.shape == (len(v), iterations + 1)
    assert np.isfinite(result.history).all() and np.isfinite(result.distance).all()
    assert set(np.unique(result.status)) <= {HIT, LOST, DIVERGED}
    if safeguarded:
        assert not np.any(result.status == DIVERGED)
        assert np.all(result.distance >= 0)


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
