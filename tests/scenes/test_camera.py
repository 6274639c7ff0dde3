"""The scene camera's pinhole model (``scenes/camera.py``) against values derived by
hand from its conventions: pixel centres, the field of view along ``fov_axis``, the
roll fixed by ``up``, row 0 at the top.

Kind: exact geometry (float64; tolerances are rounding, 1e-12)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scenes.camera import camera_rays, half_fov_tangents, pinhole_directions
from scenes.model import Camera

#: Eye at the origin looking along +y, z up: forward (0, 1, 0), right (1, 0, 0),
#: image-up (0, 0, 1), so a direction's x is "right" and its z is "up" directly.
LEVEL = Camera(position=(0.0, 0.0, 0.0), look_at=(0.0, 5.0, 0.0), fov=90.0,
               resolution=(2, 2))


def _angle(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return math.acos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1))


def test_top_left_pixel_of_a_two_by_two_image():
    """fov 90 deg along x, 2 x 2 pixels: tan(half) = 1, so pixel (0, 0)'s centre
    (0.5, 0.5) sits at (2 * 0.5 / 2 - 1, 1 - 2 * 0.5 / 2) = (-0.5, +0.5) on the film
    at unit distance: direction (-0.5, 1, 0.5) / sqrt(1.5), left (x < 0) and up
    (z > 0); row 0 is the top."""
    origins, directions = camera_rays(LEVEL)
    np.testing.assert_allclose(directions[0], np.array([-0.5, 1.0, 0.5]) / math.sqrt(1.5),
                               atol=1e-12)
    np.testing.assert_allclose(directions[3], np.array([0.5, 1.0, -0.5]) / math.sqrt(1.5),
                               atol=1e-12)
    np.testing.assert_array_equal(origins, np.zeros((4, 3)))


@pytest.mark.parametrize("resolution", [(5, 3), (7, 7), (4, 6)])
def test_the_image_centre_looks_at_look_at(resolution):
    """The film's centre (W/2, H/2), for odd sizes the middle pixel's centre too,
    sees look_at exactly, from any eye and with an up vector not perpendicular to
    the view."""
    camera = Camera(position=(1.0, -4.0, 3.0), look_at=(0.5, 0.2, 0.4), fov=37.0,
                    resolution=resolution, up=(0.3, 0.2, 1.0))
    width, height = resolution
    forward = np.subtract(camera.look_at, camera.position)
    forward /= np.linalg.norm(forward)
    np.testing.assert_allclose(pinhole_directions(camera, width / 2, height / 2), forward,
                               atol=1e-12)
    if width % 2 and height % 2:
        _, directions = camera_rays(camera)
        middle = (height // 2) * width + width // 2
        np.testing.assert_allclose(directions[middle], forward, atol=1e-12)


@pytest.mark.parametrize("fov_axis", ["x", "y"])
def test_edge_rays_span_the_fov_along_its_axis(fov_axis):
    """The rays through the middles of the two edges across ``fov_axis`` are each
    fov / 2 from the view axis (fov in degrees); across the other axis the tangent
    of the half angle is tan(fov / 2) times the aspect ratio (square pixels):
    H / W for x, W / H for y."""
    width, height, fov = 320, 180, 50.0
    camera = Camera(position=(0.0, 0.0, 1.0), look_at=(2.0, 3.0, 0.0), fov=fov,
                    resolution=(width, height), fov_axis=fov_axis)
    forward = np.subtract(camera.look_at, camera.position)
    left, right = pinhole_directions(camera, [0.0, width], [height / 2] * 2)
    top, bottom = pinhole_directions(camera, [width / 2] * 2, [0.0, height])
    across, other = ((left, right), (top, bottom)) if fov_axis == "x" else (
        (top, bottom), (left, right))
    aspect = height / width if fov_axis == "x" else width / height
    half = math.radians(fov) / 2
    for ray in across:
        assert _angle(ray, forward) == pytest.approx(half, abs=1e-12)
    for ray in other:
        assert math.tan(_angle(ray, forward)) == pytest.approx(math.tan(half) * aspect,
                                                               abs=1e-12)
    assert _angle(*across) == pytest.approx(2 * half, abs=1e-12)


def test_half_fov_tangents():
    """fov 90 deg: tan 45 deg = 1 along fov_axis; the other axis scales by the
    aspect ratio, 100 / 200 or 200 / 100."""
    wide = Camera(position=(0.0, 0.0, 0.0), look_at=(0.0, 1.0, 0.0), fov=90.0,
                  resolution=(200, 100))
    assert half_fov_tangents(wide) == pytest.approx((1.0, 0.5), abs=1e-15)
    tall = Camera(position=(0.0, 0.0, 0.0), look_at=(0.0, 1.0, 0.0), fov=90.0,
                  resolution=(200, 100), fov_axis="y")
    assert half_fov_tangents(tall) == pytest.approx((2.0, 1.0), abs=1e-15)


def test_up_fixes_only_the_roll():
    """Tilting up within the plane of up and the view axis changes no ray (only
    the component of up across the view matters); turning it 90 deg about the view
    axis (up = +x, so right = forward x up = -z) turns the image: the top-left
    pixel then looks towards +x (up) and +z (left)."""
    tilted = Camera(position=LEVEL.position, look_at=LEVEL.look_at, fov=LEVEL.fov,
                    resolution=LEVEL.resolution, up=(0.0, 0.7, 1.0))
    np.testing.assert_allclose(camera_rays(tilted)[1], camera_rays(LEVEL)[1], atol=1e-12)
    rolled = Camera(position=LEVEL.position, look_at=LEVEL.look_at, fov=LEVEL.fov,
                    resolution=LEVEL.resolution, up=(1.0, 0.0, 0.0))
    np.testing.assert_allclose(camera_rays(rolled)[1][0],
                               np.array([0.5, 1.0, 0.5]) / math.sqrt(1.5), atol=1e-12)


def test_rays_are_in_row_major_image_order():
    """Ray k = i W + j goes through pixel (row i, column j)'s centre (j + 0.5,
    i + 0.5); all are unit length, all start at the eye."""
    camera = Camera(position=(0.2, -3.0, 1.5), look_at=(0.0, 0.0, 0.3), fov=30.0,
                    resolution=(4, 3), fov_axis="y")
    origins, directions = camera_rays(camera)
    assert directions.shape == (12, 3)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0, atol=1e-12)
    np.testing.assert_array_equal(origins, np.tile(camera.position, (12, 1)))
    for k in (0, 5, 11):
        i, j = divmod(k, 4)
        np.testing.assert_allclose(directions[k],
                                   pinhole_directions(camera, j + 0.5, i + 0.5), atol=1e-15)
