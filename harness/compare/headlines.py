"""Honest headlines: what a reader must know before any number on a scene's page.

:func:`with_headlines` reads a finished :class:`~reports.records.SceneComparison`
and adds banners (``headlines``), and withholds the equal-error speedup where the
error it is computed for means nothing (``speedup_withheld``). Rules:

* **reference noise**: the reference stopped at its photon budget or its time cap
  above its noise target (``relative_noise > target_noise``), with its
  relative noise per channel over the scored caustic region. Every interval below
  is wider for it.
* **verdict**: whether the method is measurably off the noise-free image: the 95 %
  interval of its excess relMSE (receiver 0, caustic region;
  :mod:`harness.compare.uncertainty`) excludes 0 or not, with the excess, its
  interval, the raw value and what a perfect method would score against this
  reference. (The old rule, "relMSE at most the noise floor", compared the method
  with an independent reference scored against the reference, which holds twice
  the reference's variance: a method 2 % off passed it.)
* **speedup**: shown only when the error it is computed at is meaningful. It is
  withheld, with the reason, when

  - relMSE >= :data:`RELMSE_USABLE` (1): relMSE = mean (x − r)² / (r² + ε), and a
    black image (x = 0) scores mean r² / (r² + ε) < 1; an error of 1 or more is
    worse than rendering no caustic at all, not an estimate of it, and matching it
    takes the reference almost no photons;
  - the method is not measurably off (above): the reference's curve cannot be read
    at an error the comparison cannot tell from zero;
  - the reference's curve does not reach the error: its cheapest budget is already
    more accurate (``kind == "bound"``: only an upper bound), or the error is below
    the curve's best by more than :data:`EXTRAPOLATION_LIMIT` (4). The curve's
    budgets go up to a quarter of the reference's photons, so 4x the last budget is
    the reference's own photon count; beyond it the 1/t extrapolation would claim
    errors smaller than the reference itself resolves.

* **claims**: each paper claim's verdict (``harness.studies.claims``), a warning when
  it is undecided at this noise.
* **budget**: a side's flux budget that does not add up to its emitted flux within
  :data:`BUDGET_CLOSURE` (1e-3).
* **timing**: the time an external renderer reported of itself
  (``harness.compare.external``), shown as reported and labelled as not measured by
  the harness; no speedup is computed from it.
* **views**: a view the method gave no image of (an external render of the camera
  or the receivers alone), not scored.
* **checks**: every accuracy check that failed (a known gap is not a failure), each
  cited with its value and bound, first on the page. Headlines are made last in
  the pipeline, after the checks, so that they can.
"""

from __future__ import annotations

import dataclasses
import math

from harness.compare.budget import budget_closure
from reports.records import Headline, SceneComparison, SpeedupWithheld

__all__ = ["BUDGET_CLOSURE", "EXTRAPOLATION_LIMIT", "RELMSE_USABLE", "headlines_for",
           "speedup_reason", "with_headlines"]

#: relMSE at or above which the method's image is no estimate (module docstring).
RELMSE_USABLE = 1.0
#: How far below the reference curve's smallest error an extrapolated speedup may go.
EXTRAPOLATION_LIMIT = 4.0
#: Largest |emitted − Σ parts| / emitted of a budget that closes: both sides measure
#: ~1e-5 (float32 sums); 1e-3 leaves room for round-off, not for a lost item.
BUDGET_CLOSURE = 1e-3


def _relmse(comparison: SceneComparison):
    try:
        return comparison.metric("receiver0", "caustic", "relmse")
    except KeyError:
        return None


def _column(row: dict) -> float | None:
    """A cost row's error: its excess relMSE where the study computed one, else raw."""
    value = row.get("excess", row["relmse"])
    value = row["relmse"] if value is None else value
    return float(value) if value is not None and math.isfinite(float(value)) else None


def _curve_errors(comparison: SceneComparison) -> list[float]:
    if comparison.cost is None:
        return []
    errors = [_column(r) for r in comparison.cost.records() if r["series"] == "reference"]
    return [e for e in errors if e is not None and e > 0]


def _method_error(comparison: SceneComparison, *, bound: bool) -> float:
    """The error the speedup is computed at: the comparison's own excess relMSE
    (receiver 0, caustic region; its interval's upper end for a lower bound), the
    number every table quotes; else the raw relMSE of the speedup's point."""
    relmse = _relmse(comparison)
    error = None
    if relmse is not None and relmse.excess is not None:
        error = (float(relmse.excess_ci95[1]) if bound and relmse.excess_ci95 is not None
                 else float(relmse.excess))
    if error is None and comparison.speedup_point is not None:
        error = comparison.speedup_point[1]
    return math.nan if error is None else error


