"""The camera pass's projection (``camera_matrix``, ``pixel_width``) is the scene's
pinhole (``scenes/camera.py``): a point on the ray through a film position projects
back onto that film position.

Kind: exact geometry (float64; tolerances are rounding, 1e-9)."""

from __future__ import annotations

import numpy as np
import pytest

from renderers.caustics_mapping.camera import camera_matrix, pixel_width
from scenes.camera import pinhole_directions
from scenes.model import Camera


@pytest.mark.parametrize("fov_axis", ["x", "y"])
def test_points_on_a_pinhole_ray_project_onto_its_film_position(fov_axis):
    """OpenGL's normalised device coordinates of eye + t d(fx, fy), for distances t
    from 0.5 to 20 m, are (2 fx / W - 1, 1 - 2 fy / H): the pass's image (read
    bottom row first, then flipped so row 0 is the top) has each pixel where the
    pinhole model puts it."""
    camera = Camera(position=(1.0, -6.0, 4.0), look_at=(0.0, 0.0, 0.5), fov=40.0,
                    resolution=(96, 54), up=(0.1, 0.0, 1.0), fov_axis=fov_axis)
    width, height = camera.resolution
    fx = np.array([0.0, 0.5, 17.25, 48.0, 95.5, 96.0])
    fy = np.array([0.0, 53.5, 30.0, 27.0, 0.5, 54.0])
    directions = pinhole_directions(camera, fx, fy)
    matrix = camera_matrix(camera)
    for t in (0.5, 3.0, 20.0):
        points = np.asarray(camera.position) + t * directions
        clip = np.c_[points, np.ones(len(points))] @ matrix.T
        ndc = clip[:, :2] / clip[:, 3:]
        np.testing.assert_allclose(ndc[:, 0], 2 * fx / width - 1, atol=1e-9)
        np.testing.assert_allclose(ndc[:, 1], 1 - 2 * fy / height, atol=1e-9)


def test_pixel_width_is_one_pixel_of_the_film_at_unit_distance():
    """At unit distance along the view axis the film is 2 tan(fov / 2) wide, so the
    rays through two neighbouring pixel centres meet that plane 2 tan(30 deg) / 64
    apart: pixel_width (rounding, 1e-9)."""
    camera = Camera(position=(0.0, 0.0, 0.0), look_at=(0.0, 1.0, 0.0), fov=60.0,
                    resolution=(64, 64))
    a, b = pinhole_directions(camera, [32.0, 33.0], [32.0, 32.0])
    # Both rays scaled to meet the plane y = 1 (unit distance along the view axis).
    assert np.linalg.norm(b / b[1] - a / a[1]) == pytest.approx(pixel_width(camera),
                                                               abs=1e-9)
