"""The scene camera's pinhole model: the ray each point of the image sees.

One model for every layer: the reference renders with Mitsuba's ``perspective``
sensor, the caustics-mapping camera pass projects with the same field of view
(:func:`half_fov_tangents`), and the harness's exact tracers and checks cast these
rays (:func:`pinhole_directions`, :func:`camera_rays`).

Conventions (``camera`` is a :class:`scenes.model.Camera`; positions in metres):

* The eye is at ``camera.position`` and looks along
  ``forward = normalize(look_at - position)``: the ray through the image's centre.
* ``right = normalize(forward x up)`` and ``image_up = right x forward``: ``up``
  only fixes the roll (it need not be perpendicular to ``forward``). Image x grows
  to the right, image rows grow downwards: row 0 is the top of the image.
* Film positions ``(fx, fy)`` are in pixels from the image's left and top edges:
  pixel (row i, column j) covers ``[j, j + 1] x [i, i + 1]``, its centre at
  ``(j + 0.5, i + 0.5)``; the image is ``resolution = (W, H)`` pixels.
* ``fov`` (degrees) is the full angle between the rays through the middles of the
  two opposite image edges along ``fov_axis`` (``"x"``: left and right, Mitsuba's
  default). Pixels are square, so along the other axis the tangent of the half
  angle scales with the aspect ratio: for ``fov_axis = "x"``,
  ``tan(half_y) = tan(fov / 2) H / W``.

A film position maps to the direction::

    d = forward + (2 fx / W - 1) tan(half_x) right + (1 - 2 fy / H) tan(half_y) image_up

normalised to unit length.
"""

from __future__ import annotations

import math

import numpy as np

from scenes.model import Camera

__all__ = ["camera_rays", "half_fov_tangents", "pinhole_directions"]


def half_fov_tangents(camera: Camera) -> tuple[float, float]:
    """Tangents of the half field of view along image x and image y.

    Returns
    -------
    tan_x, tan_y : float
        Half-width and half-height of the image at unit distance along the view
        axis (dimensionless); ``tan_x / tan_y = W / H`` (square pixels).
    """
    width, height = camera.resolution
    half = math.tan(math.radians(camera.fov) / 2)
    return (half, half * height / width) if camera.fov_axis == "x" else (
        half * width / height, half)


def _frame(camera: Camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit forward, right and image-up vectors (see the module docstring)."""
    eye = np.asarray(camera.position, np.float64)
    forward = np.asarray(camera.look_at, np.float64) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, np.asarray(camera.up, np.float64))
    right /= np.linalg.norm(right)
    return forward, right, np.cross(right, forward)


def pinhole_directions(camera: Camera, fx, fy) -> np.ndarray:
    """Unit directions of the rays through film positions ``(fx, fy)``.

    Parameters
    ----------
    camera : Camera
    fx, fy : array_like, broadcastable
        Film positions in pixels from the image's left and top edges (the centre of
        pixel (row i, column j) is ``(j + 0.5, i + 0.5)``); any shape.

    Returns
    -------
    ndarray, (..., 3), float64
        Unit world-space directions (the broadcast shape of ``fx`` and ``fy``, then 3).
    """
    width, height = camera.resolution
    tan_x, tan_y = half_fov_tangents(camera)
    forward, right, up = _frame(camera)
    sx = (np.asarray(fx, np.float64) / width * 2 - 1) * tan_x
    sy = (1 - np.asarray(fy, np.float64) / height * 2) * tan_y
    d = forward + sx[..., None] * right + sy[..., None] * up
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def camera_rays(camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Primary rays through the pixel centres.

    Returns
    -------
    origins, directions : ndarray, (H W, 3), float64
        The eye (m), repeated, and unit directions; rows in image order (row-major,
        row 0 at the top).
    """
    width, height = camera.resolution
    fx, fy = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    directions = pinhole_directions(camera, fx, fy).reshape(-1, 3)
    origins = np.broadcast_to(np.asarray(camera.position, np.float64), directions.shape)
    return origins.copy(), directions
