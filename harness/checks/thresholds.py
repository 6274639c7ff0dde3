"""Accuracy thresholds: one reviewed TOML file of bounds, checked against metrics.

Each ``[[bound]]`` says what the caustics-mapping render of a scene must meet
against the Mitsuba reference::

    [[bound]]
    scene = "glass_sphere"
    view = "receiver0"          # camera | receiver<i>
    region = "caustic"          # full | caustic | object_masked
    metric = "relmse"           # see reports.records.METRIC_FORMULAS
    kind = "max"                # max: value <= bound; min: value >= bound;
                                # band: |value - 1| <= bound (flux ratio)
    bound = 0.12
    provenance = "spread over 4 seeds 0.081..0.093, margin 25 %, 2026-11-22, mitsuba 3.9.1"

The file is validated like a scene file: every problem names the file and field.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from reports.records import METRIC_FORMULAS, MetricValue, ThresholdCheck
from scenes.schema import Problem, SceneError, build, spec

__all__ = ["Bound", "check_bounds", "load_thresholds"]


@dataclass(frozen=True)
class Bound:
    """One accuracy bound."""

    scene: str = spec(doc="Scene name.")
    view: str = spec(doc="camera or receiver<i>.")
    region: Literal["full", "caustic", "object_masked"] = spec(doc="Region scored.")
    metric: str = spec(doc="Metric key.")
    kind: Literal["max", "min", "band"] = spec(doc="How the bound applies.")
    bound: float = spec(doc="The bound.", ge=0)
    provenance: str = spec("", doc="How the bound was calibrated.")

    def validate(self) -> list[tuple[str, str]]:
        problems = []
        if self.metric not in METRIC_FORMULAS:
            problems.append(("metric", f"unknown metric {self.metric!r}"))
        if self.view != "camera" and not (self.view.startswith("receiver")
                                          and self.view[8:].isdigit()):
            problems.append(("view", "must be camera or receiver<i>"))
        return problems

    def holds(self, value: float) -> bool:
        """Whether ``value`` meets the bound (NaN never does)."""
        if not math.isfinite(value):
            return False
        if self.kind == "max":
            return value <= self.bound
        if self.kind == "min":
            return value >= self.bound
        return abs(value - 1.0) <= self.bound


@dataclass(frozen=True)
class _File:
    bound: tuple[Bound, ...] = spec(doc="The bounds.")


def load_thresholds(path: str | Path) -> tuple[Bound, ...]:
    """Read and validate a thresholds file; SceneError names file and field on failure."""
    path = Path(path)
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError([Problem(str(path), "", f"cannot read file: {error}")]) from None
    except tomllib.TOMLDecodeError as error:
        raise SceneError([Problem(str(path), "", f"TOML syntax error: {error}")]) from None
    return build(_File, table, file=str(path), base_dir=path.parent).bound


def check_bounds(scene: str, metrics: list[MetricValue] | tuple[MetricValue, ...],
                 bounds: tuple[Bound, ...]) -> tuple[ThresholdCheck, ...]:
    """Check every bound of ``scene`` against its metric; a missing metric fails."""
    values = {(m.view, m.region, m.metric): m.value for m in metrics}
    checks = []
    for b in bounds:
        if b.scene != scene:
            continue
        value = values.get((b.view, b.region, b.metric), float("nan"))
        checks.append(ThresholdCheck(metric=b.metric, region=b.region, view=b.view,
                                     bound=b.bound, kind=b.kind, value=value,
                                     passed=b.holds(value), provenance=b.provenance))
    return tuple(checks)
