"""Matplotlib plots of the report: convergence per estimator, cost versus accuracy.

Each plot is returned as SVG bytes (for HTML) and can also be written as PDF (for
papers) with :func:`figure_bytes`. Text stays text in the SVG (``svg.fonttype =
none``) and ids are salted deterministically, so the files are small and a rebuild
gives the same bytes.

Log axes see only finite, positive values. A panel with none (a scene without a
caustic has no relMSE; an empty table has nothing) says so in words instead of
plotting: matplotlib cannot place a log axis without data.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from reports.records import EqualErrorSpeedup, Table
from scenes.files import atomic_write_bytes

__all__ = ["convergence_figure", "cost_figure", "figure_bytes"]

_RC = {"svg.fonttype": "none", "svg.hashsalt": "caustics-report", "font.size": 8}


def _pyplot():
    import matplotlib  # noqa: PLC0415 - heavy, only when a plot is drawn

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt  # noqa: PLC0415 - heavy, only when a plot is drawn

    return plt


def figure_bytes(figure, *, fmt: str = "svg") -> bytes:
    """Serialise ``figure`` as ``svg`` or ``pdf`` (without a creation date) and close it."""
    plt = _pyplot()
    buffer = io.BytesIO()
    metadata = {"Date": None} if fmt == "svg" else {"CreationDate": None}
    with plt.rc_context(_RC):
        figure.savefig(buffer, format=fmt, bbox_inches="tight", metadata=metadata)
    plt.close(figure)
    return buffer.getvalue()


def _float(values: Sequence) -> np.ndarray:
    return np.array([np.nan if v is None else float(v) for v in values], float)


def _loggable(values: np.ndarray) -> np.ndarray:
    """``values`` with anything a log axis cannot show (≤ 0, NaN, ±inf) as NaN,
    which matplotlib leaves out."""
    return np.where(np.isfinite(values) & (values > 0), values, np.nan)


def _positive(*values: float) -> bool:
    """Every value finite and positive (a point a log-log plot can show)."""
    return all(np.isfinite(v) and v > 0 for v in values)


def _no_data(ax, text: str) -> None:
    """Say in the panel why it is empty (no ticks: there is no scale to read)."""
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes,
            color="0.35", wrap=True)
    ax.set_xticks([])
    ax.set_yticks([])


def estimator_label(estimator: str, safeguarded) -> str:
    """``newton`` or ``newton (safeguarded)``."""
    return f"{estimator} (safeguarded)" if safeguarded in (True, 1, "true", "True") else estimator


def convergence_figure(table: Table):
    """Small multiples, one panel per estimator: hit-distance error (caustic-map
    texels, log scale: mean, p95, max) against the iteration, and the fraction of
    vertices converged on a second axis.

    Parameters
    ----------
    table : Table
        The convergence table (columns in ``SceneComparison.convergence``).
    """
    plt = _pyplot()
    estimators = table.column("estimator")
    guarded = (table.column("safeguarded") if "safeguarded" in table.columns
               else [False] * len(estimators))
    labels = [estimator_label(e, s) for e, s in zip(estimators, guarded, strict=True)]
    names = list(dict.fromkeys(labels)) or ["no estimator"]
    columns = 3 if len(names) > 4 else max(1, len(names))
    rows = -(-len(names) // columns)
    error_columns = [c for c in ("mean_error_texels", "p95_error_texels", "max_error_texels")
                     if c in table.columns]
    errors = {c: _loggable(_float(table.column(c))) for c in error_columns}
    # Panels share one log axis; it needs at least one finite, positive error.
    any_data = any(np.isfinite(v).any() for v in errors.values())
    with plt.rc_context(_RC):
        figure, axes = plt.subplots(rows, columns, figsize=(3.0 * columns, 2.3 * rows),
                                    sharex=True, sharey=True, squeeze=False)
        iterations = _float(table.column("iteration"))
        for ax, name in zip(axes.flat, names, strict=False):
            pick = np.array([label == name for label in labels], dtype=bool)
            order = np.argsort(iterations[pick])
            x = iterations[pick][order]
            ys = {c: errors[c][pick][order] for c in error_columns}
            ax.set_title(name)
            if not any_data or not any(np.isfinite(y).any() for y in ys.values()):
                _no_data(ax, "no finite hit-distance error")
                continue
            for column, style in zip(error_columns, ("-o", "--s", ":^"), strict=False):
                ax.plot(x, ys[column], style, markersize=3, label=column.split("_")[0])
            ax.set_yscale("log")
            ax.grid(True, which="both", alpha=0.3)
            if "converged" in table.columns:
                twin = ax.twinx()
                twin.plot(x, _float(table.column("converged"))[pick][order], color="0.5",
                          linewidth=1, label="converged")
                twin.set_ylim(-0.05, 1.05)
                twin.tick_params(labelsize=6, colors="0.4")
        for ax in axes.flat[len(names):]:
            ax.set_visible(False)
        for ax in axes[-1]:
            ax.set_xlabel("iteration")
        for ax in axes[:, 0]:
            ax.set_ylabel("hit-distance error (texels)")
        if axes.flat[0].get_legend_handles_labels()[0]:
            axes.flat[0].legend(fontsize=6, loc="upper right")
        figure.suptitle("Estimator convergence (grey: fraction converged, right axis)")
    return figure


def _speedup_point(speedup: EqualErrorSpeedup, point, front_times, front_errors):
    """The real-time (time, error) the speedup was computed for: ``point`` when
    known, else the front point nearest (in log time) to reference_time / speedup."""
    if point is not None:
        return float(point[0]), float(point[1])
    method_time = speedup.reference_time / speedup.speedup
    if not len(front_times):
        return method_time, float("nan")
    nearest = int(np.argmin(np.abs(np.log(front_times) - np.log(method_time))))
    return method_time, float(front_errors[nearest])


def _excess_column(table: Table) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(shown error, lower bar, upper bar) of each row: the excess relMSE and its 95 %
    interval where the table has them (an estimate within noise, ≤ 0, is drawn at its
    interval's upper end with no lower bar), else the raw relMSE with no bars."""
    raw = _float(table.column("relmse"))
    if "excess" not in table.columns:
        zero = np.zeros_like(raw)
        return _loggable(raw), zero, zero
    excess = _float(table.column("excess"))
    low = _float(table.column("excess_low"))
    high = _float(table.column("excess_high"))
    shown = np.where(excess > 0, excess, high)
    below = np.where((excess > 0) & (low > 0), shown - low, 0.0)
    above = np.where(np.isfinite(high) & (high > shown), high - shown, 0.0)
    return _loggable(shown), np.nan_to_num(below), np.nan_to_num(above)