def speedup_reason(error: float, measurably_off: bool | None, kind: str,
                   curve_errors: list[float], *, bound_kind: str = "estimate",
                   raw: float | None = None) -> tuple[str, str] | None:
    """Why the equal-error speedup at relMSE ``error`` is withheld, as (a few words,
    a sentence with the numbers), or None to show it (module docstring: the bound,
    the verdict, the curve's reach). ``measurably_off`` is the verdict on the
    method's excess error (None: unknown, no reference variance); a method that is
    not measurably off keeps its speedup only as a lower bound (``bound_kind``);
    ``raw`` is the raw relMSE the usability bound applies to (default ``error``)."""
    raw = error if raw is None else raw
    if raw is not None and math.isfinite(raw) and raw >= RELMSE_USABLE:
        return (f"relMSE {raw:.3g} >= {RELMSE_USABLE:g}",
                f"the method's relMSE is {raw:.3g}, at or above {RELMSE_USABLE:g}: worse "
                "than a black image (whose relMSE is below 1), so not an estimate whose "
                "cost could be compared")
    if error is None or not math.isfinite(error):
        return "relMSE not a number", "the method's relMSE is not a number"
    if measurably_off is False and bound_kind != "lower bound":
        return ("not measurably off",
                f"the method is not measurably off the noise-free image (its excess relMSE's "
                f"95 % interval contains 0; excess relMSE {error:.3g}): the reference's curve "
                "cannot be read at an error the comparison cannot tell from zero")
    if kind == "bound":
        return ("reference curve does not reach the error",
                f"the reference's cheapest budget is already more accurate than the method "
                f"(excess relMSE {error:.3g} against the curve's largest "
                f"{max(curve_errors, default=math.nan):.3g}): the curve does not reach "
                "this error, so the speedup would only be an upper bound")
    best = min(curve_errors, default=math.nan)
    if kind == "extrapolated" and math.isfinite(best) and error < best / EXTRAPOLATION_LIMIT:
        return (f"extrapolated past {EXTRAPOLATION_LIMIT:g}x the curve",
                f"the method's excess relMSE {error:.3g} is more than "
                f"{EXTRAPOLATION_LIMIT:g}x below "
                f"the reference curve's best {best:.3g}: past the reference's own photon "
                "count, where the 1/t extrapolation is not measured")
    return None


def _noise_headlines(comparison: SceneComparison) -> list[Headline]:
    out = []
    ref = comparison.provenance.reference
    noise, target = ref.get("relative_noise"), ref.get("target_noise")
    scored = (ref.get("relative_noise_scored") or {}).get("receiver0")
    if (ref.get("stopped_by") in ("budget", "time_cap") and noise is not None
            and target is not None and math.isfinite(noise) and noise > target):
        channels = (f"; per channel over the scored caustic region, R G B = "
                    f"{', '.join(f'{n:.3g}' for n in scored)}" if scored else "")
        out.append(Headline("reference_noise", "warning", (
            f"The reference missed its noise target: it stopped at its "
            f"{'time cap' if ref.get('stopped_by') == 'time_cap' else 'photon budget'} "
            f"({ref.get('photons')} photons per seed, {ref.get('seeds')} seeds) with a "
            f"relative noise of {noise:.3g} in its caustic region{channels}, against a "
            f"target of {target:.3g}. Every interval on this page is wider for it.")))
    return out


def _verdict_headline(comparison: SceneComparison) -> list[Headline]:
    relmse = _relmse(comparison)
    if relmse is None or relmse.excess is None or not math.isfinite(relmse.excess):
        return []
    numbers = (f"excess relMSE {relmse.interval_text} on receiver 0's caustic region "
               f"(raw {relmse.value:.3g}; a perfect method would score {relmse.baseline:.3g} "
               "against this reference)")
    if relmse.distinguishable and relmse.excess > 0:
        return [Headline("verdict", "note",
                         f"Measurably off the noise-free image: {numbers}.")]
    if relmse.verdict == "variance overstated":
        return [Headline("verdict", "warning", (
            f"The method's excess error lies wholly below 0: {numbers}. No method can "
            "score below a perfect one, so the reference's variance is overstated here "
            "and the interval says nothing about the method."))]
    return [Headline("verdict", "warning", (
        f"Not measurably off the noise-free image at this reference noise: {numbers}; the "
        "interval contains 0, so the comparison cannot tell the method from the truth. A "
        "less noisy reference could."))]


