"""One scene's failure is its own: a failure record, page and ``failure.json``; the
next scene is unaffected. A comparison without an answer (no caustic) is such a
failure, its data files kept."""

from __future__ import annotations

import json
from dataclasses import replace
from types import SimpleNamespace

import numpy as np

from harness.compare import isolation
from harness.compare.isolation import FAILURE_JSON, run_scene, status_failure
from reports.build import write_index
from reports.records import NO_CAUSTIC, STATUS_REASONS, FluxBudgets, SceneFailure, Table
from tests.reports.conftest import make_comparison

SCENE = SimpleNamespace(name="broken", source="/scenes/broken.toml",
                        info=SimpleNamespace(description="a scene that fails"))


def test_exception_in_the_comparison_becomes_a_failure_page(tmp_path):
    """Regression lock: an exception inside the comparison gives a SceneFailure with
    the one-line error and the stage, a page, and strict-JSON failure.json."""
    def compare():
        raise ValueError("Data cannot be log-scaled\nbecause all values are <= 0")

    item, row = run_scene(tmp_path, "broken-paper", SCENE, "paper", compare)
    assert isinstance(item, SceneFailure) and row["failure"]
    assert item.error == "ValueError: Data cannot be log-scaled because all values are <= 0"
    assert item.stage == "comparison"
    assert "Data cannot be log-scaled" in (tmp_path / "broken-paper" / "index.html").read_text()
    record = json.loads((tmp_path / "broken-paper" / FAILURE_JSON).read_text())
    assert record["failed"] == {"stage": "comparison", "error": item.error}


def test_failure_after_the_comparison_keeps_its_flux_budget(tmp_path, monkeypatch):
    """Regression lock: a failure while writing the scene's files (after the
    comparison finished) is reported with that stage and the comparison's flux
    budget, so the page still says where the light went."""
    budget = Table(("item", "flux_w", "fraction"), (("traced", 1.0, 1.0),))
    comparison = replace(make_comparison(name="broken", checks=False, camera=(24, 32),
                                         receiver=(16, 16)),
                         budgets=FluxBudgets(summary=budget))

    def fail(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(isolation, "write_comparison", fail)
    item, _ = run_scene(tmp_path, "broken-paper", SCENE, "paper", lambda: comparison)
    assert isinstance(item, SceneFailure)
    assert item.stage == "data files" and item.flux_budget is budget
    assert "No space left on device" in item.error


def test_other_scenes_complete_and_the_index_lists_both(tmp_path):
    """Regression lock: a good scene after a failed one gets its full page, and the
    index has one normal row and one failure row."""
    def broken():
        raise FloatingPointError("relMSE is NaN")

    good = make_comparison(name="good", checks=False, camera=(24, 32), receiver=(16, 16))
    failed, bad_row = run_scene(tmp_path, "broken-paper", SCENE, "paper", broken)
    assert isinstance(failed, SceneFailure)
    done, good_row = run_scene(tmp_path, "good-paper", SCENE, "paper", lambda: good)
    assert done is good and not good_row["failure"]
    assert (tmp_path / "good-paper" / "metrics.json").is_file()
    index = write_index(tmp_path, [bad_row, good_row]).read_text()
    assert "1 of 2 comparisons failed" in index
    assert "relMSE is NaN" in index and 'href="good-paper/index.html"' in index
    assert np.isfinite(json.loads((tmp_path / "good-paper" / "metrics.json").read_text())
                       ["metrics"][0]["value"])


def test_a_comparison_without_a_caustic_keeps_its_files_and_fails_its_row(tmp_path):
    """Regression lock: a comparison whose status is ``no caustic`` (no exception)
    writes its data files (where the light went) and gets a failure page and
    ``failure.json`` with that reason and its flux budget."""
    budget = Table(("item", "flux_w", "fraction"), (("traced", 1.0, 1.0),))
    dark = replace(make_comparison(name="dark", checks=False, camera=(24, 32),
                                   receiver=(16, 16)),
                   budgets=FluxBudgets(summary=budget), status=NO_CAUSTIC)
    assert not dark.answered and status_failure(make_comparison(name="lit")) is None
    item, row = run_scene(tmp_path, "dark-paper", SCENE, "paper", lambda: dark)
    assert isinstance(item, SceneFailure) and row["failure"]
    assert (item.stage, item.error) == ("comparison", STATUS_REASONS[NO_CAUSTIC])
    assert item.flux_budget is budget and item.method == dark.method
    assert (tmp_path / "dark-paper" / "metrics.json").is_file()
    record = json.loads((tmp_path / "dark-paper" / FAILURE_JSON).read_text())
    assert record["failed"]["error"].startswith("no caustic: the reference puts no caustic")
    assert "no caustic" in (tmp_path / "dark-paper" / "index.html").read_text()
