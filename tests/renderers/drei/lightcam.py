"""An orthographic light camera built as three.js builds the component's (its
``lookAt`` with +y up, ``makeOrthographic``), independently of the page, so the
mapping can be tested without a browser."""

from __future__ import annotations

import numpy as np

from renderers.drei.mapping import LightCamera


def light_camera(*, towards_light, focus, distance: float, half: float,
                 near: float = 0.0, far: float = 10.0) -> LightCamera:
    """A camera ``distance`` from ``focus`` towards the light (drei frame, glTF axes),
    looking at ``focus``, seeing ``half`` metres either side."""
    z = np.asarray(towards_light, float) / np.linalg.norm(towards_light)
    eye = np.asarray(focus, float) + distance * z
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    world = np.eye(4)
    world[:3, 0], world[:3, 1], world[:3, 2], world[:3, 3] = x, y, z, eye
    projection = np.array([
        [1 / half, 0, 0, 0], [0, 1 / half, 0, 0],
        [0, 0, -2 / (far - near), -(far + near) / (far - near)], [0, 0, 0, 1]])
    return LightCamera(projection, np.linalg.inv(world), -half, half, -half, half)
