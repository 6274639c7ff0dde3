"""Exact ray casting against the receivers, on cases with analytic answers."""

from __future__ import annotations

import numpy as np
import pytest

from harness.raycast import cast_rays
from scenes import load_scene
from scenes.geometry import build_geometry
from tests.conftest import SCENES


def test_plane_hits_are_analytic():
    """Rays from z = 2 towards the z = 0 floor: d = 2 / |r_z|; rays leaving the
    8 m floor or pointing up hit nothing (inf, receiver −1). float32 tracing:
    1e-5 relative tolerance."""
    geometry = build_geometry(load_scene(SCENES / "glass_sphere.toml"))
    origins = np.array([[0, 0, 2], [1, 1, 2], [0, 0, 2], [0, 0, 2]], float)
    directions = np.array([[0, 0, -1], [0.3, 0.4, -1], [1, 0, -0.1], [0, 0, 1]], float)
    hits = cast_rays(geometry, origins, directions)
    expected = 2 * np.linalg.norm(directions[1]) / 1.0
    np.testing.assert_allclose(hits.distance[:2], [2.0, expected], rtol=1e-5)
    assert np.isinf(hits.distance[2:]).all() and hits.receiver[2:].tolist() == [-1, -1]
    np.testing.assert_allclose(hits.position[1], [1.6, 1.8, 0.0], atol=1e-5)


def test_nearest_of_several_receivers():
    """Seabed: a ray straight down onto the rock hits the rock (receiver 1) before
    the seabed beneath it (receiver 0)."""
    geometry = build_geometry(load_scene(SCENES / "seabed.toml"))
    rock_top = geometry.receivers[1].mesh.positions.max(axis=0)
    centre = geometry.receivers[1].mesh.positions.mean(axis=0)
    hits = cast_rays(geometry, [[centre[0], centre[1], 3.0], [-1.5, -1.5, 3.0]],
                     [[0, 0, -1], [0, 0, -1]])
    assert hits.receiver.tolist() == [1, 0]
    assert hits.distance[0] == pytest.approx(3.0 - rock_top[2], abs=0.05)


def test_no_rays():
    """An empty batch returns empty arrays (Dr.Jit itself aborts on empty launches)."""
    geometry = build_geometry(load_scene(SCENES / "glass_sphere.toml"))
    hits = cast_rays(geometry, np.zeros((0, 3)), np.zeros((0, 3)))
    assert hits.distance.shape == (0,) and hits.position.shape == (0, 3)
