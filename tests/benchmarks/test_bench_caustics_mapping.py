"""Benchmark: frames per second and per-pass milliseconds of caustics mapping on
glass_sphere at a 512 x 512 camera, 128 x 128 grid, 3 iterations (the paper's
Fig. 6 setting). Goal on the 2-core llvmpipe machine: >= 30 fps. Timings come from
``ctx.finish()`` + ``time.perf_counter()`` per pass (GL timer queries are invalid
on llvmpipe); no GPU was available when this was written, so only llvmpipe numbers
exist. Not a pass/fail test of speed: it reports, and fails only on a broken render.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import pytest

from harness.scene import load_scene, with_settings
from renderers.caustics_mapping import render

from ..renderers.caustics_mapping.conftest import ROOT

FRAMES = 10


@pytest.mark.bench
def test_bench_glass_sphere(ctx, record_property):
    """Warm up once (shader compilation), then time FRAMES full frames."""
    scene = with_settings(load_scene(ROOT / "scenes" / "glass_sphere.toml"),
                          {"grid": 128, "iterations": 3})
    scene = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                  resolution=(512, 512)))
    render(scene, ctx=ctx)
    passes: dict[str, list[float]] = {}
    start = time.perf_counter()
    for _ in range(FRAMES):
        result = render(scene, ctx=ctx)
        for name, seconds in result.timings.items():
            passes.setdefault(name, []).append(seconds * 1e3)
    elapsed = (time.perf_counter() - start) / FRAMES
    fps = 1.0 / elapsed
    assert np.isfinite(result.camera).all()
    print(f"\nglass_sphere 512x512, grid 128, 3 iterations on {result.metadata['gl_renderer']}:"
          f" {fps:.1f} fps ({elapsed * 1e3:.1f} ms/frame, timer: {result.timer})")
    for name, ms in passes.items():
        print(f"  {name:36s} {np.median(ms):8.2f} ms")
    record_property("fps", fps)
    record_property("pass_ms", {k: float(np.median(v)) for k, v in passes.items()})
