"""Benchmark: what the strong preset's finer rim patches on conductors cost
(``presets._CONDUCTOR_RIM_PATCHES``: 5 x 5 where the scene has a conductor, 3 x 3
elsewhere; docs/method.md, "Rim patches"), as a ratio taken in one run.

The same scene at its own settings renders with patches of 3 and of 5, in one GL
context; each is warmed up once, then ``ROUNDS`` rounds alternate the two, so drift of
the machine falls on both alike. Reported: the patch vertices traced, the median frame
(``time.perf_counter`` around ``render()``), and the median over rounds of the
per-round ratio 5 / 3 with its distribution-free 95 % interval
(:func:`.test_bench_presets.median_interval`). Fails only on a broken render, or where
patches of 5 trace no more vertices than patches of 3.
"""

from __future__ import annotations

import pytest

from renderers.caustics_mapping import render, render_frame
from renderers.methods import load_method
from scenes import load_scene, with_settings

from ..renderers.caustics_mapping.conftest import ROOT
from .test_bench_presets import alternating_frames, print_ratio


@pytest.mark.bench
@pytest.mark.parametrize("name", ["metal_ring", "ring_point", "bowl_sun", "cup_sun"])
def test_bench_conductor_patches(ctx, name):
    strong = load_method("strong").configure(load_scene(ROOT / "scenes" / f"{name}.toml"))
    scenes = {n: with_settings(strong, {"rim_patches": n}) for n in (3, 5)}
    traced = {}
    for n, scene in scenes.items():
        traced[n] = len(render_frame(scene, ctx=ctx).patches["status"])
        render(scene, ctx=ctx)
    assert traced[5] > traced[3]
    frames = alternating_frames(scenes, lambda n: render(scenes[n], ctx=ctx))
    print_ratio(f"{name}: strong with rim patches of 3 and of 5", frames,
                {n: f"patches of {n}: {traced[n]:6d} patch records" for n in (3, 5)},
                over=(5, 3))
