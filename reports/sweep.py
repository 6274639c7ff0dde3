"""The sweep's index page: error against cost per scene, with the Pareto front.

Built from plain records (:class:`SweepIndex`, :class:`SweepRow`) that
``harness.sweep`` fills; the Pareto flags are computed there, so this module only
draws. Layout written under ``out_dir``::

    index.html                 per scene: the plot and the table of its rows
    plots/<scene>.svg          relMSE against warm frame time (log-log), one
                               marker per method, the Pareto front as a line, the
                               reference's noise floor as a dashed line
    _static/report.css         shared with the rows' pages (``<row>/index.html``,
                               written as ``caustics compare`` writes them)

Every text from a sweep or scene file (names, descriptions, settings, errors) goes
through jinja2's autoescaping, as on the other pages.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

from reports import plots

# The report's own template environment and static files (one look for every page).
from reports.build import page_environment, scene_folder, static_text
from reports.records import METRIC_FORMULAS
from scenes.files import atomic_write_bytes

__all__ = ["SweepIndex", "SweepRow", "sweep_figure", "write_sweep_index"]

_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


@dataclass(frozen=True)
class SweepRow:
    """One (scene, method, setting) row of the index.

    Attributes
    ----------
    scene, method : str
    setting : tuple of (str, str)
        The grid's settings of this row, as shown.
    values : dict of str to float
        ``excess_<m>``, ``excess_<m>_low``, ``excess_<m>_high`` and ``<m>`` for ``m`` in
        ``relmse``, ``ssim``, ``flip``, ``flux_ratio``; ``relmse_noise_floor``.
    time_warm_ms : float or None
    worker : str
    cached : bool
    pareto : bool
        On its scene's Pareto front of (time, relMSE).
    folder : str or None
        The row's page folder (None: no page, the row failed).
    error, stage : str
        Why and where the row failed ("" when it did not).
    """

    scene: str
    method: str
    setting: tuple[tuple[str, str], ...]
    values: dict[str, float] = field(default_factory=dict)
    time_warm_ms: float | None = None
    worker: str = ""
    cached: bool = False
    pareto: bool = False
    folder: str | None = None
    error: str = ""
    stage: str = ""

    @property
    def label(self) -> str:
        """``iterations=3, grid=64``, or ``defaults``."""
        return ", ".join(f"{k}={v}" for k, v in self.setting) or "defaults"


@dataclass(frozen=True)
class SweepIndex:
    """Everything the index shows.

    Attributes
    ----------
    name, description, file : str
        From the sweep file.
    columns : tuple of str
        The settings the grid varies.
    rows : tuple of SweepRow
        In the sweep's order (scene, method, setting).
    scenes : tuple of (str, str)
        Each scene's name and description, in order.
    run : dict
        How it ran: cluster kind and address, workers, tasks, wall time, reference
        budget (shown as a definition list).
    """

    name: str
    description: str
    file: str
    columns: tuple[str, ...]
    rows: tuple[SweepRow, ...]
    scenes: tuple[tuple[str, str], ...]
    run: dict[str, Any] = field(default_factory=dict)


def _positive(value: float | None) -> bool:
    return value is not None and math.isfinite(value) and value > 0


def sweep_figure(rows: Sequence[SweepRow], *, title: str):
    """Excess relMSE (the method's own error against the noise-free image) against warm
    frame time (ms), log-log: each method's rows with its own marker and the 95 %
    interval as an error bar, the Pareto front joined in time order. Rows without a
    finite, positive pair are left out (an excess within noise may be ≤ 0: it is
    drawn at its interval's upper end, marked as an upper bound), and a panel with
    none says so."""
    plt = plots._pyplot()
    with plt.rc_context(plots._RC):
        figure, ax = plt.subplots(figsize=(5.5, 3.8))
        ax.set_title(title)
        points = [r for r in rows if _positive(r.time_warm_ms)
                  and _positive(_shown(r))]
        if not points:
            plots._no_data(ax, "no row has a finite, positive time and excess relMSE")
            return figure
        for i, method in enumerate(dict.fromkeys(r.method for r in points)):
            mine = [r for r in points if r.method == method]
            y = np.array([_shown(r) for r in mine])
            low = np.array([r.values.get("excess_relmse_low", np.nan) for r in mine], float)
            high = np.array([r.values.get("excess_relmse_high", np.nan) for r in mine], float)
            below = np.where(np.isfinite(low) & (low > 0), y - low, 0.0)
            above = np.where(np.isfinite(high) & (high > y), high - y, 0.0)
            ax.errorbar([r.time_warm_ms for r in mine], y, yerr=[below, above],
                        fmt=_MARKERS[i % len(_MARKERS)], markersize=4, alpha=0.8,
                        elinewidth=0.8, capsize=2, label=method)
        front = sorted((r for r in points if r.pareto), key=lambda r: r.time_warm_ms)
        if front:
            ax.plot([r.time_warm_ms for r in front], [_shown(r) for r in front],
                    "-", color="0.25", linewidth=1, label="Pareto front")
            for r in front:
                ax.annotate(r.label, (r.time_warm_ms, _shown(r)), fontsize=6,
                            xytext=(3, 3), textcoords="offset points", color="0.25")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("warm frame time (ms)")
        ax.set_ylabel("excess relMSE (receiver 0, caustic region)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    return figure


def _shown(row: SweepRow) -> float:
    """The excess relMSE drawn for ``row``: the estimate, or its interval's upper end
    where the estimate is not positive (within noise)."""
    value = row.values.get("excess_relmse", float("nan"))
    if _positive(value):
        return value
    return row.values.get("excess_relmse_high", float("nan"))


def write_sweep_index(out_dir: str | Path, index: SweepIndex) -> Path:
    """Write ``out_dir/index.html``, one plot per scene and ``_static/``; returns the
    index's path."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    for name in ("report.css", "report.js"):
        atomic_write_bytes(out_dir / "_static" / name, static_text(name).encode("utf-8"))
    sections, taken = [], []
    for scene, description in index.scenes:
        rows = [r for r in index.rows if r.scene == scene]
        plot = scene_folder(scene, taken=taken)
        taken.append(plot)
        svg = plots.figure_bytes(sweep_figure(rows, title=f"{scene}: error against cost"))
        atomic_write_bytes(out_dir / "plots" / f"{plot}.svg", svg)
        sections.append({
            "name": scene, "description": description, "anchor": plot,
            "plot": f"plots/{quote(plot)}.svg",
            "rows": [{"r": r, "href": f"{quote(r.folder)}/index.html" if r.folder else None,
                      "thumbnail": _thumbnail(out_dir, r.folder)} for r in rows],
            "failed": sum(1 for r in rows if r.error),
        })
    html = page_environment().get_template("sweep.html.j2").render({
        "index": index, "sections": sections, "formulas": METRIC_FORMULAS,
        "failed": sum(1 for r in index.rows if r.error),
        "cached": sum(1 for r in index.rows if r.cached),
        "self_contained": False, "static": "_static/", "css": "", "script_hashes": "",
    })
    path = out_dir / "index.html"
    atomic_write_bytes(path, html.encode("utf-8"))
    return path


def _thumbnail(out_dir: Path, folder: str | None) -> str | None:
    """The row page's thumbnail of its first view's method image, when it has one."""
    if folder is None or not (out_dir / folder / "thumbnail_method.png").is_file():
        return None
    return f"{quote(folder)}/thumbnail_method.png"
