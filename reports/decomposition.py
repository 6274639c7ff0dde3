"""The error decomposition in the report: a waterfall of the relMSE each step adds,
the steps' table, the sentence naming the largest error source and the verdicts.

Waterfall: one floating bar per step from the previous step's relMSE to its own (the
first from 0), red where the step adds error, green where it removes some (an
approximation cancelling an earlier one), each labelled with its change; a last grey
bar from 0 to the method's relMSE shows that the bars add up to it. A dashed line
marks the reference's noise floor (what an independent reference scores), a dotted
one half of it (what the truth itself is expected to score against the reference).
"""

from __future__ import annotations

import math
import textwrap
from typing import Any

from reports.decomposition_records import DecompositionRecord
from reports.panels import Assets
from reports.plots import figure_bytes
from reports.records import SceneComparison

__all__ = ["decomposition_section", "draw_waterfall", "waterfall_figure"]

_UP, _DOWN, _FIRST, _TOTAL = "tab:red", "tab:green", "tab:blue", "0.45"


def draw_waterfall(ax, record: DecompositionRecord, *, title: str = "") -> None:
    """Draw ``record``'s waterfall on the matplotlib axes ``ax``."""
    rows = record.table.records()
    if not rows:
        ax.text(0.5, 0.5, "no steps", ha="center", va="center", transform=ax.transAxes)
        return
    names = [r["step"] for r in rows] + ["method (total)"]
    tops = []
    for i, r in enumerate(rows):
        bottom, added = r["relmse_previous"], r["relmse_added"]
        colour = _FIRST if i == 0 else (_UP if added >= 0 else _DOWN)
        ax.bar(i, added, bottom=bottom, color=colour, width=0.6, edgecolor="0.2",
               linewidth=0.4)
        top = max(bottom, bottom + added)
        tops.append(top)
        label = f"{r['relmse']:.3g}" if i == 0 else f"{added:+.2g}"
        ax.annotate(label, (i, top), textcoords="offset points", xytext=(0, 2),
                    ha="center", va="bottom", fontsize=6)
        if i + 1 < len(rows):
            ax.plot([i + 0.3, i + 0.7], [r["relmse"]] * 2, color="0.3", linewidth=0.6)
    total = rows[-1]["relmse"]
    ax.bar(len(rows), total, color=_TOTAL, width=0.6, edgecolor="0.2", linewidth=0.4)
    ax.annotate(f"{total:.3g}", (len(rows), total), textcoords="offset points",
                xytext=(0, 2), ha="center", va="bottom", fontsize=6)
    floor = record.noise_floor
    if floor is not None and math.isfinite(floor):
        ax.axhline(floor, color="0.2", linestyle="--", linewidth=0.7,
                   label=f"reference noise floor ({record.noise_floor_kind}) {floor:.2g}")
        ax.axhline(0.5 * floor, color="0.2", linestyle=":", linewidth=0.7,
                   label="half the floor (the truth's expected relMSE)")
        ax.legend(fontsize=5, loc="upper left", frameon=False, ncol=2)
    ax.set_xticks(range(len(names)))
    ax.set_xticklabels([textwrap.fill(n, 12) for n in names], fontsize=6)
    ax.set_ylabel("caustic-region relMSE", fontsize=7)
    ax.tick_params(axis="y", labelsize=6)
    finite = [v for v in (*tops, total, floor) if v is not None and math.isfinite(v)]
    # Head room above the bars for their labels and the legend.
    ax.set_ylim(0, 1.45 * max(finite, default=0.0) or 1.0)
    if title:
        ax.set_title(title, fontsize=8)


def waterfall_figure(record: DecompositionRecord, *, title: str = ""):
    """A figure holding one waterfall (:func:`draw_waterfall`)."""
    import matplotlib  # noqa: PLC0415 - heavy, only when a plot is drawn

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt  # noqa: PLC0415 - heavy, only when a plot is drawn

    figure, ax = plt.subplots(figsize=(5.6, 3.0))
    draw_waterfall(ax, record, title=title)
    return figure


def decomposition_section(comparison: SceneComparison, assets: Assets) -> dict[str, Any] | None:
    """What ``decomposition.html.j2`` shows (None when the study did not run): the
    waterfall (SVG asset), the table, the summary, the verdicts, the exact paths'
    flux fates and the study's run time."""
    record = getattr(comparison, "decomposition", None)
    if record is None:
        return None
    svg = figure_bytes(waterfall_figure(
        record, title=f"{comparison.name}: {comparison.method}"))
    return {
        "waterfall": assets.add("decomposition.svg", svg, mime="image/svg+xml"),
        "table": {"columns": list(record.table.columns),
                  "rows": [list(r) for r in record.table.rows]},
        "summary": record.summary, "claims": record.claims, "fates": record.fates,
        "run_time_s": record.run_time_s, "noise_floor": record.noise_floor,
        "noise_floor_kind": record.noise_floor_kind, "notes": record.notes,
    }
