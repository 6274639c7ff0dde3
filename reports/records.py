"""What one scene's comparison produced: the in-memory contract between the
comparison (``harness.compare``) and the HTML report (``reports``).

The comparison fills a :class:`SceneComparison`; the report turns it into
``DIR/<scene>/index.html`` and the summary ``DIR/index.html``. Nothing in here
renders or computes; these are plain frozen records.

Image naming: ``images`` keys are ``"<view>/<kind>"`` where view is ``camera`` or
``receiver0``, ``receiver1``, ... and kind is one of

* ``method``       caustics-mapping image, linear float32 (H, W, 3)
* ``reference``  Mitsuba mean, linear float32 (H, W, 3)
* ``reference_variance``  variance of that mean (receivers, and the camera when it
  is compared), float32 (H, W, 3)
* ``signed``     method − reference, float (H, W, 3)
* ``ssim``       SSIM map of the tone-mapped images, float (H, W) in [-1, 1]
* ``flip``       HDR-FLIP map, float (H, W) in [0, 1]
* ``mask_caustic``  bool (H, W): the scene's caustic region, the independent
  reference above its threshold (``harness.compare.regions.scene_caustic_region``)
* ``mask_object``   bool (H, W), camera only: pixels of the caustic object and its
  silhouette (excluded from ``object_masked``; the ``object`` region is its interior)

Receiver maps are stored with row 0 at vmin (``renderers.results``); flip them
vertically for display so +v points up.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import TYPE_CHECKING, Any, Literal, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:  # the temporal record imports Table from here
    from reports.decomposition_records import DecompositionRecord
    from reports.temporal_records import TemporalComparison

__all__ = [
    "CHECK_KINDS",
    "CHECK_KIND_MEANING",
    "CHECK_RELATIONS",
    "CLAIM_VERDICTS",
    "COMPARED",
    "METRIC_FORMULAS",
    "NO_CAUSTIC",
    "STATUS_REASONS",
    "Check",
    "ClaimVerdict",
    "ConvergenceSection",
    "CostSection",
    "EqualErrorSpeedup",
    "FluxBudgets",
    "Headline",
    "MethodProvenance",
    "MetricValue",
    "Provenance",
    "RecordSection",
    "SceneComparison",
    "SceneFailure",
    "Section",
    "SpeedupWithheld",
    "StudySection",
    "Table",
    "slower",
]

#: Human-readable formula of each metric, shown beside its value in every output.
METRIC_FORMULAS: dict[str, str] = {
    "relmse": "mean of (method − ref)² / (ref² + 0.01) over pixels and channels",
    "relmse_trimmed": "relMSE after dropping the largest 0.1 % of the terms",
    "psnr": "10 log10(peak² / MSE) dB, peak = max of ref in the region",
    "ssim": "mean SSIM (Wang et al. 2004: Gaussian σ = 1.5, population covariance, "
            "K1 = 0.01, K2 = 0.03) of Reinhard + sRGB tone-mapped images, data_range 1",
    "flip": "mean HDR-FLIP (Andersson et al. 2021) with the scene's fixed exposure range",
    "flux_ratio": "Σ luminance(method) / Σ luminance(ref) over the region (1 = energy kept)",
    "stray_flux": "Σ luminance(method) outside the scene's caustic region / Σ luminance(ref) "
                  "over the whole map (excess: minus the reference's own share there)",
}


#: A comparison's status: it answered the question (its metrics, studies and checks).
COMPARED = "compared"
#: A comparison's status: the reference puts no caustic light on any receiver, so the
#: scene poses no question (every caustic metric NaN); the scores and the flux budget
#: still say where the light went, and no study, check or cross-check ran.
NO_CAUSTIC = "no caustic"
#: Why a comparison with a status other than :data:`COMPARED` is not an answer (the
#: one line its failure row and page show).
STATUS_REASONS: dict[str, str] = {
    NO_CAUSTIC: "no caustic: the reference puts no caustic light on any receiver (check "
                "where the light, objects and receivers are)",
}


def slower(speedup: float) -> bool:
    """Whether an equal-error speedup means the method is slower than the reference
    at the same error (a finite, positive speedup below 1): it then reads "1.6×
    slower", never "0.62× speedup"."""
    return math.isfinite(speedup) and 0 < speedup < 1


