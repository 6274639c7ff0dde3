"""Failed scenes and flux budgets in the report: a failure row and page, and the
budget table shown exactly when the flux ratio is far from 1."""

from __future__ import annotations

import re
from dataclasses import replace
from html import unescape

import pytest

from reports import build_report
from reports.records import FluxBudgets, MetricValue, SceneFailure, Table
from tests.reports.conftest import HOSTILE_NAME

BUDGET = Table(("item", "flux_w", "fraction"), (
    ("traced: light through the object grid", 16.6, 1.0),
    ("splatted on a receiver (hit)", 0.0, 0.0),
    ("total internal reflection at the exit", 0.19, 0.0115),
    ("on the receivers: method maps", 0.0, 0.0),
))


def _text(path) -> str:
    return unescape(re.sub(r"<[^>]+>", " ", path.read_text("utf-8")))


def _with_flux_ratio(comparison, ratio):
    metrics = tuple(replace(m, value=ratio) if (m.view, m.region, m.metric)
                    == ("receiver0", "full", "flux_ratio") else m for m in comparison.metrics)
    return replace(comparison, metrics=metrics, budgets=FluxBudgets(summary=BUDGET))


def test_failure_gets_a_row_and_a_page_and_the_others_are_intact(tmp_path, comparison):
    """Regression lock: a SceneFailure among comparisons gives a failure row (with
    the one-line error) in the index, its own page with the error and flux budget,
    and the other scenes' pages as usual. The error text is escaped like any scene
    text."""
    failure = SceneFailure(name=HOSTILE_NAME, method="paper", source="bad.toml",
                           error="ValueError: <b>Data</b> cannot be log-scaled",
                           stage="comparison", flux_budget=BUDGET)
    index = build_report(tmp_path, [comparison, failure])
    html = index.read_text("utf-8")
    assert "1 of 2 comparisons failed" in _text(index)
    assert html.count('class="fail failure"') == 1
    assert "&lt;b&gt;Data&lt;/b&gt; cannot be log-scaled" in html  # escaped, inert
    assert "<script>window.__pwned" not in html
    (good, bad) = [p.parent for p in sorted(tmp_path.glob("*/index.html"))
                   if p.parent.name != "_static"]
    assert "Metrics" in _text(good / "index.html")
    page = _text(bad / "index.html")
    assert "This comparison failed" in page and "cannot be log-scaled" in page
    assert "Flux budget" in page and "total internal reflection" in page


@pytest.mark.parametrize(("ratio", "shown"), [
    (1.0, False), (2.0, False), (0.2, True), (float("nan"), True), (float("inf"), True),
])
def test_flux_budget_is_shown_when_the_flux_ratio_is_far_from_one(tmp_path, comparison,
                                                                 ratio, shown):
    """Method target: the page explains where the light went when the method's flux
    ratio (receiver 0, whole map) is outside [0.5, 2] or not finite, and stays
    quiet otherwise."""
    build_report(tmp_path, [_with_flux_ratio(comparison, ratio)])
    page = _text(next(p for p in tmp_path.glob("*/index.html")))
    assert ("Flux budget" in page) is shown
    if shown:
        assert "traced: light through the object grid" in page


def test_no_flux_budget_without_a_flux_ratio(tmp_path, comparison):
    """Regression lock: a comparison without a receiver flux ratio shows no budget."""
    metrics = tuple(m for m in comparison.metrics if m.metric != "flux_ratio")
    build_report(tmp_path, [replace(comparison, metrics=metrics,
                                    budgets=FluxBudgets(summary=BUDGET))])
    assert "Flux budget" not in _text(next(p for p in tmp_path.glob("*/index.html")))


def test_non_finite_difference_range_still_draws(tmp_path, comparison):
    """Regression lock: a NaN colour-bar range (a method image with NaN in it) falls
    back to a finite one instead of failing the page."""
    broken = replace(comparison, exposure={**comparison.exposure,
                                           "diff_range": {"camera": float("nan"),
                                                          "receiver0": float("inf")}},
                     metrics=(*comparison.metrics,
                              MetricValue("receiver0", "caustic", "psnr", float("nan"))))
    assert build_report(tmp_path, [broken]).is_file()
