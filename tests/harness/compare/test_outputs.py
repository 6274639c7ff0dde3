"""Comparison outputs: strict JSON (NaN/inf encoded), CSV, EXR originals round-trip."""

from __future__ import annotations

import csv
import json

import numpy as np

from harness.compare.outputs import write_comparison
from renderers.exr import read_exr
from reports.records import MetricValue, SceneComparison, Table


def test_write_comparison_round_trip(tmp_path):
    image = np.random.default_rng(0).random((6, 8, 3)).astype(np.float32)
    comparison = SceneComparison(
        name="s", description="d", source="s.toml", effects=("shadows",), settings={"grid": 8},
        metrics=(MetricValue("camera", "full", "psnr", float("inf"), float("nan")),),
        images={"camera/method": image, "camera/ssim": image[..., 0]},
        exposure={"white": 1.0},
        convergence=Table(("estimator", "iteration"), (("modified", 0), ("modified", 1))),
        files={"camera/method": "camera_method.exr", "camera/ssim": "camera_ssim.exr"},
    )
    write_comparison(tmp_path, comparison)
    data = json.loads((tmp_path / "metrics.json").read_text())  # strict JSON parses
    assert data["metrics"][0]["value"] == "inf" and data["metrics"][0]["noise_floor"] is None
    assert "relmse" in data["formulas"]
    rows = list(csv.reader((tmp_path / "convergence.csv").open()))
    assert rows == [["estimator", "iteration"], ["modified", "0"], ["modified", "1"]]
    np.testing.assert_array_equal(read_exr(tmp_path / "camera_method.exr")["RGB"], image)
    assert read_exr(tmp_path / "camera_ssim.exr")["RGB"].shape == (6, 8, 3)
    assert not list(tmp_path.glob(".*tmp"))  # no temporary files left behind
