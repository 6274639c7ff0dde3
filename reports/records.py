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
* ``mask_caustic``  bool (H, W): the caustic region (reference above its threshold)
* ``mask_object``   bool (H, W), camera only: pixels of the caustic object and its
  silhouette (excluded from ``object_masked``; the ``object`` region is its interior)

Receiver maps are stored with row 0 at vmin (``renderers.results``); flip them
vertically for display so +v points up.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

if TYPE_CHECKING:  # the temporal record imports Table from here
    from reports.decomposition_records import DecompositionRecord
    from reports.temporal_records import TemporalComparison

__all__ = [
    "CHECK_KINDS",
    "CHECK_KIND_MEANING",
    "CLAIM_VERDICTS",
    "METRIC_FORMULAS",
    "ClaimVerdict",
    "EqualErrorSpeedup",
    "Headline",
    "MetricValue",
    "SceneComparison",
    "SceneFailure",
    "SpeedupWithheld",
    "Table",
    "ThresholdCheck",
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
}


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
    """

    speedup: float
    reference_time: float
    kind: Literal["interpolated", "extrapolated", "bound"]


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


#: A paper claim's verdict: it holds or fails by more than twice its standard error,
#: or the margin is within that (undecided); or it could not be measured.
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
    """

    claim: str
    verdict: str
    value: float
    bound: float
    standard_error: float | None
    quantity: str
    uncertainty: str
    text: str

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
        (a paper claim's verdict), ``budget`` (a flux budget that does not close).
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
    """One metric of the real-time render, beside the reference's noise floor.

    Attributes
    ----------
    view : str
        ``camera`` or ``receiver<i>``.
    region : str
        ``full`` (the whole receiver map or image), ``caustic`` (reference above
        the caustic threshold), ``object`` (camera pixels inside a caustic object's
        silhouette: the object seen through) or ``object_masked`` (camera without
        the object and its silhouette).
    metric : str
        A key of :data:`METRIC_FORMULAS`.
    value : float
        Caustics mapping vs the reference.
    noise_floor : float or None
        The same metric of an independent reference seed vs the reference: the
        error the reference's own noise alone produces.
    """

    view: str
    region: str
    metric: str
    value: float
    noise_floor: float | None = None


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


@dataclass(frozen=True)
class ThresholdCheck:
    """One accuracy check and whether it held.

    ``category`` is one of :data:`CHECK_KINDS`; ``subject`` says whose output is
    checked (``method`` or ``reference``); ``kind`` how the bound applies (``max``:
    value <= bound, ``min``: value >= bound, ``band``: |value − 1| <= bound);
    ``provenance`` where the number comes from (its derivation, reason or
    calibration); ``gap`` is set when the check is a known miss (an expected failure
    whose reason names the gap).
    """

    metric: str
    region: str
    view: str
    bound: float
    kind: str
    value: float
    passed: bool
    provenance: str = ""
    category: str = "regression lock"
    subject: str = "method"
    gap: str = ""

    @property
    def outcome(self) -> str:
        """``pass``, ``FAIL``, ``known gap`` (failed as expected) or ``gap closed``
        (a known gap that now passes: the gap entry should go)."""
        if self.gap:
            return "gap closed" if self.passed else "known gap"
        return "pass" if self.passed else "FAIL"

    @property
    def bound_text(self) -> str:
        """The bound as a condition on the value."""
        sign = {"max": "≤ ", "min": "≥ ", "band": "|v − 1| ≤ "}.get(self.kind, "")
        return f"{sign}{self.bound:.4g}"


@dataclass(frozen=True, eq=False)
class SceneComparison:
    """Everything the report shows for one scene.

    Attributes
    ----------
    name, description, source : str
        From the scene file (untrusted text: the report must escape it).
    effects : tuple of str
        Effects the scene calls for.
    settings : dict
        Renderer settings used (JSON-serialisable).
    metrics : tuple of MetricValue
    images : dict of str to ndarray
        See the module docstring for keys and layouts.
    exposure : dict
        ``white`` (tone-curve white point per view), ``flip_start``, ``flip_stop``
        (exposure stops), ``diff_range`` (symmetric colour-bar limit per view).
    convergence : Table or None
        Columns: estimator, safeguarded, iteration, mean_error_m, p95_error_m,
        max_error_m, mean_error_texels, p95_error_texels, max_error_texels,
        converged, diverged, oscillating, stalled, lost, lookups_per_vertex, relmse,
        time_ms.
    cost : Table or None
        Columns: series (``caustics_mapping`` or ``reference``), label, estimator,
        iterations, grid, caustic_map, splat_sigma, time_warm_s, time_cold_s, relmse,
        pareto.
    speedup : EqualErrorSpeedup or None
        Warm against warm: the headline (``harness.studies.timing``).
    speedup_cold : EqualErrorSpeedup or None
        Cold against cold: one-off build and compile costs included on both sides.
    timing : dict or None
        The timing policy and each side's one-off costs: ``{"policy": str,
        "method": {"build_s", "compile_s"}, "reference": {...}}``.
    temporal : TemporalComparison or None
        The temporal study (``--studies temporal``): the animation compared frame by
        frame, its flicker metrics and per-pixel maps (``reports.temporal_records``).
    decomposition : DecompositionRecord or None
        Where the error comes from (``--studies decomposition``): exact light paths,
        then the method's approximations one at a time (``reports.decomposition_records``).
    claims : dict of str to str
        The paper's claims checked against the convergence numbers, and the outcome.
    provenance : dict
        Passes run, event chains counted, photons/spp, seeds, versions, timings,
        timer, machine, reference cache hit.
    files : dict of str to str
        Paths of written originals relative to the scene's output folder
        (``{"camera/method": "camera_method.exr", ...}``).
    thresholds : tuple of ThresholdCheck
        The accuracy checks of every kind (physical requirements, method targets,
        regression locks) that applied to this scene and method.
    stability : dict or None
        Outcome of the numerical-stability checks for this scene, if run.
    crosscheck : Table or None
        The reference against an independent renderer, when one was run. Columns:
        kind (total, encircled, region), label, share, reference_w, other_w, ratio,
        deviation_pct (100 (ratio - 1)), sigma_pct, z, tolerance_pct, agrees.
    speedup_point : (float, float) or None
        The caustics-mapping (time s, relMSE) that ``speedup`` was computed for;
        the report marks it on the cost plot (when None it takes the Pareto point
        nearest to ``speedup.reference_time / speedup.speedup``).
    method, method_description : str
        The method compared (a caustics-mapping preset, ``paper`` or ``strong``, or a
        registered third-party method) and its one-line description.
    flux_budget : Table or None
        Where the light went (``harness.compare.budget``). Columns: item, flux_w,
        fraction (of the traced flux); the report shows it when the flux ratio is
        far from 1.
    method_budget, reference_budget : Table or None
        Each side's flux budget in watts per RGB channel
        (``harness.compare.budget.SIDE_COLUMNS``): emitted toward the object, where
        it went, and what is unaccounted; the reference's from a separate
        caustic-only trace (``budget_trace``), with standard errors.
    budget_trace : dict or None
        Provenance of the reference's budget trace (photons, launches, seed, stream,
        seconds, emitted and unaccounted watts).
    headlines : tuple of Headline
        Banners at the top of the page (``harness.compare.headlines``).
    claim_verdicts : tuple of ClaimVerdict
        The paper's claims with the uncertainty of their numbers (``claims`` holds
        the same verdicts as sentences).
    speedup_withheld : SpeedupWithheld or None
        Set when the equal-error speedup is not meaningful (``speedup`` and
        ``speedup_cold`` are then None): why, and the values computed.
    """

    name: str
    description: str
    source: str
    effects: tuple[str, ...]
    settings: dict[str, Any]
    metrics: tuple[MetricValue, ...]
    images: dict[str, np.ndarray]
    exposure: dict[str, Any]
    convergence: Table | None = None
    cost: Table | None = None
    speedup: EqualErrorSpeedup | None = None
    claims: dict[str, str] = field(default_factory=dict)
    provenance: dict[str, Any] = field(default_factory=dict)
    files: dict[str, str] = field(default_factory=dict)
    thresholds: tuple[ThresholdCheck, ...] = ()
    stability: dict[str, Any] | None = None
    speedup_point: tuple[float, float] | None = None
    crosscheck: Table | None = None
    method: str = "paper"
    method_description: str = ""
    flux_budget: Table | None = None
    speedup_cold: EqualErrorSpeedup | None = None
    timing: dict[str, Any] | None = None
    temporal: TemporalComparison | None = None
    decomposition: DecompositionRecord | None = None
    method_budget: Table | None = None
    reference_budget: Table | None = None
    budget_trace: dict[str, Any] | None = None
    headlines: tuple[Headline, ...] = ()
    claim_verdicts: tuple[ClaimVerdict, ...] = ()
    speedup_withheld: SpeedupWithheld | None = None

    @property
    def page(self) -> str:
        """The page's name: scene and method (``glass_sphere-strong``)."""
        return f"{self.name}-{self.method}"

    def metric(self, view: str, region: str, metric: str) -> MetricValue:
        """Look one metric up; KeyError if it was not computed."""
        for m in self.metrics:
            if (m.view, m.region, m.metric) == (view, region, metric):
                return m
        raise KeyError((view, region, metric))


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
