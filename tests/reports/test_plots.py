"""The report's plots with nothing finite to show: a scene without a caustic has NaN
relMSE everywhere, and a log axis cannot be placed without positive data."""

from __future__ import annotations

import numpy as np
import pytest

from reports import plots
from reports.build import speedup_text
from reports.records import EqualErrorSpeedup, Table
from tests.reports.conftest import convergence_table, cost_table


def _with(table: Table, **columns) -> Table:
    """``table`` with the named columns set to one value (or a per-row function)."""
    rows = []
    for record in table.records():
        for name, value in columns.items():
            record[name] = value(record) if callable(value) else value
        rows.append(record)
    return Table.from_records(table.columns, rows)


@pytest.mark.parametrize("value", [float("nan"), 0.0, float("inf"), None])
def test_cost_plot_without_finite_relmse_says_no_caustic(value):
    """Regression lock: a cost table whose every relMSE is NaN, zero, inf or missing
    (a scene whose light forms no caustic) draws a panel saying so; before, matplotlib
    raised "Data cannot be log-scaled" and the whole run was lost."""
    table, _, _ = cost_table(np.random.default_rng(0))
    table = _with(table, relmse=value)
    speedup = EqualErrorSpeedup(float("nan"), float("nan"), "bound")
    svg = plots.figure_bytes(plots.cost_figure(table, speedup=speedup)).decode()
    assert "no caustic" in svg
    pdf = plots.figure_bytes(plots.cost_figure(table), fmt="pdf")
    assert pdf.startswith(b"%PDF")


def test_cost_plot_with_partly_nan_relmse_plots_the_rest():
    """Regression lock: NaN configurations are left out; the others are drawn on
    log axes as before (no "no caustic" panel)."""
    table, time, error = cost_table(np.random.default_rng(1))
    table = _with(table, relmse=lambda r: float("nan") if r["label"] == "cfg0" else r["relmse"])
    svg = plots.figure_bytes(plots.cost_figure(table, point=(time, error))).decode()
    assert "no caustic" not in svg and "Pareto front" in svg


@pytest.mark.parametrize("value", [float("nan"), 0.0])
def test_convergence_plot_without_finite_error_says_so(value):
    """Regression lock: every hit-distance error NaN or zero gives labelled empty
    panels, not an exception."""
    table = convergence_table(np.random.default_rng(0))
    table = _with(table, mean_error_texels=value, p95_error_texels=value,
                  max_error_texels=value, converged=float("nan"))
    svg = plots.figure_bytes(plots.convergence_figure(table)).decode()
    assert "no finite hit-distance error" in svg


def test_convergence_plot_with_one_empty_estimator():
    """Regression lock: one estimator without finite errors gets its own labelled
    panel; the others keep their log-scale curves."""
    table = convergence_table(np.random.default_rng(0))
    nan_for_newton = {c: (lambda r, c=c: float("nan") if r["estimator"] == "newton" else r[c])
                      for c in ("mean_error_texels", "p95_error_texels", "max_error_texels")}
    svg = plots.figure_bytes(plots.convergence_figure(_with(table, **nan_for_newton))).decode()
    assert svg.count("no finite hit-distance error") == 1


def test_empty_tables_do_not_crash():
    """Regression lock: tables without rows still give a figure."""
    convergence = Table(convergence_table(np.random.default_rng(0)).columns, ())
    cost = Table(cost_table(np.random.default_rng(0))[0].columns, ())
    assert plots.figure_bytes(plots.convergence_figure(convergence)).startswith(b"<?xml")
    assert b"no caustic" in plots.figure_bytes(plots.cost_figure(cost))


def _with_excess(table: Table) -> Table:
    """``table`` with excess columns: the relMSE less a constant baseline of 1e-4, its
    interval ±10 %."""
    columns = (*table.columns, "excess", "excess_low", "excess_high")
    rows = []
    for record in table.records():
        excess = record["relmse"] - 1e-4
        rows.append({**record, "excess": excess, "excess_low": 0.9 * excess,
                     "excess_high": 1.1 * excess})
    return Table.from_records(columns, rows)


def test_cost_plot_draws_the_excess_with_bars_and_the_cold_points():
    """Regression lock: with excess columns the y axis is the excess relMSE, each point
    has its interval bar, and the method's cold points are drawn (hollow) beside the
    warm ones; a speedup below 1 reads "slower" in the title."""
    table, time, error = cost_table(np.random.default_rng(2))
    speedup = EqualErrorSpeedup(0.625, 0.01, "interpolated", low=0.5, high=0.8)
    figure = plots.cost_figure(_with_excess(table), speedup=speedup, point=(time, error))
    ax = figure.axes[0]
    labels = ax.get_legend_handles_labels()[1]
    assert "method, cold (first frame)" in labels and "method, warm" in labels
    assert ax.get_ylabel().startswith("excess relMSE")
    assert "1.6× slower" in ax.get_title()
    bars = [c for c in ax.containers if hasattr(c, "has_yerr") and c.has_yerr]
    assert len(bars) == 2      # the method's configurations and the reference's curve


def test_scene_cost_plot_holds_every_method_and_the_reference():
    """Regression lock: the index's per-scene plot draws each method's point at the
    scene settings, warm and cold, and the reference's curve once."""
    table, _, _ = cost_table(np.random.default_rng(3))
    tables = {"paper": _with_excess(table), "strong": _with_excess(table)}
    ax = plots.scene_cost_figure("glass_sphere", tables).axes[0]
    labels = ax.get_legend_handles_labels()[1]
    assert labels.count("reference (Mitsuba), warm") == 1
    assert labels.count("reference, cold (build + compile + warm)") == 1
    for method in tables:
        assert f"{method}, warm" in labels and f"{method}, cold" in labels
    empty = plots.scene_cost_figure("none", {"paper": _with(table, relmse=float("nan"))})
    assert empty.axes[0].texts, "no panel text for a scene without finite points"


def test_a_speedup_below_one_reads_slower():
    """The report's and the record's texts agree: 0.625 is "1.6× slower"."""
    speedup = EqualErrorSpeedup(0.625, 0.01, "interpolated", low=0.5, high=0.8)
    assert speedup.text.startswith("1.6× slower (speedup 0.625×")
    assert speedup_text(speedup).startswith("1.6× slower (speedup 0.625×")
    assert EqualErrorSpeedup(2.5, 0.01, "interpolated").text == "2.5×"
