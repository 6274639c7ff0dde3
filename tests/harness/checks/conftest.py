"""Fixtures of the accuracy-check tests: the session's GL context for a module, the
folder failure images go to, and the method's renders at the golden settings."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from harness.checks import GOLDEN_DIR
from harness.checks.golden import golden_scene, load_golden
from renderers.caustics_mapping import render
from scenes import with_settings
from tests.conftest import SCENES


@pytest.fixture(scope="module")
def ctx_module(context_factory):
    """The session's GL context, error-free after this module's renders."""
    ctx = context_factory()
    with ctx:
        yield ctx
        assert ctx.error == "GL_NO_ERROR"


@pytest.fixture(scope="session")
def failure_dir(tmp_path_factory) -> Path:
    """Where a failing check writes its images (method, reference, difference,
    p-value): ``$CAUSTICS_FAILURE_DIR`` if set, else a folder under pytest's basetemp.
    Every failure message prints the path."""
    named = os.environ.get("CAUSTICS_FAILURE_DIR")
    if named:
        Path(named).mkdir(parents=True, exist_ok=True)
        return Path(named)
    return tmp_path_factory.mktemp("accuracy-failures")


class GoldenRenders:
    """Lazily rendered caustics-mapping results at the golden settings, per (scene,
    method), and the golden references, each made once per session."""

    def __init__(self, ctx):
        self.ctx = ctx
        self._results, self._golden = {}, {}

    def golden(self, name):
        if name not in self._golden:
            self._golden[name] = load_golden(GOLDEN_DIR, name)
        return self._golden[name]

    def scene(self, name, method):
        return with_settings(golden_scene(SCENES, name), {"preset": method})

    def result(self, name, method):
        """RenderResult of the method at the golden settings (camera 16 x 16)."""
        import dataclasses  # noqa: PLC0415

        key = (name, method)
        if key not in self._results:
            scene = self.scene(name, method)
            small = dataclasses.replace(scene, camera=dataclasses.replace(
                scene.camera, resolution=(16, 16)))
            with self.ctx:
                self._results[key] = render(small, ctx=self.ctx)
        return self._results[key]

    def maps(self, name, method):
        return [m.irradiance for m in self.result(name, method).receivers]


@pytest.fixture(scope="session")
def golden_renders(context_factory) -> GoldenRenders:
    """Shared by the physical-requirement and regression-lock tests (one render each)."""
    return GoldenRenders(context_factory())

