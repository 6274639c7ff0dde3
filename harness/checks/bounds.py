"""The reviewed TOML files of accuracy checks: regression locks, method targets and
known gaps, validated like scene files (every problem names the file and field).

Regression locks (``data/regression_locks.toml``, written by ``caustics calibrate``)::

    [[lock]]
    scene = "glass_sphere"
    view = "receiver0"          # camera | receiver<i>
    region = "caustic"          # full | caustic | object | object_masked
    metric = "relmse"           # see reports.records.METRIC_FORMULAS
    kind = "max"                # max: value <= bound; min: value >= bound;
                                # band: |value - 1| <= bound (flux ratio)
    bound = 0.12
    provenance = "4 references 0.081..0.093, platform jitter ..., 2026-11-22, mitsuba 3.9.1"

Method targets (``data/method_targets.toml``)::

    [[target]]
    scene = "glass_sphere"
    method = "strong"
    metric = "relmse"           # a key of MEASURES (computed in harness.checks.targets)
    kind = "max"
    bound = 0.012
    reason = "why this number (where it comes from)"
    contrast = "paper"          # optional: a method that must miss the target, so
                                # the measure is shown able to fail
    gap = ""                    # non-empty: missed today; the reason names the gap

Known gaps of physical requirements (``data/known_gaps.toml``)::

    [[gap]]
    check = "flux agreement"    # harness.checks.physical check name
    scene = "bunny"
    method = "paper"            # or "*"
    reason = "what is wrong, measured"

A file that is missing or unreadable is a :class:`ChecksFileError` naming it; it is
never taken for "no checks".
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from reports.records import METRIC_FORMULAS, Check, MetricValue
from scenes.errors import HarnessError
from scenes.schema import build, spec

__all__ = ["MEASURES", "Bound", "ChecksFileError", "Gap", "Target", "check_locks", "holds",
           "judge", "load_gaps", "load_locks", "load_targets", "locked_quantity"]

LOCK = "regression lock"
#: What a lock's value is measured at, which differs from the comparison's own records.
LOCK_SETTINGS = ("at the golden settings against the golden reference, over the scene's "
                 "caustic region from an independent reference (relMSE: the excess with "
                 "its interval; not this run's settings or reference)")

#: The measures a method target may name, each with a one-line description;
#: :mod:`harness.checks.targets` computes them and documents each in full.
MEASURES = {
    "relmse": "caustic-region excess relMSE (against the noise-free image), with its 95 % "
              "interval",
    "flux_ratio": "total flux ratio, channel furthest from 1",
    "focus_peak_ratio": "largest 3x3 box mean of the luminance, method / reference",
    "focus_share_difference": "|method − reference| share of luminance within 5 cm of the focus",
    "tir_flux_fraction": "share of the traced flux lost to total internal reflection",
    "off_receiver_flux_fraction": "share of the traced flux splatted off every receiver",
    "object_vertices": "grid vertices that traced an object",
    "camera_black_fraction_difference":
        "|black fraction of the camera over the sphere − the exact lens image's|",
    "camera_object_radiance_ratio":
        "mean luminance over the sphere, camera / exact lens image",
}


class ChecksFileError(HarnessError):
    """A locks, targets or gaps file is missing or unreadable (the message names it)."""


def holds(kind: str, bound: float, value: float) -> bool:
    """Whether ``value`` meets ``bound`` under ``kind`` (NaN never does)."""
    if not math.isfinite(value):
        return False
    if kind == "max":
        return value <= bound
    if kind == "min":
        return value >= bound
    return abs(value - 1.0) <= bound


def judge(kind: str, bound: float, value: float,
          interval: tuple[float, float] | None = None) -> str:
    """``holds``, ``fails`` or ``undecided``: a check judged from the 95 % interval of
    its value where it has one, as the pytest plugin's assertions judge.

    ``max``: holds when the interval's upper end is at most ``bound``, fails when its
    lower end is above it; ``min`` the mirror image; ``band`` (a ratio, |v − 1| ≤
    bound): holds when the whole interval lies within 1 ± bound, fails when none of
    it does. Otherwise the interval straddles the bound: undecided (more reference
    photons would decide it). Without an interval the value alone decides
    (:func:`holds`); a non-finite value or a NaN interval end fails (an infinite end
    is an unbounded interval: a ratio over a reference total that may be 0).
    """
    if interval is None:
        return "holds" if holds(kind, bound, value) else "fails"
    low, high = (float(x) for x in interval)
    if not math.isfinite(value) or math.isnan(low) or math.isnan(high):
        return "fails"
    if kind == "max":
        inside, outside = high <= bound, low > bound
    elif kind == "min":
        inside, outside = low >= bound, high < bound
    else:
        inside = 1.0 - bound <= low and high <= 1.0 + bound
        outside = high < 1.0 - bound or low > 1.0 + bound
    return "holds" if inside else "fails" if outside else "undecided"


def _view_problem(view: str) -> list[tuple[str, str]]:
    if view != "camera" and not (view.startswith("receiver") and view[8:].isdigit()):
        return [("view", "must be camera or receiver<i>")]
    return []


@dataclass(frozen=True)
class Bound:
    """One regression lock: today's calibrated value with a margin."""

    scene: str = spec(doc="Scene name.")
    view: str = spec(doc="camera or receiver<i>.")
    region: Literal["full", "caustic", "object", "object_masked"] = spec(doc="Region scored.")
    metric: str = spec(doc="Metric key.")
    kind: Literal["max", "min", "band"] = spec(doc="How the bound applies.")
    bound: float = spec(doc="The bound.", ge=0)
    provenance: str = spec(doc="How the bound was calibrated.")

    def validate(self) -> list[tuple[str, str]]:
        problems = _view_problem(self.view)
        if self.metric not in METRIC_FORMULAS:
            problems.append(("metric", f"unknown metric {self.metric!r}"))
        if not self.provenance.strip():
            problems.append(("provenance", "must say how the bound was calibrated"))
        return problems

    def holds(self, value: float) -> bool:
        """Whether ``value`` meets the bound (NaN never does)."""
        return holds(self.kind, self.bound, value)


