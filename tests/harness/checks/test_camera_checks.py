"""The camera checks of ``compare`` (harness/checks/camera.py) fail on the two wrong
lens images a renderer can draw (black, or one refraction to a plane). Kind:
physical requirement (the reference's lens image) and method target measures; that
the real renderers pass is shown by tests/renderers/mitsuba/test_camera_trace.py and
tests/renderers/caustics_mapping/test_camera_pass.py, and by test_method_targets.py."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.checks.camera import LENS_BOUND, camera_measures, camera_requirements, exact_camera
from harness.checks.sphere_camera import luminance
from renderers.results import ReceiverMap
from scenes import load_scene
from scenes.geometry import build_geometry
from tests.conftest import SCENES


@pytest.fixture(scope="module")
def sphere():
    scene = load_scene(SCENES / "glass_sphere.toml")
    scene = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                  resolution=(96, 96)))
    extent = build_geometry(scene).receivers[0].extent
    no_caustic = ReceiverMap(np.zeros((8, 8, 3), np.float32), extent)
    return scene, exact_camera(scene, [no_caustic])


def test_a_black_sphere_fails_the_lens_image(sphere):
    """ptracer draws the sphere black: its black fraction 1 is far from the exact
    lens image's (about 0.5 without the caustic), beyond the bound 0.05
    (harness/checks/camera.py)."""
    _, exact = sphere
    black = exact.image.copy()
    black[exact.sphere] = 0
    (check,) = camera_requirements(exact, black)
    assert check.subject == "reference" and check.bound == LENS_BOUND
    assert not check.passed and check.value > 0.4


def test_a_uniform_grey_ball_misses_the_method_targets(sphere):
    """The old single refraction to a plane drew a uniform grey ball (1.5 % black):
    filling the sphere with its mean radiance misses the black fraction by over the
    0.08 target."""
    _, exact = sphere
    grey = exact.image.copy()
    grey[exact.sphere] = exact.image[exact.interior].mean(axis=0)
    measures = camera_measures(exact, grey)
    assert measures["camera_black_fraction_difference"] > 0.4
    assert luminance(grey)[exact.interior].min() > 0


def test_exact_camera_applies_only_where_the_ideal_sphere_does():
    """The bunny is not a sphere: no exact lens image, so no camera check."""
    scene = load_scene(SCENES / "bunny.toml")
    assert exact_camera(scene, [None]) is None
