"""The exact fates of the vertices whose search ended without a verified hit
(harness/checks/stability.py ``search_outcomes``) and their rows in the method's flux
budget (harness/compare/budget.py), on hand-made records over the deep bowl scene:
rays whose exact answer is known from the scene's geometry alone (a unit hemispherical
bowl with its pole on the floor at the origin and its rim at z = 1; a 12 m floor)."""

from __future__ import annotations

import numpy as np
import pytest

from harness.checks.stability import search_outcomes
from harness.compare.budget import SEARCH_ROWS, method_budget
from renderers.caustics_mapping.caustic_trace import STATUS
from scenes import load_scene
from scenes.geometry import build_geometry
from tests.conftest import SCENES

BOWL = SCENES / "hard" / "concave" / "bowl_deep_sun30.toml"


@pytest.fixture(scope="module")
def bowl():
    scene = load_scene(BOWL)
    return scene, build_geometry(scene)


def _records():
    """Six vertices, fluxes 1 to 6 W per channel (15 W a channel traced, the empty
    vertex left out):
    upwards from above the bowl (leaves, unconverged, 1 W), down into the bowl half
    a metre off its axis (meets it at z = 0.13: lost, 2 W), down onto the floor beside it
    (a receiver: the estimator failed, unconverged, 3 W; diverged, 4 W), a splatted
    hit pointing down onto the floor (not judged, 5 W) and an empty vertex (6 W, not
    traced: left out of every share)."""
    origin = np.array([[0, 0, 3], [0.5, 0, 3], [3, 3, 1], [-3, 2, 1], [3, -3, 1], [0, 0, 3.0]])
    direction = np.array([[0, 0, 1], [0, 0, -1], [0, 0, -1], [0.1, 0, -1], [0, 0, -1],
                          [0, 0, -1.0]])
    status = np.array([STATUS[s] for s in ("unconverged", "lost", "unconverged", "diverged",
                                           "hit", "empty")])
    flux = np.repeat(np.arange(1.0, 7.0)[:, None], 3, axis=1)
    return {"status": status, "origin": origin, "direction": direction, "flux": flux,
            "receiver": np.full(6, -1)}


def test_search_outcomes_sort_the_unfound_flux_by_exact_rays(bowl):
    """Regression lock on hand-derived shares (known answer): leaves 1/15, meets the
    object 2/15, estimator failed (3 + 4)/15 of the traced 15 W a channel; the three
    add up to the lost, unconverged and diverged statuses' share, 10/15."""
    scene, geometry = bowl
    shares = search_outcomes(scene, geometry, _records())
    assert shares["leaves_scene_flux_fraction"] == pytest.approx(1 / 15)
    assert shares["meets_object_flux_fraction"] == pytest.approx(2 / 15)
    assert shares["estimator_failed_flux_fraction"] == pytest.approx(7 / 15)


def test_method_budget_shows_the_three_fates_apart(bowl):
    """Regression lock: the budget's detail rows carry the three shares (and the
    re-entered vertices' share that reaches a receiver, 0 here) under their own keys,
    in watts of the traced flux (15 W a channel, 45 W summed)."""
    scene, geometry = bowl
    hits = _records()
    stability = search_outcomes(scene, geometry, hits)
    table = method_budget({}, stability, [], hits).records()
    rows = {r["key"]: r for r in table if r["role"] == "detail"}
    for key, short, _ in SEARCH_ROWS:
        assert rows[short]["fraction"] == pytest.approx(stability[key])
        assert rows[short]["flux_w"] == pytest.approx(45.0 * stability[key])


def test_an_origin_just_inside_its_own_surface_is_not_a_second_meeting(bowl):
    """Regression lock (known answer): an unconverged vertex 3 mm inside the bowl's
    wall (radius 0.997 about the sphere's centre (0, 0, 1), 45 deg below the rim),
    its ray radial and outwards, meets the wall at once and then the floor at
    x = 1: its flux is the estimator's failure, not a second meeting with the bowl."""
    scene, geometry = bowl
    s = np.sqrt(0.5)
    hits = {"status": np.array([STATUS["unconverged"]]),
            "origin": np.array([[0.997 * s, 0.0, 1.0 - 0.997 * s]]),
            "direction": np.array([[s, 0.0, -s]]), "flux": np.ones((1, 3)),
            "receiver": np.array([-1])}
    shares = search_outcomes(scene, geometry, hits)
    assert shares["estimator_failed_flux_fraction"] == pytest.approx(1.0)
    assert shares["meets_object_flux_fraction"] == 0.0


def test_a_reentered_vertex_whose_ray_meets_the_floor_is_light_a_test_dropped(bowl):
    """Regression lock on hand-derived shares (known answer): of three vertices, 7 W a
    channel traced, one ended as re-entered with its ray down into the bowl (meets it:
    the chain truly ends, 1 W), one ended as re-entered with its ray down onto the floor
    beside the bowl (2 W: a test dropped light that reaches a receiver) and one
    unconverged onto the floor (4 W: the estimator failed). The re-entered vertices
    stay out of the three fates of the unfound ones."""
    scene, geometry = bowl
    hits = {"status": np.array([STATUS[s] for s in ("reentered", "reentered", "unconverged")]),
            "origin": np.array([[0.5, 0, 3], [3, 3, 1], [-3, 2, 1.0]]),
            "direction": np.array([[0, 0, -1], [0, 0, -1], [0, 0, -1.0]]),
            "flux": np.repeat(np.array([[1.0], [2.0], [4.0]]), 3, axis=1),
            "receiver": np.full(3, -1)}
    shares = search_outcomes(scene, geometry, hits)
    assert shares["reentered_reaches_receiver_flux_fraction"] == pytest.approx(2 / 7)
    assert shares["estimator_failed_flux_fraction"] == pytest.approx(4 / 7)
    assert shares["meets_object_flux_fraction"] == 0.0
    assert shares["leaves_scene_flux_fraction"] == 0.0
