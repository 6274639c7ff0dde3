"""Scenes the export tests share."""

from __future__ import annotations

import dataclasses

from scenes import Scene, load_scene, resolve_scene
from scenes.model import AreaLight


def area_light_scene() -> Scene:
    """glass_sphere lit by a 0.5 m x 0.25 m area light facing down (no bundled scene has
    one)."""
    scene = load_scene(resolve_scene("glass_sphere"))
    return dataclasses.replace(scene, light=AreaLight(
        center=(1.0, -0.5, 6.0), normal=(0.0, 0.0, -1.0), size=(0.5, 0.25),
        intensity=(30.0, 20.0, 10.0)))
