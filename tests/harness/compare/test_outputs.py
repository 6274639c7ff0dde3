"""Comparison outputs: strict JSON (NaN/inf as null with a reason), CSV, EXR originals
round-trip."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from harness.compare.outputs import write_comparison, write_json
from renderers.exr import read_exr
from reports.records import (
    ConvergenceSection,
    MethodProvenance,
    MetricValue,
    Provenance,
    SceneComparison,
    Table,
)
from scenes.files import NULL_REASONS, dumps_strict


def test_write_comparison_round_trip(tmp_path):
    image = np.random.default_rng(0).random((6, 8, 3)).astype(np.float32)
    comparison = SceneComparison(
        name="s", description="d", source="s.toml", effects=("shadows",), settings={"grid": 8},
        method="m", method_description="a method",
        metrics=(MetricValue("camera", "full", "psnr", float("inf"), float("nan")),),
        images={"camera/method": image, "camera/ssim": image[..., 0]},
        exposure={"white": 1.0},
        files={"camera/method": "camera_method.exr", "camera/ssim": "camera_ssim.exr"},
        provenance=Provenance("s.toml", MethodProvenance("m", "r", "perf_counter", 1.0)),
        sections=(ConvergenceSection(
            Table(("estimator", "iteration"), (("modified", 0), ("modified", 1)))),),
    )
    write_comparison(tmp_path, comparison)
    data = json.loads((tmp_path / "metrics.json").read_text())  # strict JSON parses
    assert data["metrics"][0]["value"] is None and data["metrics"][0]["noise_floor"] is None
    assert data["null_reasons"] == {"/metrics/0/value": "+Infinity",
                                    "/metrics/0/noise_floor": "NaN"}
    assert "relmse" in data["formulas"]
    rows = list(csv.reader((tmp_path / "convergence.csv").open()))
    assert rows == [["estimator", "iteration"], ["modified", "0"], ["modified", "1"]]
    np.testing.assert_array_equal(read_exr(tmp_path / "camera_method.exr")["RGB"], image)
    ssim = read_exr(tmp_path / "camera_ssim.exr")
    assert list(ssim) == ["Y"] and ssim["Y"].shape == (6, 8)  # a map is one channel
    assert not list(tmp_path.glob(".*tmp"))  # no temporary files left behind


def _strict_loads(text: str):
    """json.loads that refuses NaN/Infinity tokens (what a strict parser does)."""
    def refuse(token):
        raise ValueError(f"non-standard JSON token {token}")
    return json.loads(text, parse_constant=refuse)


def test_dumps_strict_replaces_non_finite_numbers_and_says_why():
    """Regression lock: NaN and ±inf anywhere (floats, NumPy scalars and arrays,
    nested lists and dicts) become null, and ``null_reasons`` maps each one's JSON
    Pointer (``/`` and ``~`` in keys escaped) to its reason; the text parses as
    strict JSON."""
    document = {"a": float("nan"), "b": [1.0, np.float32("inf")],
                "c/d~e": {"x": -np.inf}, "arr": np.array([0.5, np.nan]), "ok": None,
                "path": Path("/x/y")}
    data = _strict_loads(dumps_strict(document))
    assert data["a"] is None and data["b"] == [1.0, None] and data["c/d~e"] == {"x": None}
    assert data["arr"] == [0.5, None] and data["ok"] is None and data["path"] == "/x/y"
    assert data[NULL_REASONS] == {"/a": "NaN", "/b/1": "+Infinity", "/c~1d~0e/x": "-Infinity",
                                  "/arr/1": "NaN"}
    assert NULL_REASONS not in _strict_loads(dumps_strict({"v": 1.0}))


def test_dumps_strict_rejects_what_json_cannot_hold():
    """Regression lock: an object JSON cannot hold, or a document that already uses
    the reasons key while a number is replaced, is an error, never silent output."""
    with pytest.raises(TypeError):
        dumps_strict({"x": object()})
    with pytest.raises(ValueError, match=NULL_REASONS):
        dumps_strict({NULL_REASONS: {}, "x": float("nan")})


def test_write_json_is_strict(tmp_path):
    """Regression lock: every JSON the harness writes through write_json (metrics,
    crosscheck, figure data, failure records) parses with a strict parser."""
    write_json(tmp_path / "x.json", {"v": [float("nan"), 1]})
    text = (tmp_path / "x.json").read_text()
    assert "NaN" not in text.replace('"NaN"', "") and text.endswith("}\n")
    assert _strict_loads(text)[NULL_REASONS] == {"/v/0": "NaN"}


def test_reference_result_json_is_strict(tmp_path):
    """Regression lock: `caustics reference` hands the result directory writer only
    finite numbers (NaN relative noise of a caustic-free scene, say), with the
    reasons beside them, and keeps the arrays that go to the EXRs."""
    from harness.commands.reference import strict_result  # noqa: PLC0415 - loads Mitsuba
    from renderers.results import RenderResult  # noqa: PLC0415

    variance = np.zeros((2, 2, 3), np.float32)
    result = RenderResult("mitsuba", np.zeros((2, 2, 3), np.float32), (), (),
                          timings={"photons": float("inf")},
                          metadata={"relative_noise": float("nan"), "camera_variance": variance,
                                    "photons": 10})
    strict = strict_result(result)
    assert strict.metadata["camera_variance"] is variance
    assert strict.metadata["relative_noise"] is None and strict.timings == {"photons": None}
    assert strict.metadata[NULL_REASONS] == {"/relative_noise": "NaN",
                                             "/timings/photons": "+Infinity"}
    assert _strict_loads(json.dumps({k: v for k, v in strict.metadata.items()
                                     if k != "camera_variance"}, allow_nan=False))
