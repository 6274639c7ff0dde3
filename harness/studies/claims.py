"""The paper's two convergence claims, checked against measured numbers and the
uncertainty of those numbers.

Shah et al. 2007, Section 3.4: "For a fairly uniform topology, the error is
negligible after only five iterations. For the purpose of rendering caustics, we
observed that only a single iteration is sufficient."

We make both testable:

* **five iterations**: after 5 iterations of the modified estimator, the 95th
  percentile of the hit-distance error is at most one caustic-map texel
  (``NEGLIGIBLE_TEXELS``): below what the caustic map can resolve.
* **one iteration**: the image error (relMSE of the receiver map against the
  reference) after one iteration is within ``ONE_ITERATION_MARGIN`` (10 %) of the
  error after the most iterations measured: more iterations no longer change what
  one sees.

Verdict
-------
Each claim is "value <= bound" for a measured value with standard error σ. With the
margin m = bound − value, the claim **holds** when m >= k σ, **does not hold** when
m <= −k σ, and is **undecided at this noise** when |m| < k σ, k =
:data:`UNDECIDED_SIGMAS` = 2 (a two-sided 95 % interval for a normal error: a verdict
closer to the bound than that could flip on another reference seed). Without a
standard error the sign of m decides, and the sentence says the uncertainty is not
known.

Uncertainty of the one-iteration ratio
--------------------------------------
R = relMSE(x_1, m) / relMSE(x_N, m), with x_k the method's receiver map after k
iterations and m the reference's mean map, whose per-texel variance of the mean v
comes from its K independent seeds (``ReceiverMap.variance``). The method's maps
are deterministic; only m is noisy. A parametric bootstrap draws B reference maps
m*_b = m + sqrt(v) z_b (z standard normal per texel and channel), recomputes both
relMSEs against the same m*_b (so the noise they share stays correlated, as it is
in R: drawing them apart would overstate σ_R several times when x_1 ≈ x_N) and
takes σ_R = the sample standard deviation of R*_b. To first order this is the
delta method, Var R ≈ Σ_i (∂R/∂m_i)² v_i with, for relMSE_k = (1/n) Σ (x_k − m)² /
(m² + ε), ∂relMSE_k/∂m_i = (1/n) [−2 (x_k − m_i) / (m_i² + ε) − 2 m_i (x_k − m_i)² /
(m_i² + ε)²] (tests/harness/studies/test_claims.py holds the two together); where
the method's error is not much larger than the reference noise (near the noise
floor) relMSE is no longer linear in the noise, and the bootstrap keeps the higher
orders the delta method drops. Its draws add v once more to m's own noise, so the
spread is that of R around m rather than around the truth: the usual plug-in
approximation.

Uncertainty of the five-iteration p95
-------------------------------------
The p95 hit-distance error (texels) is a sample quantile over the grid's rays. Its
standard error is the bootstrap one: resample the rays with replacement B times,
take each resample's 95th percentile, σ = their standard deviation. Neighbouring
grid rays are correlated (they sample one smooth surface), so the rays are fewer
independent samples than their count and σ is, if anything, too small; the
reference's noise does not enter (the error is against exact ray casts).
"""

from __future__ import annotations

import math

import numpy as np

from harness.metrics import relative_mse
from harness.raycast import ReceiverTracer
from harness.studies.convergence import classify
from harness.studies.convergence_study import texel_footprint
from renderers.caustics_mapping.caustic_trace import STATUS
from reports.records import ClaimVerdict

__all__ = ["BOOTSTRAP_DRAWS", "FIVE_ITERATIONS", "NEGLIGIBLE_TEXELS", "ONE_ITERATION",
           "ONE_ITERATION_MARGIN", "UNDECIDED_SIGMAS", "check_five_iterations",
           "check_one_iteration", "claim_verdict", "five_iterations_verdict",
           "hit_errors_texels", "one_iteration_verdict", "paper_claims",
           "percentile_standard_error", "ratio_standard_error"]

NEGLIGIBLE_TEXELS = 1.0
ONE_ITERATION_MARGIN = 0.10
#: Margins within this many standard errors of zero are undecided (two-sided 95 %).
UNDECIDED_SIGMAS = 2.0
#: Bootstrap draws of both uncertainties: a standard error from B draws is itself
#: uncertain by about 1 / sqrt(2 (B − 1)), 5 % at B = 200.
BOOTSTRAP_DRAWS = 200
FIVE_ITERATIONS = "error negligible after five iterations (modified estimator)"
ONE_ITERATION = "one iteration is enough for rendering (modified estimator)"


def claim_verdict(value: float, bound: float, standard_error: float | None, *,
                  sigmas: float = UNDECIDED_SIGMAS) -> str:
    """``holds``, ``does not hold`` or ``undecided at this noise`` for the claim
    "value <= bound" (module docstring, "Verdict"); ``not measured`` for a NaN value.
    An infinite value does not hold whatever its uncertainty."""
    if value is None or math.isnan(value):
        return "not measured"
    margin = bound - value
    if math.isinf(value):
        return "does not hold" if value > 0 else "holds"
    if standard_error is not None and math.isfinite(standard_error) and standard_error > 0:
        if abs(margin) < sigmas * standard_error:
            return "undecided at this noise"
    return "holds" if margin >= 0 else "does not hold"


