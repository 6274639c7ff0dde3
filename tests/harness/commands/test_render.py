"""``caustics render`` writes the files the README's CLI table names, with finite contents."""

from __future__ import annotations

import json

import numpy as np

from harness.cli import main
from renderers.exr import read_exr
from tests.conftest import REPO as ROOT


def test_render_writes_outputs(tmp_path, capsys):
    """camera.exr, receiver_irradiance.exr (extent in result.json), caustic_map.exr,
    hits.npz (v, r, d per iteration, status) and result.json (passes, lost_splats,
    timings, timer)."""
    scene = ROOT / "scenes" / "water_pool.toml"
    out = tmp_path / "out"
    code = main(["render", str(scene), "-o", str(out), "--grid", "32", "--caustic-map", "128",
                 "--iterations", "2", "--estimator", "secant"])
    assert code == 0
    summary = json.loads((out / "result.json").read_text())
    assert summary["receiver_extent"] == [[-2.0, 2.0, -2.0, 2.0]]
    assert "caustic_map" in summary["passes"]
    assert set(summary["timings"]) == set(summary["passes"])
    assert "perf_counter" in summary["timer"]
    assert isinstance(summary["lost_splats"], int)
    for name in ("camera.exr", "receiver_irradiance.exr", "caustic_map.exr"):
        layers = read_exr(out / name)
        assert all(np.isfinite(a).all() for a in layers.values())
    hits = np.load(out / "hits.npz")
    assert hits["history"].shape == (32 * 32, 3)
    for key in ("origin", "direction", "status"):
        assert len(hits[key]) == 32 * 32