@dataclass(frozen=True)
class EqualErrorSpeedup:
    """Equal-error speedup of a real-time point over the reference's curve.

    Attributes
    ----------
    speedup : float
        t_ref(e_method) / t_method (an upper bound when ``kind == "bound"``).
    reference_time : float
        t_ref(e_method) in seconds.
    kind : {"interpolated", "extrapolated", "bound"}
        How t_ref(e_method) was obtained (see the module docstring).
    low, high : float
        95 % interval of the speedup (``harness.studies.pareto``); NaN where none
        was computed, ``high`` infinite for a lower bound.
    slope, slope_stderr : float
        Fitted log-log slope of the reference's excess relMSE against its time, and
        its standard error (NaN where no fit was made).
    bound_kind : {"estimate", "lower bound", "upper bound"}
        ``speedup`` is an estimate, or "at least" (the method's excess interval
        contains 0: the bound at its upper end), or "at most" (the reference's
        cheapest budget already reaches the method's error).
    """

    speedup: float
    reference_time: float
    kind: Literal["interpolated", "extrapolated", "bound"]
    low: float = float("nan")
    high: float = float("nan")
    slope: float = float("nan")
    slope_stderr: float = float("nan")
    bound_kind: Literal["estimate", "lower bound", "upper bound"] = "estimate"

    @property
    def text(self) -> str:
        """``12.3× (95 % [9.8, 15.1])``, ``1.6× slower (speedup 0.625×, 95 % [0.5,
        0.8])``, ``at least 40×`` or ``at most 2×``."""
        if self.bound_kind == "lower bound":
            return f"at least {self.speedup:.3g}×"
        if self.bound_kind == "upper bound" or self.kind == "bound":
            return f"at most {self.speedup:.3g}×"
        interval = (f"95 % [{self.low:.3g}, {self.high:.3g}]"
                    if self.low == self.low and self.high == self.high else "")  # not NaN
        if slower(self.speedup):
            inside = ", ".join(p for p in (f"speedup {self.speedup:.3g}×", interval) if p)
            return f"{1 / self.speedup:.3g}× slower ({inside})"
        return f"{self.speedup:.3g}×" + (f" ({interval})" if interval else "")


@dataclass(frozen=True)
class SpeedupWithheld:
    """An equal-error speedup the report does not show, and why
    (``harness.compare.headlines``).

    Attributes
    ----------
    reason : str
        One sentence: the bound the error broke, with the numbers.
    warm, cold : EqualErrorSpeedup or None
        The speedups computed (kept for metrics.json, not shown).
    short : str
        The reason in a few words (the CLI's summary table).
    """

    reason: str
    warm: EqualErrorSpeedup | None = None
    cold: EqualErrorSpeedup | None = None
    short: str = ""


#: A paper claim's verdict: its 95 % interval lies within the claim's bound (holds) or
#: beyond it (does not hold), or straddles it (undecided); or it was not measured.
CLAIM_VERDICTS = ("holds", "does not hold", "undecided at this noise", "not measured")


@dataclass(frozen=True)
class ClaimVerdict:
    """One of the paper's claims against a measured number and its uncertainty
    (``harness.studies.claims``).

    Attributes
    ----------
    claim : str
        The claim, as the report names it.
    verdict : str
        One of :data:`CLAIM_VERDICTS`.
    value, bound : float
        The measured quantity and the largest value for which the claim holds.
    standard_error : float or None
        One standard error of ``value`` (None: not known).
    quantity : str
        What ``value`` is, with its units.
    uncertainty : str
        Where ``standard_error`` comes from.
    text : str
        The sentence the report shows (verdict first, then the numbers).
    ci95 : tuple of float or None
        The 95 % interval (low, high) of ``value`` the verdict is read from (None:
        not known).
    """

    claim: str
    verdict: str
    value: float
    bound: float
    standard_error: float | None
    quantity: str
    uncertainty: str
    text: str
    ci95: tuple[float, float] | None = None

    @property
    def margin(self) -> float:
        """bound − value: positive where the claim holds."""
        return self.bound - self.value


