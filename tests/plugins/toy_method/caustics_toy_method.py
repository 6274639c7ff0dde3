"""A third-party method for the tests: the caustics-mapping ``paper`` render with the
camera image and every receiver map doubled, so a harness that measures this method
(and not some other) reports twice the paper preset's flux ratio."""

from __future__ import annotations

import dataclasses

from renderers.methods import load_method


class DoubledPaper:
    """Registered as ``toy-double``; the entry point names the class, which the
    harness calls to get the method."""

    name = "toy-double"
    description = "test plug-in: the paper preset's render, doubled"

    def configure(self, scene):
        return load_method("paper").configure(scene)

    def render(self, scene):
        result = load_method("paper").render(scene)
        receivers = tuple(dataclasses.replace(r, irradiance=2 * r.irradiance)
                          for r in result.receivers)
        return dataclasses.replace(result, camera=2 * result.camera, receivers=receivers,
                                   renderer="toy-double")