def _speedup(comparison: SceneComparison) -> tuple[Headline | None, SpeedupWithheld | None]:
    cost = comparison.section("cost")
    warm, cold = (cost.speedup, cost.speedup_cold) if cost is not None else (None, None)
    if warm is None and cold is None:
        return None, None
    relmse = _relmse(comparison)
    first = warm or cold
    error = _method_error(comparison, bound=first.bound_kind == "lower bound")
    raw = comparison.speedup_point[1] if comparison.speedup_point is not None else None
    verdict = relmse.distinguishable if relmse is not None else None
    reason = speedup_reason(error, verdict, first.kind, _curve_errors(comparison),
                            bound_kind=first.bound_kind, raw=raw)
    if reason is None:
        text = (f"Equal-error speedup, warm against warm: {warm.text} ({warm.kind})"
                if warm is not None else "")
        if cold is not None:
            text += f"{'; cold' if text else 'Cold'} against cold: {cold.text}"
        return Headline("speedup", "note",
                        text + f", at excess relMSE {error:.3g}."), None
    short, reason = reason
    return (Headline("speedup", "warning", f"Equal-error speedup withheld: {reason}."),
            SpeedupWithheld(reason=reason, warm=warm, cold=cold, short=short))


def _checks_headline(comparison: SceneComparison) -> list[Headline]:
    failed = comparison.failed_checks
    if not failed:
        return []
    cited = "; ".join(f"{c.label} = {c.value:.4g}"
                      + (f" (95 % {c.interval_text})" if c.interval is not None else "")
                      + f", bound {c.bound_text}" for c in failed)
    return [Headline("checks", "warning", (
        f"{len(failed)} accuracy check{'s' if len(failed) > 1 else ''} failed: {cited}."))]


def _reported_timing_headline(comparison: SceneComparison) -> list[Headline]:
    """The time an external renderer reported, as reported (module docstring)."""
    reported = comparison.provenance.method.metadata.get("reported_timing")
    if not reported:
        return []
    frame = reported.get("frame_ms")
    device = reported.get("device")
    said = (f"{frame:.4g} ms a frame" if frame is not None else "no frame time")
    said += f" on {device}" if device else ""
    return [Headline("timing", "note", (
        f"Time {reported.get('label', 'reported by the renderer')}: {said}. No "
        "equal-error speedup is computed from it: the harness times only what it "
        "renders."))]


def headlines_for(comparison: SceneComparison) -> tuple[tuple[Headline, ...],
                                                         SpeedupWithheld | None]:
    """The banners of ``comparison`` and the speedup it withholds (module docstring)."""
    out = (_checks_headline(comparison) + _noise_headlines(comparison)
           + _verdict_headline(comparison))
    out += [Headline("views", "note", f"{note[0].upper()}{note[1:]}.")
            for note in comparison.provenance.notes if " not scored: " in note]
    out += _reported_timing_headline(comparison)
    speedup, withheld = _speedup(comparison)
    if speedup is not None:
        out.append(speedup)
    for v in comparison.claim_verdicts:
        level = "warning" if v.verdict == "undecided at this noise" else "note"
        out.append(Headline("claim", level, f"Paper claim, {v.claim}: {v.text}."))
    for side, table in (("method", comparison.budgets.method),
                        ("reference", comparison.budgets.reference)):
        closure = budget_closure(table)
        if closure is not None and closure > BUDGET_CLOSURE:
            out.append(Headline("budget", "warning", (
                f"The {side}'s flux budget does not close: its parts miss the emitted flux "
                f"by {closure:.2%} (more than {BUDGET_CLOSURE:g}): flux went somewhere the "
                "budget does not name.")))
    return tuple(out), withheld


def with_headlines(comparison: SceneComparison) -> SceneComparison:
    """``comparison`` with its headlines, and its speedups withheld (kept in
    ``speedup_withheld``, with the reason) where they are not meaningful."""
    headlines, withheld = headlines_for(comparison)
    return dataclasses.replace(comparison, headlines=headlines, speedup_withheld=withheld)
