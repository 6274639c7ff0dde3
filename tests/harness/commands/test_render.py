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


def test_render_writes_the_rim_patches_of_its_own_frame(tmp_path):
    """The strong preset's rim patches go to patches.npz (one grid quad per patch of
    4 x 4 vertices, a share per vertex); a render without patches into the same
    folder removes it, so no earlier render's patches pass for its own."""
    scene = ROOT / "scenes" / "glass_sphere.toml"
    out = tmp_path / "out"
    small = ["--grid", "32", "--caustic-map", "128", "--preset", "strong"]
    assert main(["render", str(scene), "-o", str(out), *small]) == 0
    patches = np.load(out / "patches.npz")
    assert len(patches["status"]) == 16 * len(np.unique(patches["quad"])) > 0
    assert patches["share"].max() == 1.0 and patches["share"].min() == 0.25
    assert main(["render", str(scene), "-o", str(out), *small,
                 "--set", "rim_patches=1"]) == 0
    assert not (out / "patches.npz").exists()
    assert (out / "hits.npz").exists()