def _uncertainty_text(margin: float, se: float | None, fmt: str, source: str) -> str:
    if se is None or not math.isfinite(se):
        return "uncertainty not known"
    return (f"margin {margin:{fmt}} against {UNDECIDED_SIGMAS:g}σ = "
            f"{UNDECIDED_SIGMAS * se:{fmt}}; ± is one standard error, {source}")


def five_iterations_verdict(p95_error_texels_by_iteration: dict[int, float], *,
                            standard_error: float | None = None) -> ClaimVerdict:
    """The five-iteration claim: p95 hit error after 5 iterations <= 1 texel."""
    quantity = "p95 hit-distance error after 5 iterations (caustic-map texels)"
    source = "bootstrap over the grid's rays"
    if 5 not in p95_error_texels_by_iteration:
        return ClaimVerdict(FIVE_ITERATIONS, "not measured", math.nan, NEGLIGIBLE_TEXELS,
                            None, quantity, source,
                            "not measured: fewer than 5 iterations were run")
    value = float(p95_error_texels_by_iteration[5])
    verdict = claim_verdict(value, NEGLIGIBLE_TEXELS, standard_error)
    se = "" if standard_error is None else f" ± {standard_error:.2g}"
    text = (f"{verdict}: p95 hit-distance error after 5 iterations is {value:.3g}{se} "
            f"texels (negligible means <= {NEGLIGIBLE_TEXELS:g} texel; "
            f"{_uncertainty_text(NEGLIGIBLE_TEXELS - value, standard_error, '.2g', source)})")
    return ClaimVerdict(FIVE_ITERATIONS, verdict, value, NEGLIGIBLE_TEXELS, standard_error,
                        quantity, source, text)


def one_iteration_verdict(relmse_by_iteration: dict[int, float], *,
                          standard_error: float | None = None) -> ClaimVerdict:
    """The one-iteration claim: relMSE(1) / relMSE(last) <= 1.10; ``standard_error``
    is that ratio's (:func:`ratio_standard_error`)."""
    bound = 1 + ONE_ITERATION_MARGIN
    quantity = "receiver relMSE after 1 iteration / after the most iterations"
    source = "parametric bootstrap of the reference's per-texel variance"
    if 1 not in relmse_by_iteration or len(relmse_by_iteration) < 2:
        return ClaimVerdict(ONE_ITERATION, "not measured", math.nan, bound, None, quantity,
                            source, "not measured: need iteration 1 and a later one")
    last = max(relmse_by_iteration)
    one, best = relmse_by_iteration[1], relmse_by_iteration[last]
    if math.isnan(one) or math.isnan(best):
        return ClaimVerdict(ONE_ITERATION, "not measured", math.nan, bound, None, quantity,
                            source, f"not measured: the relMSE after 1 or {last} iterations is "
                            "not a number (no caustic region to score)")
    if not math.isfinite(one):
        ratio = math.inf
    else:
        ratio = one / best if best > 0 else (1.0 if one == best else math.inf)
    verdict = claim_verdict(ratio, bound, standard_error)
    se = "" if standard_error is None else f" ± {standard_error:.2g}"
    text = (f"{verdict}: receiver relMSE after 1 iteration is {one:.4g}, after {last} it is "
            f"{best:.4g} (ratio {ratio:.3f}{se}; claim allows {bound:.2f}; "
            f"{_uncertainty_text(bound - ratio, standard_error, '.3f', source)})")
    return ClaimVerdict(ONE_ITERATION, verdict, ratio, bound, standard_error, quantity,
                        source, text)


def check_five_iterations(p95_error_texels_by_iteration: dict[int, float], *,
                          standard_error: float | None = None) -> tuple[bool, str]:
    """Does the p95 hit error fall to ≤ 1 texel by iteration 5? (holds, sentence)"""
    v = five_iterations_verdict(p95_error_texels_by_iteration, standard_error=standard_error)
    return v.verdict == "holds", v.text


def check_one_iteration(relmse_by_iteration: dict[int, float], *,
                        standard_error: float | None = None) -> tuple[bool, str]:
    """Is the image error after 1 iteration within 10 % of the most-iterated one?
    (holds, sentence)"""
    v = one_iteration_verdict(relmse_by_iteration, standard_error=standard_error)
    return v.verdict == "holds", v.text


