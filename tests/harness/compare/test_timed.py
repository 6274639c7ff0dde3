"""One road for every method (``harness.compare.timed``): the comparison pipeline,
the Python API and sweep rows render the built-in presets and a third-party plug-in
alike, through the method protocol's ``render``."""

from __future__ import annotations

import numpy as np
import pytest

from harness import api
from harness.compare.timed import gl_runner, render_method, timed_render
from harness.sweep.rows import render_row
from renderers.caustics_mapping.methods import STRONG, PresetMethod
from renderers.methods import has_gl_runner
from tests.conftest import REPO
from tests.harness.compare.test_pipeline import _small

TOY = REPO / "tests" / "plugins" / "toy_method"


@pytest.fixture()
def toy(monkeypatch):
    """The toy plug-in's class (it doubles the paper preset's render), imported from
    its folder as an installed plug-in would be."""
    monkeypatch.syspath_prepend(str(TOY))
    from caustics_toy_method import DoubledPaper  # noqa: PLC0415 - on the path just now

    return DoubledPaper


def _spy(monkeypatch, cls, calls: list) -> None:
    """Record each call of ``cls.render`` as (method name, rendered in a caller's GL
    context, the result) and pass it through."""
    real = cls.render

    def render(self, scene):
        result = real(self, scene)
        calls.append((self.name, getattr(self, "ctx", None) is not None, result))
        return result

    monkeypatch.setattr(cls, "render", render)


def test_a_preset_and_a_plug_in_render_through_the_protocol(tmp_path, monkeypatch, toy):
    """Regression lock (one road): ``harness.api.compare`` of the ``strong`` preset and
    of the toy plug-in (metrics only, quick: one warm-up and one timed render each)
    calls each method's own ``render`` twice, the preset's in the GL runner's
    context, and scores the last call's result; a sweep row renders through it too.
    The plug-in wraps ``paper``, whose ``render`` it calls in its own context."""
    calls: list = []
    _spy(monkeypatch, PresetMethod, calls)
    _spy(monkeypatch, toy, calls)
    plugin = toy()
    assert has_gl_runner(STRONG) and not has_gl_runner(plugin)
    result = api.compare(_small(tmp_path), ["strong", plugin], studies=("metrics",),
                         quick=True, checks=False)
    names = [(name, in_context) for name, in_context, _ in calls]
    assert names == [("strong", True)] * 2 + [("paper", False), ("toy-double", False)] * 2
    for method in ("strong", "toy-double"):
        last = [r for name, _, r in calls if name == method][-1]
        scored = result.get(method).record.images["receiver0/method"]
        assert np.array_equal(scored, last.receivers[0].irradiance), method
    calls.clear()
    scene = STRONG.configure(_small(tmp_path))
    row = render_row(scene, "strong", repeats=1)
    assert [(name, in_context) for name, in_context, _ in calls] == [("strong", True)] * 2
    assert row.timed.result is calls[-1][2] and row.timed.hits is not None


def test_the_presets_render_in_a_runner_is_the_runners_frame(tmp_path):
    """Regression lock: ``strong``'s render through the protocol in its GL runner's
    context draws exactly the runner's frame of the same scene (what the studies
    render) and what the preset renders in a context of its own, bit for bit; so
    the runner books it as its configuration without overrides."""
    scene = STRONG.configure(_small(tmp_path))
    own = STRONG.render(scene)
    with gl_runner(STRONG, scene, repeats=1) as runner:
        road = render_method(STRONG, scene, ctx=runner.ctx, geometry=runner.geometry)
        frame = runner.render().result
    for other in (frame, own):
        assert np.array_equal(road.camera, other.camera)
        assert np.array_equal(road.receivers[0].irradiance, other.receivers[0].irradiance)
        assert road.metadata["passes"] == other.metadata["passes"]
    assert np.array_equal(road.records["flux"], frame.records["flux"])


def test_the_road_refuses_a_context_it_cannot_use(tmp_path, toy):
    """Physical requirement of the timing policy: a method with a GL runner is timed
    in it, never silently in contexts of its own; a method without one is never
    handed a context."""
    scene = STRONG.configure(_small(tmp_path))
    with pytest.raises(ValueError, match="has a GL runner"):
        timed_render(STRONG, scene, repeats=1)
    with pytest.raises(ValueError, match="has no GL runner"):
        render_method(toy(), scene, ctx=object())
    with gl_runner(toy(), scene, repeats=1) as runner:
        assert runner is None
