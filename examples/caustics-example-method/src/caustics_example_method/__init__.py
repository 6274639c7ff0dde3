"""An example caustics method for the harness: the ``strong`` caustics-mapping preset
with every receiver's caustic irradiance map scaled by a factor (1 by default).

A method is an object with ``name``, ``description``, ``configure(scene)`` and
``render(scene)`` (``renderers.methods.Method``); this package registers
:class:`ExampleMethod` in the entry-point group ``caustics_harness.methods`` as
``example`` (``pyproject.toml``), and the tests build a broken variant with
``ExampleMethod(scale=1.05)``.
"""

from __future__ import annotations

import dataclasses

from renderers.methods import load_method

__all__ = ["ExampleMethod"]


class ExampleMethod:
    """The ``strong`` preset's render with each receiver's irradiance map (W/m^2, RGB)
    multiplied by ``scale``.

    Parameters
    ----------
    scale : float
        Factor on the caustic irradiance maps; 1 leaves the render as it is.
    name : str
        The name reports give it (``example``, or e.g. ``example-x1.05``).
    """

    description = "example plug-in: the strong preset, caustic maps scaled"

    def __init__(self, scale: float = 1.0, name: str | None = None):
        self.scale = float(scale)
        self.name = name or ("example" if self.scale == 1.0 else f"example-x{self.scale:g}")
        self._base = load_method("strong")

    def configure(self, scene):
        """The scene with the strong preset's settings (any set in the scene win)."""
        return self._base.configure(scene)

    def render(self, scene):
        """The strong preset's render, its receiver maps times :attr:`scale`."""
        result = self._base.render(scene)
        receivers = tuple(dataclasses.replace(r, irradiance=self.scale * r.irradiance)
                          for r in result.receivers)
        return dataclasses.replace(result, receivers=receivers, renderer=self.name)
