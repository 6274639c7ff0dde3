"""Benchmark: the two caustics-mapping presets' frame times, and their ratio, taken
in one run (docs/method.md, "Presets: paper and strong").

Both presets render the same scene at its own settings in one GL context; each is
warmed up once (shader compilation is not a frame cost), then ROUNDS rounds alternate
paper and strong, so drift of the machine falls on both alike. Reported per preset:
the median wall time of ``render()`` (``time.perf_counter``, which on llvmpipe
includes the ``ctx.finish()`` inside every pass) and the median of each pass; and
the median over rounds of the per-round ratio strong / paper. Fails only on a
broken render.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from renderers.caustics_mapping import render
from renderers.methods import load_method
from scenes import load_scene

from ..renderers.caustics_mapping.conftest import ROOT

ROUNDS = 7


@pytest.mark.bench
@pytest.mark.parametrize("name", ["glass_sphere", "bunny"])
def test_bench_presets(ctx, name):
    base = load_scene(ROOT / "scenes" / f"{name}.toml")
    scenes = {p: load_method(p).configure(base) for p in ("paper", "strong")}
    for scene in scenes.values():
        render(scene, ctx=ctx)
    frames = {p: [] for p in scenes}
    passes = {p: {} for p in scenes}
    for _ in range(ROUNDS):
        for preset, scene in scenes.items():
            start = time.perf_counter()
            result = render(scene, ctx=ctx)
            frames[preset].append((time.perf_counter() - start) * 1e3)
            assert np.isfinite(result.receivers[0].irradiance).all()
            for key, seconds in result.timings.items():
                passes[preset].setdefault(key, []).append(seconds * 1e3)
    ratio = np.median(np.asarray(frames["strong"]) / np.asarray(frames["paper"]))
    print(f"\n{name}: presets on {result.metadata['gl_renderer']}, {ROUNDS} alternating "
          "rounds after a warm-up each (time.perf_counter around render())")
    for preset in scenes:
        print(f"  {preset:7s} frame {np.median(frames[preset]):7.1f} ms (median, min "
              f"{np.min(frames[preset]):.1f})")
    print(f"  strong / paper: {ratio:.2f} (median of per-round ratios)")
    for key in passes["strong"]:
        paper = np.median(passes["paper"].get(key, [np.nan]))
        print(f"    {key:36s} paper {paper:7.2f} ms  strong "
              f"{np.median(passes['strong'][key]):7.2f} ms")
