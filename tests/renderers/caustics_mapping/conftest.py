"""Helpers for the caustics-mapping tests (the GL context fixtures are in
``tests/renderers/conftest.py``)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from scenes import load_scene, with_settings

ROOT = Path(__file__).resolve().parents[3]
SCENES = sorted((ROOT / "scenes").glob("*.toml")) + sorted(
    (ROOT / "scenes" / "hard").glob("*.toml"))

#: Small settings so every scene renders in well under a second on llvmpipe.
SMALL = {"grid": 48, "caustic_map": 128, "positions_map": 128, "shadow_map": 128,
         "receiver_map": [64, 64]}


def small_scene(path, *, camera=(48, 48), **settings):
    """``path`` loaded with :data:`SMALL` settings (plus ``settings``) and a small camera."""
    scene = with_settings(load_scene(path), {**SMALL, **settings})
    return dataclasses.replace(
        scene, camera=dataclasses.replace(scene.camera, resolution=camera))
