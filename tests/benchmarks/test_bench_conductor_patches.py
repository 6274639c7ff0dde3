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

import time

import numpy as np
import pytest

from renderers.caustics_mapping import render, render_frame
from renderers.methods import load_method
from scenes import load_scene, with_settings

from ..renderers.caustics_mapping.conftest import ROOT
from .test_bench_presets import ROUNDS, median_interval


@pytest.mark.bench
@pytest.mark.parametrize("name", ["metal_ring", "ring_point", "bowl_sun", "cup_sun"])
def test_bench_conductor_patches(ctx, name):
    strong = load_method("strong").configure(load_scene(ROOT / "scenes" / f"{name}.toml"))
    scenes = {n: with_settings(strong, {"rim_patches": n}) for n in (3, 5)}
    traced, frames = {}, {n: [] for n in scenes}
    for n, scene in scenes.items():
        traced[n] = len(render_frame(scene, ctx=ctx).patches["status"])
        render(scene, ctx=ctx)
    assert traced[5] > traced[3]
    for _ in range(ROUNDS):
        for n, scene in scenes.items():
            start = time.perf_counter()
            result = render(scene, ctx=ctx)
            frames[n].append((time.perf_counter() - start) * 1e3)
            assert np.isfinite(result.receivers[0].irradiance).all()
    ratios = np.asarray(frames[5]) / np.asarray(frames[3])
    low, high, coverage = median_interval(ratios)
    print(f"\n{name}: strong with rim patches of 3 and of 5, {ROUNDS} alternating rounds "
          "after a warm-up each (time.perf_counter around render())")
    for n in scenes:
        print(f"  patches of {n}: {traced[n]:6d} patch records, frame "
              f"{np.median(frames[n]):7.1f} ms (median, min {np.min(frames[n]):.1f})")
    print(f"  5 / 3: {np.median(ratios):.3f} (median of per-round ratios; [{low:.3f}, "
          f"{high:.3f}] holds the median with probability {coverage:.3f})")