def _reference_curve(ax, table: Table) -> bool:
    """Draw the table's reference rows: excess relMSE (95 % bars) against warm time
    (solid) and cold time (build + compile + warm, dashed); whether any point is finite."""
    series = np.array(table.column("series"))
    errors, below, above = _excess_column(table)
    warm = _loggable(_float(table.column("time_warm_s")))
    cold = _loggable(_float(table.column("time_cold_s")))
    ref = np.flatnonzero(series == "reference")
    if not ref.size:
        return False
    ref = ref[np.argsort(warm[ref])]
    ax.errorbar(warm[ref], errors[ref], yerr=[below[ref], above[ref]], fmt="-s",
                color="tab:red", markersize=3, elinewidth=0.7, label="reference (Mitsuba), warm")
    ax.plot(cold[ref], errors[ref], "--", color="tab:red", alpha=0.6,
            label="reference, cold (build + compile + warm)")
    return bool(np.isfinite(errors[ref]).any())


def cost_figure(table: Table, *, speedup: EqualErrorSpeedup | None = None,
                point: tuple[float, float] | None = None,
                cold: EqualErrorSpeedup | None = None):
    """Excess relMSE (the error against the noise-free image, with its 95 % interval as
    a bar) against time, log-log: every caustics-mapping configuration warm (filled)
    and cold (hollow: first frame in a fresh context, compilation included), their
    Pareto front (the table's ``pareto`` column), the reference's own
    error-versus-time curve warm (solid) and cold (dashed), and the equal-error
    speedups in the title ("1.6× slower" below 1).

    Parameters
    ----------
    table : Table
        The cost table (columns in ``SceneComparison.cost``).
    speedup : EqualErrorSpeedup, optional
        Shown in the title and as an arrow from the real-time point to the
        reference time that reaches the same error.
    point : (float, float), optional
        The real-time (time s, error) the speedup was computed for; when not
        given, the Pareto point nearest to ``reference_time / speedup`` in time.
    cold : EqualErrorSpeedup, optional
        The cold-against-cold speedup, named in the title beside the warm one.
    """
    plt = _pyplot()
    series = np.array(table.column("series"))
    times = _loggable(_float(table.column("time_warm_s")))
    cold_times = _loggable(_float(table.column("time_cold_s")))
    errors, below, above = _excess_column(table)
    label = "excess relMSE" if "excess" in table.columns else "relMSE"
    with plt.rc_context(_RC):
        figure, ax = plt.subplots(figsize=(6.0, 4.2))
        if not (np.isfinite(times) & np.isfinite(errors)).any():
            ax.set_title("Cost versus accuracy")
            _no_data(ax, f"no caustic: no configuration has a finite, positive {label}")
            return figure
        cm = series == "caustics_mapping"
        ax.errorbar(times[cm], errors[cm], yerr=[below[cm], above[cm]], fmt="o",
                    markersize=3, color="tab:blue", alpha=0.6, elinewidth=0.7,
                    label="method, warm")
        ax.scatter(cold_times[cm], errors[cm], s=14, facecolors="none",
                   edgecolors="tab:blue", alpha=0.6, label="method, cold (first frame)")
        on_front = np.asarray(table.column("pareto"), dtype=bool)
        front = np.flatnonzero(cm & on_front)
        front = front[np.argsort(times[front], kind="stable")]
        ax.plot(times[front], errors[front], "-", color="tab:blue", linewidth=1.2,
                label="Pareto front (warm)")
        _reference_curve(ax, table)
        title = "Cost versus accuracy"
        if speedup is not None and _positive(speedup.speedup, speedup.reference_time):
            method_time, method_error = _speedup_point(speedup, point, times[front], errors[front])
            title += f"\nequal-error speedup {speedup.text} warm ({speedup.kind})"
            if cold is not None:
                title += f", {cold.text} cold"
            if _positive(method_time, method_error):
                ax.annotate("", xy=(speedup.reference_time, method_error),
                            xytext=(method_time, method_error),
                            arrowprops={"arrowstyle": "->", "color": "0.3"})
                ax.plot([speedup.reference_time], [method_error], "x", color="tab:red",
                        label=f"reference at equal error ({speedup.reference_time:.3g} s)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time (s): the passes producing the receiver maps")
        ax.set_ylabel(f"{label} (receiver 0, caustic region)")
        ax.set_title(title, fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    return figure


def scene_cost_figure(scene: str, tables: dict[str, Table]):
    """What accuracy costs on one scene, every method on the same axes: each method's
    point at the scene's settings (its cost table's first method row), warm (filled)
    and cold (hollow), excess relMSE with its 95 % interval as a bar, and the
    reference's own error-versus-time curve warm and cold (from the first table that
    has it: every method of a scene is scored against the same reference).

    Parameters
    ----------
    scene : str
        The scene's name (the title).
    tables : dict of str to Table
        Method name to its cost table (columns in ``SceneComparison.cost``).
    """
    plt = _pyplot()
    markers = "osD^v<>"
    with plt.rc_context(_RC):
        figure, ax = plt.subplots(figsize=(6.0, 4.2))
        ax.set_title(f"{scene}: what accuracy costs", fontsize=9)
        reference = next((t for t in tables.values()
                          if "reference" in t.column("series")), None)
        drawn = reference is not None and _reference_curve(ax, reference)
        for i, (method, table) in enumerate(tables.items()):
            series = np.array(table.column("series"))
            mine = np.flatnonzero(series != "reference")
            if not mine.size:
                continue
            row = mine[:1]
            errors, below, above = _excess_column(table)
            warm = _loggable(_float(table.column("time_warm_s")))[row]
            cold = _loggable(_float(table.column("time_cold_s")))[row]
            colour = f"C{i}"
            ax.errorbar(warm, errors[row], yerr=[below[row], above[row]],
                        fmt=markers[i % len(markers)], color=colour, markersize=5,
                        elinewidth=0.8, capsize=2, label=f"{method}, warm")
            ax.scatter(cold, errors[row], s=30, marker=markers[i % len(markers)],
                       facecolors="none", edgecolors=colour, label=f"{method}, cold")
            drawn = drawn or bool(np.isfinite(errors[row]).any())
        if not drawn:
            _no_data(ax, "no method or reference point with a finite, positive error")
            return figure
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time (s): the passes producing the receiver maps")
        ax.set_ylabel("excess relMSE (receiver 0, caustic region)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    return figure


def write_pdfs(folder, comparison) -> list[str]:
    """``convergence.pdf`` and ``cost_accuracy.pdf`` (for papers) beside the report's
    SVGs, when the comparison has those tables; returns the names written."""
    folder = Path(folder)
    written = []
    if comparison.convergence is not None and comparison.convergence.rows:
        atomic_write_bytes(folder / "convergence.pdf", figure_bytes(
            convergence_figure(comparison.convergence), fmt="pdf"))
        written.append("convergence.pdf")
    if comparison.cost is not None and comparison.cost.rows:
        atomic_write_bytes(folder / "cost_accuracy.pdf", figure_bytes(cost_figure(
            comparison.cost, speedup=comparison.speedup, point=comparison.speedup_point,
            cold=comparison.speedup_cold),
            fmt="pdf"))
        written.append("cost_accuracy.pdf")
    return written