@dataclass(frozen=True)
class Headline:
    """A banner at the top of a scene's page (``harness.compare.headlines``).

    Attributes
    ----------
    kind : str
        ``reference_noise`` (the reference missed its noise target),
        ``noise_floor`` (the method's error is within the reference's noise),
        ``speedup`` (the equal-error speedup, or why it is withheld), ``claim``
        (a paper claim's verdict), ``budget`` (a flux budget that does not close),
        ``checks`` (accuracy checks that failed, each cited), ``timing`` (a time
        reported by an external renderer, not measured by the harness), ``views`` (a
        view the method gave no image of, not scored).
    level : str
        ``warning`` (read before any number below) or ``note``.
    text : str
        One or two sentences with the numbers.
    """

    kind: str
    level: str
    text: str


@dataclass(frozen=True)
class MetricValue:
    """One metric of the method's render, with what the reference's noise alone would
    give and the method's own (excess) error with its uncertainty.

    Attributes
    ----------
    view : str
        ``camera`` or ``receiver<i>``.
    region : str
        ``full`` (the whole receiver map or image), ``caustic`` (the scene's caustic
        region: thresholded on the independent reference alone, the same texels for
        every method; never the scored reference's own, which would select on its
        noise), ``outside`` (the receiver map outside it: ``stray_flux`` only),
        ``object`` (camera pixels inside a caustic object's silhouette: the object
        seen through) or ``object_masked`` (camera without the object and its
        silhouette).
    metric : str
        A key of :data:`METRIC_FORMULAS`.
    value : float
        The method against the reference.
    noise_floor : float or None
        The same metric of an independent reference against the reference (it holds
        both references' noise: twice what a perfect method scores on relMSE).
    baseline : float or None
        A perfect method's expected value against this reference (its noise alone).
    excess : float or None
        The method's own error against the noise-free image, estimated without bias
        (``docs/statistics.md``): excess relMSE; SSIM baseline − value; FLIP value −
        baseline; flux ratio − 1. None where the metric has no such estimator
        (``relmse_trimmed``, ``psnr``) or the reference has no variance.
    excess_stderr : float or None
        Its standard error (the texel is the unit: a texel's channels are one sample).
    excess_ci95 : (float, float) or None
        Its 95 % interval.
    distinguishable : bool or None
        Whether the interval excludes 0: the method is measurably off the truth.
    pixels : int or None
        The size of the region the value was computed over (texels or pixels).
    """

    view: str
    region: str
    metric: str
    value: float
    noise_floor: float | None = None
    baseline: float | None = None
    excess: float | None = None
    excess_stderr: float | None = None
    excess_ci95: tuple[float, float] | None = None
    distinguishable: bool | None = None
    pixels: int | None = None

    @property
    def verdict(self) -> str:
        """``measurably off`` (the interval lies above 0; below 0 for a flux measure),
        ``within noise`` (the interval contains 0), ``variance overstated`` (an excess
        error wholly below 0, which no method can score) or ``no interval``."""
        if self.excess_ci95 is None:
            return "no interval"
        low, high = self.excess_ci95
        if low <= 0 <= high:
            return "within noise"
        if high < 0 and self.metric in ("relmse", "ssim", "flip"):
            return "variance overstated"
        return "measurably off"

    @property
    def interval_text(self) -> str:
        """``excess ± stderr [low, high]`` for headlines and tables ('' if none)."""
        if self.excess is None or self.excess_ci95 is None:
            return ""
        low, high = self.excess_ci95
        return f"{self.excess:.3g} ± {self.excess_stderr:.2g} (95 % [{low:.3g}, {high:.3g}])"


