"""Benchmark: what the rim patches' grazing band costs the strong preset on the
conductors (docs/method.md, "Rim patches"), as a ratio taken in one run.

The same scene at its own settings renders with the band off (``GRAZING_COS`` = 0,
the silhouette's band alone) and on, in one GL context; each is warmed up once, then
``ROUNDS`` rounds alternate the two, so drift of the machine falls on both alike.
Reported: the patched quads of each, the median frame (``time.perf_counter`` around
``render()``), and the median over rounds of the per-round ratio on / off with its
distribution-free 95 % interval (:func:`.test_bench_presets.median_interval`). Fails
only on a broken render, or where the band patches no more quads than the silhouette.
"""

from __future__ import annotations

import numpy as np
import pytest

from renderers.caustics_mapping import render, render_frame, rim_patches
from renderers.methods import load_method
from scenes import load_scene

from ..renderers.caustics_mapping.conftest import ROOT
from .test_bench_presets import alternating_frames, print_ratio


@pytest.mark.bench
@pytest.mark.parametrize("name", ["metal_ring", "ring_point", "bowl_sun", "cup_sun"])
def test_bench_grazing_band(ctx, monkeypatch, name):
    scene = load_method("strong").configure(load_scene(ROOT / "scenes" / f"{name}.toml"))
    band = {"off": 0.0, "on": rim_patches.GRAZING_COS}
    quads = {}
    for key, cos in band.items():
        monkeypatch.setattr(rim_patches, "GRAZING_COS", cos)
        quads[key] = len(np.unique(render_frame(scene, ctx=ctx).patches["quad"]))
        render(scene, ctx=ctx)
    assert quads["on"] > quads["off"]

    def render_with(key):
        monkeypatch.setattr(rim_patches, "GRAZING_COS", band[key])
        return render(scene, ctx=ctx)

    frames = alternating_frames(band, render_with)
    print_ratio(f"{name}: strong with the grazing band off and on", frames,
                {key: f"band {key:3s}: {quads[key]:5d} patched quads" for key in band},
                over=("on", "off"))
