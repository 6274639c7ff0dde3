"""The caustics-mapping presets as methods (:mod:`renderers.methods`).

``paper`` and ``strong`` (:mod:`.presets`) are registered in the entry-point group
``caustics_harness.methods`` by this project's ``pyproject.toml``. They are methods
like any other: the harness renders them through :meth:`PresetMethod.render`. They
also have the capability :class:`renderers.methods.GLMethod`: :meth:`PresetMethod.in_context`
gives the preset rendering in a GL context the caller holds.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from renderers.caustics_mapping.presets import resolve_scene
from renderers.caustics_mapping.renderer import render
from renderers.results import RenderResult
from scenes import Scene
from scenes.geometry import SceneGeometry

__all__ = ["PAPER", "STRONG", "PresetMethod"]


@dataclass(frozen=True)
class PresetMethod:
    """Caustics mapping with one preset; the scene's own settings (file and command
    line) still override the preset's choices.

    Attributes
    ----------
    name, description : str
        The preset's name (``paper``, ``strong``) and one line for reports.
    ctx : moderngl.Context or None
        The GL context its renders draw in (:meth:`in_context`); None: each render
        makes and releases its own.
    geometry : SceneGeometry or None
        The meshes of the scenes it renders (None: built per render).
    """

    name: str
    description: str
    ctx: Any = field(default=None, compare=False, repr=False)
    geometry: SceneGeometry | None = field(default=None, compare=False, repr=False)

    def configure(self, scene: Scene) -> Scene:
        """``scene`` with every setting it leaves unset filled from the preset."""
        settings = dataclasses.replace(scene.settings, preset=self.name)
        return resolve_scene(dataclasses.replace(scene, settings=settings))

    def render(self, scene: Scene) -> RenderResult:
        """The caustics-mapping render of ``scene`` configured by this preset (its
        ``records`` included), in :attr:`ctx` when there is one."""
        return render(self.configure(scene), ctx=self.ctx, geometry=self.geometry)

    def in_context(self, ctx: Any, *, geometry: SceneGeometry | None = None) -> PresetMethod:
        """This preset rendering in ``ctx`` on ``geometry``
        (:class:`renderers.methods.GLMethod`)."""
        return dataclasses.replace(self, ctx=ctx, geometry=geometry)


PAPER = PresetMethod("paper", "caustics mapping as published (Shah et al. 2007)")
STRONG = PresetMethod("strong", "caustics mapping, best known implementation")
