"""The drei tests' one browser render: the glass sphere under the sun, small (128²
texture, 64² map, 48² camera), on the test session's Chromium (``tests/browser.py``).

Needs the JavaScript workspace (``npm ci --prefix renderers/web``) and Chromium with
Playwright; without them the tests that use it are skipped locally and fail on CI
(``CI`` set)."""

from __future__ import annotations

import dataclasses
import os

import pytest

from renderers.drei import bundle, driver
from renderers.drei.method import DreiMethod
from scenes import load_scene, with_settings
from tests.renderers.drei.scenes import SUN_SCENE


@pytest.fixture(scope="session")
def small_sun():
    """The sun scene at the browser tests' sizes."""
    scene = with_settings(load_scene(SUN_SCENE), {"caustic_map": 128,
                                                  "receiver_map": [64, 64]})
    return dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                 resolution=(48, 48)))


@pytest.fixture(scope="session")
def drei(chromium, small_sun):
    """drei-caustics' render of :func:`small_sun` (a ``DreiRender``)."""
    reason = bundle.unavailable_reason() or driver.unavailable_reason()
    if reason:
        if os.environ.get("CI"):
            pytest.fail(f"the drei page must run on CI: {reason}")
        pytest.skip(reason)
    return DreiMethod(browser=chromium, repeats=1).render_all(small_sun)