@dataclass(frozen=True)
class Target:
    """One method target: what a method should reach on a scene, and why."""

    scene: str = spec(doc="Scene name.")
    method: str = spec(doc="Method (preset) name.")
    metric: str = spec(doc="Measure (a key of MEASURES).")
    kind: Literal["max", "min", "band"] = spec(doc="How the bound applies.")
    bound: float = spec(doc="The target.", ge=0)
    reason: str = spec(doc="Why this number: where it comes from.")
    view: str = spec("receiver0", doc="camera or receiver<i>.")
    region: Literal["full", "caustic", "object", "object_masked"] = spec("caustic",
                                                                       doc="Region.")
    contrast: str = spec("", doc="A method that misses the target (shows it can fail).")
    gap: str = spec("", doc="Non-empty: missed today; names the gap.")

    def validate(self) -> list[tuple[str, str]]:
        problems = _view_problem(self.view)
        if self.metric not in MEASURES:
            problems.append(("metric", f"unknown measure {self.metric!r} "
                                       f"(one of {', '.join(sorted(MEASURES))})"))
        if not self.reason.strip():
            problems.append(("reason", "must say where the number comes from"))
        return problems


@dataclass(frozen=True)
class Gap:
    """A physical requirement a method misses today."""

    check: str = spec(doc="Check name (harness.checks.physical).")
    scene: str = spec(doc="Scene name.")
    method: str = spec(doc="Method name, or * for every method.")
    reason: str = spec(doc="What is wrong, measured.")

    def validate(self) -> list[tuple[str, str]]:
        return [] if self.reason.strip() else [("reason", "must name the gap")]


@dataclass(frozen=True)
class _Locks:
    lock: tuple[Bound, ...] = spec(doc="The locks.")


@dataclass(frozen=True)
class _Targets:
    target: tuple[Target, ...] = spec(doc="The targets.")


@dataclass(frozen=True)
class _Gaps:
    gap: tuple[Gap, ...] = spec((), doc="The known gaps.")


def _load(path: str | Path, cls: type):
    path = Path(path)
    if not path.is_file():
        raise ChecksFileError(f"{path}: no such file" if not path.exists()
                              else f"{path}: not a file")
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as error:
        raise ChecksFileError(f"{path}: cannot read file ({error})") from None
    except tomllib.TOMLDecodeError as error:
        raise ChecksFileError(f"{path}: TOML syntax error ({error})") from None
    return build(cls, table, file=str(path), base_dir=path.parent)


def load_locks(path: str | Path) -> tuple[Bound, ...]:
    """Read and validate a regression-locks file."""
    return _load(path, _Locks).lock


def load_targets(path: str | Path) -> tuple[Target, ...]:
    """Read and validate a method-targets file."""
    return _load(path, _Targets).target


def load_gaps(path: str | Path) -> tuple[Gap, ...]:
    """Read and validate a known-gaps file."""
    return _load(path, _Gaps).gap


def locked_quantity(record: MetricValue) -> tuple[float, tuple[float, float] | None]:
    """What a lock on ``record`` holds, with its 95 % interval (None without one):
    relMSE its excess; the flux ratio its value, the interval of its excess (ratio − 1)
    moved back by 1; SSIM and FLIP their value (descriptive: no interval)."""
    interval = (tuple(float(x) for x in record.excess_ci95)
                if record.excess_ci95 is not None else None)
    if record.metric == "relmse" and record.excess is not None:
        return float(record.excess), interval
    if record.metric == "flux_ratio" and record.excess is not None and interval is not None:
        shift = float(record.value) - float(record.excess)
        return float(record.value), (interval[0] + shift, interval[1] + shift)
    return float(record.value), None


def check_locks(scene: str, metrics: list[MetricValue] | tuple[MetricValue, ...],
                bounds: tuple[Bound, ...]) -> tuple[Check, ...]:
    """Check every lock of ``scene`` against its metric; a missing metric fails. Each
    is judged from the 95 % interval of its locked quantity where it has one
    (:func:`locked_quantity`, :func:`judge`: holds, fails or undecided), else from the
    value."""
    records = {(m.view, m.region, m.metric): m for m in metrics}
    checks = []
    for b in bounds:
        if b.scene != scene:
            continue
        record = records.get((b.view, b.region, b.metric))
        value, interval = (float("nan"), None) if record is None else locked_quantity(record)
        verdict = judge(b.kind, b.bound, value, interval)
        # A lock is measured at other settings than the comparison's: its label says so,
        # so its relMSE is not read as the page's number for the same name.
        checks.append(Check(metric=b.metric, region=b.region, view=b.view,
                            bound=b.bound, relation=b.kind, value=value,
                            passed=verdict == "holds",
                            origin=f"{LOCK_SETTINGS}: {b.provenance}", kind=LOCK,
                            interval=interval, verdict=verdict if interval is not None else ""))
    return tuple(checks)