def ratio_standard_error(method_one: np.ndarray, method_last: np.ndarray,
                         reference: np.ndarray, variance: np.ndarray, mask: np.ndarray, *,
                         draws: int = BOOTSTRAP_DRAWS, seed: int = 0) -> float:
    """σ of relMSE(method_one, m) / relMSE(method_last, m) under the reference's noise
    (module docstring): parametric bootstrap with ``draws`` reference maps
    m + sqrt(variance) z over the pixels of ``mask``. NaN where a ratio is undefined.

    Parameters
    ----------
    method_one, method_last, reference, variance : ndarray (H, W, 3)
        The method's maps (W/m²), the reference's mean map and its variance of the
        mean per texel ((W/m²)²).
    mask : ndarray (H, W) of bool
        The region both relMSEs are taken over (NaN when it is empty).
    """
    mask = np.asarray(mask, bool)
    if not mask.any():
        return float("nan")
    one = np.asarray(method_one, np.float64)[mask][None]
    last = np.asarray(method_last, np.float64)[mask][None]
    mean = np.asarray(reference, np.float64)[mask][None]
    sd = np.sqrt(np.maximum(np.asarray(variance, np.float64)[mask][None], 0.0))
    rng = np.random.default_rng(seed)
    ratios = np.empty(draws)
    for b in range(draws):
        drawn = mean + sd * rng.standard_normal(mean.shape)
        best = relative_mse(last, drawn)
        ratios[b] = relative_mse(one, drawn) / best if best > 0 else np.nan
    if not np.isfinite(ratios).all():
        return float("nan")
    return float(np.std(ratios, ddof=1))


def percentile_standard_error(values: np.ndarray, *, percentile: float = 95.0,
                              draws: int = BOOTSTRAP_DRAWS, seed: int = 0) -> float:
    """Bootstrap standard error of the ``percentile`` of ``values`` (resampled with
    replacement ``draws`` times); NaN for fewer than two values."""
    values = np.asarray(values, np.float64)
    values = values[np.isfinite(values)]
    if values.size < 2:
        return float("nan")
    rng = np.random.default_rng(seed)
    picks = (np.percentile(values[rng.integers(0, values.size, values.size)], percentile)
             for _ in range(draws))
    return float(np.std(np.fromiter(picks, float, draws), ddof=1))


def hit_errors_texels(runner, iterations: int) -> np.ndarray:
    """Per-ray hit-distance errors (texels) of the modified estimator after
    ``iterations``: the rays and the definition the convergence table's p95 uses
    (:func:`harness.studies.convergence.iteration_stats`)."""
    hits = runner.render(estimator="modified", safeguarded=False, iterations=iterations).hits
    status = hits["status"].astype(int)
    traced = np.isin(status, [STATUS["hit"], STATUS["lost"], STATUS["diverged"],
                              STATUS["unconverged"]])
    exact = ReceiverTracer(runner.geometry)(hits["origin"][traced], hits["direction"][traced])
    history = hits["history"][traced].astype(np.float64)
    history[status[traced] == STATUS["diverged"], -1] = np.nan
    lost = status[traced] == STATUS["lost"]
    points = np.where(np.isfinite(exact.position), exact.position, hits["origin"][traced])
    texel = texel_footprint(runner, {"light": hits["light"][traced]}, points)
    outcome = classify(history, lost, exact.distance, texel)
    with np.errstate(invalid="ignore"):
        error = np.abs(history[:, -1] - exact.distance)
    ok = (outcome != "") & (outcome != "lost") & np.isfinite(error)
    return (error / texel)[ok]


def paper_claims(convergence, *, runner=None, reference=None, caustic=None
                 ) -> tuple[dict[str, str], tuple[ClaimVerdict, ...]]:
    """Both claims from the convergence table (rows of the plain modified estimator),
    with their uncertainties when ``runner`` (the study's
    :class:`~harness.studies.runner.RealtimeRunner`), ``reference`` (receiver 0's
    :class:`~renderers.results.ReceiverMap`, with its variance) and ``caustic`` (the
    region the table's relMSE is taken over) are given: the maps and rays are
    rendered again (the renders are deterministic) for the bootstraps.

    Returns the claim sentences by claim (``SceneComparison.claims``) and the
    verdicts.
    """
    rows = [r for r in convergence.records()
            if r["estimator"] == "modified" and not r["safeguarded"]]
    p95 = {r["iteration"]: r["p95_error_texels"] for r in rows}
    relmse = {r["iteration"]: r["relmse"] for r in rows}
    five_se = ratio_se = None
    if runner is not None:
        if 5 in p95:
            five_se = percentile_standard_error(hit_errors_texels(runner, 5))
        variance = getattr(reference, "variance", None)
        if 1 in relmse and len(relmse) > 1 and variance is not None and caustic is not None:
            maps = [runner.render(estimator="modified", safeguarded=False,
                                  iterations=k).result.receivers[0].irradiance
                    for k in (1, max(relmse))]
            ratio_se = ratio_standard_error(maps[0], maps[1], reference.irradiance, variance,
                                            caustic)
    verdicts = (five_iterations_verdict(p95, standard_error=five_se),
                one_iteration_verdict(relmse, standard_error=ratio_se))
    return {v.claim: v.text for v in verdicts}, verdicts
