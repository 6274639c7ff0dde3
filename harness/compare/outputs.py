"""Write a comparison's data files: metrics.json, CSV tables, EXR originals.

All writes are atomic (temporary file, then rename), so an interrupted run never
leaves a half-written file for the report or a later reader.
"""

from __future__ import annotations

import csv
import io
from dataclasses import asdict
from pathlib import Path
from typing import Any

from harness.compare.temporal_outputs import write_temporal_maps
from renderers.exr import write_exr
from reports.records import METRIC_FORMULAS, SceneComparison, Table
from scenes.files import atomic_write_bytes, dumps_strict

__all__ = ["HALF_MAPS", "budget_table", "comparison_json", "write_comparison", "write_json",
           "write_table"]

#: Map kinds written as 16-bit floats: bounded, and kept at that precision.
HALF_MAPS = frozenset({"ssim", "flip"})


def write_json(path: str | Path, data: Any) -> None:
    """Strict JSON (:func:`scenes.files.dumps_strict`: a non-finite float is ``null``,
    its reason under ``null_reasons``), written atomically."""
    atomic_write_bytes(path, (dumps_strict(data) + "\n").encode("utf-8"))


def write_table(path: str | Path, table: Table) -> None:
    """A :class:`Table` as CSV, written atomically."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(table.columns)
    writer.writerows(table.rows)
    atomic_write_bytes(path, buffer.getvalue().encode("utf-8"))


def _speedups(comparison: SceneComparison) -> dict[str, Any] | None:
    """Both equal-error speedups and the timing policy they follow, or None when
    no cost study ran. A withheld speedup keeps its values, with ``shown`` false and
    the reason (``harness.compare.headlines``)."""
    cost = comparison.section("cost")
    if cost is None:
        return None
    withheld = comparison.speedup_withheld
    return {"warm": asdict(cost.speedup) if cost.speedup else None,
            "cold": asdict(cost.speedup_cold) if cost.speedup_cold else None,
            "shown": withheld is None,
            "withheld_because": withheld.reason if withheld else None,
            **cost.timing}


def _records(table: Table | None) -> list[dict[str, Any]] | None:
    return table.records() if table is not None else None


def budget_table(comparison: SceneComparison) -> Table | None:
    """Both sides' flux budgets in one table (``side`` first), for budget.csv."""
    budgets = comparison.budgets
    sides = [(side, t) for side, t in (("method", budgets.method),
                                       ("reference", budgets.reference))
             if t is not None]
    if not sides:
        return None
    columns = ("side", *sides[0][1].columns)
    return Table(columns, tuple((side, *row) for side, t in sides for row in t.rows))


def comparison_json(comparison: SceneComparison) -> dict[str, Any]:
    """The JSON form of a comparison (everything but the images)."""
    return {
        "scene": {"name": comparison.name, "description": comparison.description,
                  "source": comparison.source, "effects": list(comparison.effects)},
        "method": {"name": comparison.method, "description": comparison.method_description},
        "settings": comparison.settings,
        "formulas": METRIC_FORMULAS,
        "metrics": [asdict(m) for m in comparison.metrics],
        "exposure": comparison.exposure,
        "equal_error_speedup": _speedups(comparison),
        "claims": comparison.claims,
        "checks": [asdict(t) for t in comparison.checks],
        "stability": comparison.stability,
        "flux_budget": _records(comparison.budgets.summary),
        "budgets": {"method": _records(comparison.budgets.method),
                    "reference": _records(comparison.budgets.reference),
                    "reference_trace": comparison.budgets.trace},
        "headlines": [asdict(h) for h in comparison.headlines],
        "claim_verdicts": [asdict(v) for v in comparison.claim_verdicts],
        "crosscheck": comparison.crosscheck.records() if comparison.crosscheck else None,
        "provenance": comparison.provenance.as_dict(),
        "studies": {s.name: s.as_dict() for s in comparison.sections},
        "files": comparison.files,
    }



def write_comparison(scene_dir: str | Path, comparison: SceneComparison) -> None:
    """Write metrics.json, each study section's tables (``convergence.csv``,
    ``cost_accuracy.csv``, ``temporal.csv``, ``decomposition.csv``, a plug-in's own),
    the temporal maps (``harness.compare.temporal_outputs``), flux_budget.csv (both
    sides' budgets, :func:`budget_table`) and the EXR originals named in
    ``comparison.files`` (keys ``<view>/<kind>`` of ``comparison.images``)."""
    scene_dir = Path(scene_dir)
    for key, name in comparison.files.items():
        image = comparison.images[key]
        # A map (SSIM, FLIP) is one channel, Y, held at half precision
        # (``harness.compare.evaluate.score_view``); an image is RGB, float32.
        write_exr(scene_dir / name, {"RGB" if image.ndim == 3 else "Y": image},
                  half=key.rsplit("/", 1)[-1] in HALF_MAPS)
    for section in comparison.sections:
        for name, table in section.tables().items():
            write_table(scene_dir / name, table)
    if comparison.temporal is not None:
        write_temporal_maps(scene_dir, comparison.temporal)
    budgets = budget_table(comparison)
    if budgets is not None:
        write_table(scene_dir / "flux_budget.csv", budgets)
    write_json(scene_dir / "metrics.json", comparison_json(comparison))