@dataclass(frozen=True)
class Table:
    """A small column table (CSV-shaped): ``rows`` are tuples in ``columns`` order."""

    columns: tuple[str, ...]
    rows: tuple[tuple[Any, ...], ...]

    def column(self, name: str) -> list[Any]:
        """All values of one column."""
        i = self.columns.index(name)
        return [row[i] for row in self.rows]

    def records(self) -> list[dict[str, Any]]:
        """The rows as dicts keyed by column name."""
        return [dict(zip(self.columns, row, strict=True)) for row in self.rows]

    @classmethod
    def from_records(cls, columns: tuple[str, ...], records) -> Table:
        """A table from dicts keyed by column name; every column must be present."""
        return cls(tuple(columns), tuple(tuple(r[c] for c in columns) for r in records))


#: The three kinds of accuracy check (``harness.checks``), in the order reports list them.
CHECK_KINDS = ("physical requirement", "method target", "regression lock")
#: What each kind means, shown beside it in every output.
CHECK_KIND_MEANING = {
    "physical requirement": "independent of the method's output: analytic answers, energy, "
                            "flux agreement, finite values; each constant carries its derivation",
    "method target": "what this method should reach, with the reason for the number; a target "
                     "missed today is a known gap, never a loosened number",
    "regression lock": "calibrated from today's output: guards against change, not accuracy",
}
#: How a check's bound applies to its value.
CHECK_RELATIONS = {"max": "value <= bound", "min": "value >= bound", "band": "|value - 1| <= bound"}


@dataclass(frozen=True)
class Check:
    """One accuracy check and whether it held.

    Attributes
    ----------
    metric, region, view : str
        What was measured, and where.
    bound : float
        The number the value is held to.
    relation : str
        How the bound applies (:data:`CHECK_RELATIONS`): ``max`` (value <= bound),
        ``min`` (value >= bound) or ``band`` (|value − 1| <= bound).
    value : float
        The measured value.
    passed : bool
        Whether the check holds: the value kept the bound, or, for a check judged
        from an interval, the whole interval did.
    origin : str
        Where the bound comes from: its derivation, the reason for a target, or the
        calibration of a lock.
    kind : str
        One of :data:`CHECK_KINDS`.
    subject : str
        Whose output is checked: ``method`` or ``reference``.
    gap : str
        Set when the check is a known miss (an expected failure whose reason names
        the gap).
    interval : (float, float) or None
        The value's 95 % interval where the measure has one (an excess error under
        the reference's noise): the check is judged from it (:attr:`verdict`).
    verdict : str
        ``holds`` (the interval, or the value, keeps the bound), ``fails`` (the
        interval, or the value, breaks it) or ``undecided`` (the interval straddles
        the bound: more reference photons would decide it). Empty: from ``passed``.
    """

    metric: str
    region: str
    view: str
    bound: float
    relation: str
    value: float
    passed: bool
    origin: str = ""
    kind: str = "regression lock"
    subject: str = "method"
    gap: str = ""
    interval: tuple[float, float] | None = None
    verdict: str = ""

    @property
    def decision(self) -> str:
        """:attr:`verdict`, or ``holds``/``fails`` from :attr:`passed`."""
        return self.verdict or ("holds" if self.passed else "fails")

    @property
    def outcome(self) -> str:
        """``pass``, ``FAIL``, ``undecided`` (the interval straddles the bound),
        ``known gap`` (a known gap that does not hold) or ``gap closed`` (a known gap
        that now holds: the gap entry should go)."""
        decision = self.decision
        if self.gap:
            return "gap closed" if decision == "holds" else "known gap"
        return {"holds": "pass", "undecided": "undecided"}.get(decision, "FAIL")

    @property
    def interval_text(self) -> str:
        """``[low, high]`` of the value's 95 % interval ('' when it has none)."""
        if self.interval is None:
            return ""
        return f"[{self.interval[0]:.4g}, {self.interval[1]:.4g}]"

    @property
    def bound_text(self) -> str:
        """The bound as a condition on the value."""
        sign = {"max": "≤ ", "min": "≥ ", "band": "|v − 1| ≤ "}.get(self.relation, "")
        return f"{sign}{self.bound:.4g}"

    @property
    def label(self) -> str:
        """``kind: metric (view, region)``, as headlines cite it."""
        return f"{self.kind}: {self.metric} ({self.view}, {self.region})"


