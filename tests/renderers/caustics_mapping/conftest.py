"""Fixtures for the caustics-mapping tests, in the style of moderngl's own
tests/conftest.py: ONE context factory for the session, and a ``ctx`` fixture that
asserts the context holds no GL error before and after every test."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from harness.scene import load_scene, with_settings
from renderers.caustics_mapping import create_context

ROOT = Path(__file__).resolve().parents[3]
SCENES = sorted((ROOT / "scenes").glob("*.toml")) + sorted(
    (ROOT / "scenes" / "hard").glob("*.toml"))

#: Small settings so every scene renders in well under a second on llvmpipe.
SMALL = {"grid": 48, "caustic_map": 128, "positions_map": 128, "shadow_map": 128,
         "receiver_map": [64, 64]}


@pytest.fixture(scope="session")
def context_factory():
    """The one place a GL context is created; shared by the whole session."""
    ctx = create_context()
    yield lambda: ctx
    ctx.release()


@pytest.fixture
def ctx(context_factory):
    """The session's context, asserting GL_NO_ERROR before and after the test."""
    context = context_factory()
    assert context.error == "GL_NO_ERROR"
    yield context
    assert context.error == "GL_NO_ERROR"


def small_scene(path, *, camera=(48, 48), **settings):
    """``path`` loaded with :data:`SMALL` settings (plus ``settings``) and a small camera."""
    scene = with_settings(load_scene(path), {**SMALL, **settings})
    return dataclasses.replace(
        scene, camera=dataclasses.replace(scene.camera, resolution=camera))
