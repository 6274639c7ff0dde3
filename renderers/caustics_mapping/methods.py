"""The caustics-mapping presets as methods (:mod:`renderers.methods`).

``paper`` and ``strong`` (:mod:`.presets`) are registered in the entry-point group
``caustics_harness.methods`` by this project's ``pyproject.toml``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from renderers.caustics_mapping.presets import resolve_scene
from renderers.caustics_mapping.renderer import render
from renderers.results import RenderResult
from scenes import Scene

__all__ = ["PAPER", "STRONG", "PresetMethod"]


@dataclass(frozen=True)
class PresetMethod:
    """Caustics mapping with one preset; the scene's own settings (file and command
    line) still override the preset's choices."""

    name: str
    description: str
    studies: bool = True

    def configure(self, scene: Scene) -> Scene:
        settings = dataclasses.replace(scene.settings, preset=self.name)
        return resolve_scene(dataclasses.replace(scene, settings=settings))

    def render(self, scene: Scene) -> RenderResult:
        return render(self.configure(scene))


PAPER = PresetMethod("paper", "caustics mapping as published (Shah et al. 2007)")
STRONG = PresetMethod("strong", "caustics mapping, best known implementation")
