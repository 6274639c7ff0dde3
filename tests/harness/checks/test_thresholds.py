"""Thresholds file: validated like scenes, bounds applied as max/min/band."""

from __future__ import annotations

import math

import pytest

from harness.checks.thresholds import check_bounds, load_thresholds
from reports.records import MetricValue
from scenes import SceneError

GOOD = """
[[bound]]
scene = "s"
view = "receiver0"
region = "caustic"
metric = "relmse"
kind = "max"
bound = 0.1

[[bound]]
scene = "s"
view = "receiver0"
region = "full"
metric = "flux_ratio"
kind = "band"
bound = 0.05

[[bound]]
scene = "s"
view = "camera"
region = "object_masked"
metric = "ssim"
kind = "min"
bound = 0.9
"""


def test_bounds_apply(tmp_path):
    path = tmp_path / "t.toml"
    path.write_text(GOOD)
    bounds = load_thresholds(path)
    metrics = [MetricValue("receiver0", "caustic", "relmse", 0.05),
               MetricValue("receiver0", "full", "flux_ratio", 1.07),
               MetricValue("camera", "object_masked", "ssim", math.nan)]
    checks = check_bounds("s", metrics, bounds)
    assert [c.passed for c in checks] == [True, False, False]  # NaN never passes
    assert check_bounds("other", metrics, bounds) == ()


def test_bad_file_names_field(tmp_path):
    path = tmp_path / "t.toml"
    path.write_text(GOOD.replace('metric = "relmse"', 'metric = "mse"'))
    with pytest.raises(SceneError, match=r"t.toml: bound\[0\].metric: unknown metric 'mse'"):
        load_thresholds(path)