@dataclass(frozen=True)
class MethodProvenance:
    """How the method's render was made and timed.

    Attributes
    ----------
    name, renderer : str
        The method's registered name and the renderer it reports.
    timer : str
        What ``frame_time_ms`` measured, with which clock.
    frame_time_ms : float
        Warm frame time (median of the repeats after a warm-up), ms.
    timings_ms : dict of str to float
        The last timed frame's per-pass times (ms), when the method reports passes.
    maps_time_ms : float or None
        Warm time of the passes that produce the receiver maps (ms): the scope of the
        equal-error speedup (caustics mapping only).
    preset, passes, gl_renderer, lost_splats, status_counts, status_flux_fraction
        Caustics mapping only: the preset, the passes run, the GL renderer, splats
        lost, per-status vertex counts and flux shares.
    worker : str or None
        The Dask worker that rendered it (sweeps).
    metadata : dict
        What a third-party method reported (its ``RenderResult.metadata``).
    """

    name: str
    renderer: str
    timer: str
    frame_time_ms: float
    timings_ms: dict[str, float] = field(default_factory=dict)
    maps_time_ms: float | None = None
    preset: str | None = None
    passes: tuple[str, ...] | None = None
    gl_renderer: str | None = None
    lost_splats: Any = None
    status_counts: dict[str, Any] | None = None
    status_flux_fraction: dict[str, Any] | None = None
    worker: str | None = None
    metadata: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Provenance:
    """Where every number of a comparison comes from.

    Attributes
    ----------
    scene_file : str
        The scene file compared.
    method : MethodProvenance
        The method's render and its timing.
    reference, independent_reference : dict
        The reference's settings, noise, versions, timings and cache outcome; the
        independent reference's seeds, noise and cache outcome.
    machine : dict
        Platform, processor, CPU count, Python version.
    notes : tuple of str
        What was left out and why (e.g. a camera that a ``ptracer`` reference cannot
        score).
    checks_not_applied : dict of str to str
        Per kind of accuracy check that did not apply, why.
    crosscheck : dict or None
        The independent renderer's settings, when a cross-check ran.
    sweep : dict or None
        The sweep row's settings, when the comparison is a sweep row.
    """

    scene_file: str
    method: MethodProvenance
    reference: dict[str, Any] = field(default_factory=dict)
    independent_reference: dict[str, Any] = field(default_factory=dict)
    machine: dict[str, Any] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    checks_not_applied: dict[str, str] = field(default_factory=dict)
    crosscheck: dict[str, Any] | None = None
    sweep: dict[str, Any] | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON form (``metrics.json``'s ``provenance``)."""
        return asdict(self)


@runtime_checkable
class Section(Protocol):
    """What a study adds to a comparison (``harness.compare.studies``): a typed
    record with a name, a title, a JSON form and its tables.

    ``metrics.json`` holds ``as_dict()`` under ``studies[name]``; every table of
    ``tables()`` is written as a CSV file of that name beside it; the page shows the
    section under its title (its values and tables, unless the report has a
    dedicated panel for it).
    """

    name: str
    title: str

    def as_dict(self) -> dict[str, Any]:
        """JSON form (strict JSON: NaN becomes null)."""
        ...

    def tables(self) -> dict[str, Table]:
        """CSV files to write: file name (``convergence.csv``) → table."""
        ...


@dataclass(frozen=True)
class StudySection:
    """A generic study section: a summary sentence, named values and tables.

    Attributes
    ----------
    name : str
        Key in ``metrics.json``'s ``studies`` and the page's anchor (letters, digits,
        ``_``).
    title : str
        Heading on the page.
    summary : str
        One or two sentences with the study's finding.
    values : dict
        Named numbers (JSON-serialisable), shown as a list on the page.
    files : dict of str to Table
        CSV files to write beside ``metrics.json`` (file name → table).
    """

    name: str
    title: str
    summary: str = ""
    values: dict[str, Any] = field(default_factory=dict)
    files: dict[str, Table] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """JSON form: summary, values and each table's records."""
        return {"summary": self.summary, "values": self.values,
                "tables": {name: t.records() for name, t in self.files.items()}}

    def tables(self) -> dict[str, Table]:
        """The CSV files of :attr:`files`."""
        return dict(self.files)


@dataclass(frozen=True)
class ConvergenceSection:
    """The estimators' convergence table and the paper's claims judged on it.

    Attributes
    ----------
    table : Table
        Columns: estimator, safeguarded, iteration, mean_error_m, p95_error_m,
        max_error_m, mean_error_texels, p95_error_texels, max_error_texels,
        converged, diverged, oscillating, stalled, lost, lookups_per_vertex, relmse,
        time_ms.
    claims : dict of str to str
        Each claim and its verdict as a sentence.
    claim_verdicts : tuple of ClaimVerdict
        The same verdicts with their numbers and uncertainties.
    """

    table: Table
    claims: dict[str, str] = field(default_factory=dict)
    claim_verdicts: tuple[ClaimVerdict, ...] = ()
    name: str = "convergence"
    title: str = "Convergence of the intersection estimators"

    def as_dict(self) -> dict[str, Any]:
        """JSON form: the claims (the table is ``convergence.csv``)."""
        return {"claims": self.claims, "claim_verdicts": [asdict(v) for v in self.claim_verdicts]}

    def tables(self) -> dict[str, Table]:
        """``convergence.csv``."""
        return {"convergence.csv": self.table}


@dataclass(frozen=True)
class CostSection:
    """What accuracy costs in time: the sweep and the equal-error speedup.

    Attributes
    ----------
    table : Table
        Columns: series (``caustics_mapping`` or ``reference``), label, estimator,
        iterations, grid, caustic_map, splat_sigma, time_warm_s, time_cold_s, relmse,
        pareto.
    speedup, speedup_cold : EqualErrorSpeedup or None
        Warm against warm (the headline) and cold against cold.
    point : (float, float) or None
        The method's (time s, relMSE) the speedups were computed for.
    timing : dict
        The timing policy and each side's one-off costs: ``{"policy": str,
        "method": {"build_s", "compile_s"}, "reference": {...}}``.
    """

    table: Table
    speedup: EqualErrorSpeedup | None = None
    speedup_cold: EqualErrorSpeedup | None = None
    point: tuple[float, float] | None = None
    timing: dict[str, Any] = field(default_factory=dict)
    name: str = "cost"
    title: str = "What accuracy costs in time"

    def as_dict(self) -> dict[str, Any]:
        """JSON form: the speedups, the point and the timing policy (the sweep is
        ``cost_accuracy.csv``)."""
        return {"warm": asdict(self.speedup) if self.speedup else None,
                "cold": asdict(self.speedup_cold) if self.speedup_cold else None,
                "point": list(self.point) if self.point else None, **self.timing}

    def tables(self) -> dict[str, Table]:
        """``cost_accuracy.csv``."""
        return {"cost_accuracy.csv": self.table}


@dataclass(frozen=True)
class RecordSection:
    """A study whose record has a panel of its own on the page (the temporal study's
    :class:`~reports.temporal_records.TemporalComparison`, the decomposition's
    :class:`~reports.decomposition_records.DecompositionRecord`).

    Attributes
    ----------
    name, title : str
        As :class:`Section`.
    record : object
        The study's record; it has ``as_dict()`` and a ``table`` (the CSV named
        ``csv``).
    csv : str
        File name of the record's table.
    """

    name: str
    title: str
    record: Any
    csv: str

    def as_dict(self) -> dict[str, Any]:
        """The record's JSON form."""
        return self.record.as_dict()

    def tables(self) -> dict[str, Table]:
        """The record's table under :attr:`csv`."""
        return {self.csv: self.record.table}


@dataclass(frozen=True)
class FluxBudgets:
    """Where the light went, on both sides (``harness.compare.budget``).

    Attributes
    ----------
    summary : Table or None
        Columns: item, flux_w, fraction (of the traced flux); the report shows it
        when the flux ratio is far from 1.
    method, reference : Table or None
        Each side's budget in watts per RGB channel
        (``harness.compare.budget.SIDE_COLUMNS``): emitted toward the object, where
        it went, and what is unaccounted; the reference's from a separate
        caustic-only trace, with standard errors.
    trace : dict or None
        Provenance of the reference's budget trace (photons, launches, seed, stream,
        seconds, emitted and unaccounted watts).
    """

    summary: Table | None = None
    method: Table | None = None
    reference: Table | None = None
    trace: dict[str, Any] | None = None


@dataclass(frozen=True, eq=False)
class SceneComparison:
    """Everything the report shows for one scene and method, in typed sections.

    Attributes
    ----------
    name, description, source : str
        From the scene file (untrusted text: the report must escape it).
    effects : tuple of str
        Effects the scene calls for.
    settings : dict
        Renderer settings used (JSON-serialisable).
    method, method_description : str
        The method compared (a caustics-mapping preset, ``paper`` or ``strong``, or a
        registered third-party method) and its one-line description.
    metrics : tuple of MetricValue
    images : dict of str to ndarray
        See the module docstring for keys and layouts.
    exposure : dict
        ``white`` (tone-curve white point per view), ``flip_start``, ``flip_stop``
        (exposure stops), ``diff_range`` (symmetric colour-bar limit per view).
    files : dict of str to str
        Paths of written originals relative to the scene's output folder
        (``{"camera/method": "camera_method.exr", ...}``).
    provenance : Provenance
    stability : dict or None
        Outcome of the numerical-stability checks for this scene, if run.
    budgets : FluxBudgets
        Where the light went on both sides.
    sections : tuple of Section
        What each study added (``harness.compare.studies``), in the order they ran.
    checks : tuple of Check
        The accuracy checks of every kind (physical requirements, method targets,
        regression locks) that applied to this scene and method.
    crosscheck : Table or None
        The reference against an independent renderer, when one was run. Columns:
        kind (total, encircled, region), label, share, reference_w, other_w, ratio,
        deviation_pct (100 (ratio - 1)), sigma_pct, z, tolerance_pct, agrees.
    headlines : tuple of Headline
        Banners at the top of the page (``harness.compare.headlines``), made last so
        that they can cite the checks.
    speedup_withheld : SpeedupWithheld or None
        Set when the equal-error speedup is not meaningful: why, and the values
        computed (:attr:`speedup` and :attr:`speedup_cold` are then None).
    status : str
        :data:`COMPARED`, or why the comparison is not an answer
        (:data:`STATUS_REASONS`: :data:`NO_CAUSTIC`); the callers make such a
        comparison a failure row and page that keeps its data files.
    """

    name: str
    description: str
    source: str
    effects: tuple[str, ...]
    settings: dict[str, Any]
    method: str
    method_description: str
    metrics: tuple[MetricValue, ...]
    images: dict[str, np.ndarray]
    exposure: dict[str, Any]
    files: dict[str, str]
    provenance: Provenance
    stability: dict[str, Any] | None = None
    budgets: FluxBudgets = field(default_factory=FluxBudgets)
    sections: tuple[Section, ...] = ()
    checks: tuple[Check, ...] = ()
    crosscheck: Table | None = None
    headlines: tuple[Headline, ...] = ()
    speedup_withheld: SpeedupWithheld | None = None
    status: str = COMPARED

    @property
    def page(self) -> str:
        """The page's name: scene and method (``glass_sphere-strong``)."""
        return f"{self.name}-{self.method}"

    @property
    def answered(self) -> bool:
        """Whether the comparison answered (:attr:`status` is :data:`COMPARED`)."""
        return self.status == COMPARED

    def metric(self, view: str, region: str, metric: str) -> MetricValue:
        """Look one metric up; KeyError if it was not computed."""
        for m in self.metrics:
            if (m.view, m.region, m.metric) == (view, region, metric):
                return m
        raise KeyError((view, region, metric))

    def section(self, name: str) -> Section | None:
        """The section a study named ``name`` added, or None."""
        return next((s for s in self.sections if s.name == name), None)

    def with_section(self, section: Section) -> SceneComparison:
        """A copy with ``section`` in place of the one of its name (or added last)."""
        kept = [s for s in self.sections if s.name != section.name]
        at = next((i for i, s in enumerate(self.sections) if s.name == section.name),
                  len(kept))
        return replace(self, sections=(*kept[:at], section, *kept[at:]))

    # Typed views of the built-in studies' sections, for the report's own panels.

    def _of(self, study: str, field_name: str, default: Any = None) -> Any:
        """``field_name`` of the section ``study`` added, or ``default``."""
        section = self.section(study)
        return getattr(section, field_name) if section is not None else default

    @property
    def convergence(self) -> Table | None:
        """The convergence table (:class:`ConvergenceSection`), if that study ran."""
        return self._of("convergence", "table")

    @property
    def claim_verdicts(self) -> tuple[ClaimVerdict, ...]:
        """The paper's claims with their numbers (from the convergence study)."""
        return self._of("convergence", "claim_verdicts", ())

    @property
    def cost(self) -> Table | None:
        """The cost-versus-accuracy sweep (:class:`CostSection`), if that study ran."""
        return self._of("cost", "table")

    @property
    def speedup(self) -> EqualErrorSpeedup | None:
        """Warm-against-warm equal-error speedup; None when withheld or not run."""
        return None if self.speedup_withheld else self._of("cost", "speedup")

    @property
    def speedup_cold(self) -> EqualErrorSpeedup | None:
        """Cold-against-cold equal-error speedup; None when withheld or not run."""
        return None if self.speedup_withheld else self._of("cost", "speedup_cold")

    @property
    def speedup_point(self) -> tuple[float, float] | None:
        """The method's (time s, relMSE) the speedups were computed for."""
        return self._of("cost", "point")

    @property
    def timing(self) -> dict[str, Any] | None:
        """The cost study's timing policy and one-off costs, if it ran."""
        return self._of("cost", "timing")

    @property
    def temporal(self) -> TemporalComparison | None:
        """The temporal study's record, if it ran."""
        return self._of("temporal", "record")

    @property
    def decomposition(self) -> DecompositionRecord | None:
        """The decomposition study's record, if it ran."""
        return self._of("decomposition", "record")

    @property
    def claims(self) -> dict[str, str]:
        """Every claim any section judged, as sentences."""
        out: dict[str, str] = {}
        for s in self.sections:
            claims = getattr(s, "claims", None)
            if claims is None and isinstance(s, RecordSection):
                claims = getattr(s.record, "claims", None)
            out |= claims or {}
        return out

    @property
    def flux_budget(self) -> Table | None:
        """The summary flux budget (:attr:`FluxBudgets.summary`)."""
        return self.budgets.summary

    @property
    def failed_checks(self) -> tuple[Check, ...]:
        """The checks that failed (known gaps excluded)."""
        return tuple(c for c in self.checks if c.outcome == "FAIL")


@dataclass(frozen=True)
class SceneFailure:
    """A scene and method whose comparison (or its files, or its page) failed: the
    index gets a failure row and the page says why, while the other scenes go on.

    Attributes
    ----------
    name, method, source : str
        Scene name, method name and scene file (untrusted text: escape it).
    error : str
        One line: the exception's type and message.
    stage : str
        What was running: ``comparison``, ``data files`` or ``report page``.
    description : str
        The scene's description.
    flux_budget : Table or None
        Where the light went, when the comparison got that far (as in
        :class:`SceneComparison`).
    """

    name: str
    method: str
    source: str
    error: str
    stage: str = "comparison"
    description: str = ""
    flux_budget: Table | None = None

    @property
    def page(self) -> str:
        """The page's name, as :attr:`SceneComparison.page`."""
        return f"{self.name}-{self.method}"
