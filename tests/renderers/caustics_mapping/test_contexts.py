"""Several standalone GL contexts in one process (studies, figures and tests each
make one): a render on a context must not land in whichever was made current last.
And the per-pass timer's GL timer queries, which only a hardware context runs."""

from __future__ import annotations

import dataclasses

import numpy as np

from renderers.caustics_mapping import create_context, render
from renderers.caustics_mapping.context import PassTimer
from scenes import load_scene, with_settings
from tests.conftest import SCENES


def test_render_after_another_context_came_and_went():
    scene = with_settings(load_scene(SCENES / "glass_sphere.toml"),
                          {"grid": 32, "caustic_map": 64, "positions_map": 64,
                           "shadow_map": 64, "receiver_map": [32, 32]})
    scene = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                  resolution=(16, 16)))
    first = create_context()
    try:
        before = render(scene, ctx=first).receivers[0].irradiance
        other = create_context()
        render(scene, ctx=other)
        other.release()
        after = render(scene, ctx=first).receivers[0].irradiance
        assert first.error == "GL_NO_ERROR"
        np.testing.assert_array_equal(before, after)
    finally:
        first.release()


def test_pass_timer_runs_its_gl_timer_query_pass_after_pass():
    """Regression lock: on a hardware device each timed pass runs inside a
    GL_TIME_ELAPSED query. moderngl's Query has no ``release`` (calling it failed
    every render on an NVIDIA GPU at its first pass). Queries are forced on here: llvmpipe
    runs them but answers with an invalid count, so ``gpu_timings`` stays empty.
    Three passes in a row must run without a Python or GL error and share one query.
    A context of its own, so the shared one keeps no query or framebuffer of this test."""
    ctx = create_context()
    try:
        timer = PassTimer(ctx)
        timer.queries = True
        target = ctx.simple_framebuffer((8, 8))
        queries = set()
        for name in ("first", "second", "first"):
            with timer.measure(name):
                target.use()
                target.clear(0.5, 0.5, 0.5, 1.0)
            queries.add(id(ctx.extra["time_query"]))
        assert set(timer.timings) == {"first", "second"}
        assert len(queries) == 1
        assert ctx.error == "GL_NO_ERROR"
    finally:
        ctx.release()
