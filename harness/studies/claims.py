"""The paper's two convergence claims, checked against measured numbers and a 95 %
interval for each.

Shah et al. 2007, Section 3.4: "For a fairly uniform topology, the error is
negligible after only five iterations. For the purpose of rendering caustics, we
observed that only a single iteration is sufficient."

We make both testable, each as "value <= bound":

* **five iterations**: after 5 iterations of the modified estimator, the 95th
  percentile of the hit-distance error is at most one caustic-map texel
  (``NEGLIGIBLE_TEXELS``): below what the caustic map can resolve.
* **one iteration**: the image error after one iteration is within
  ``ONE_ITERATION_MARGIN`` (10 %) of the error after the most iterations measured,
  N: more iterations no longer change what one sees. The error is the receiver
  map's *excess* relMSE over the scene's caustic region
  (:func:`harness.metrics.excess.excess_relative_mse`: its relMSE against the
  noise-free image, the reference's noise removed), so the ratio is e₁ / e_N.

Verdict
-------
From the value's 95 % interval [lo, hi]: the claim **holds** when hi <= bound,
**does not hold** when lo > bound, and is **undecided at this noise** when the
interval straddles the bound (another reference seed or another grid could flip
it). Without an interval the sign of bound − value decides and the sentence says
the uncertainty is not known; a NaN value is **not measured**.

Why excess errors in the one-iteration ratio
--------------------------------------------
The raw relMSE against a K-seed reference R = T + η is, per texel, about
w (b² + v) with b = M − T the method's bias and v the variance of R's mean: the
reference's noise n = mean w v is added to both iterations' errors, and
(b₁² + n) / (b_N² + n) → 1 as n grows. A noisy enough reference makes any
method's first iteration "as good as" its last. The excess e = mean w_T b²
removes n (unbiased, with a model standard error under the reference's noise), so
e₁ / e_N is the ratio of what the method is accountable for.

Interval of the one-iteration ratio (Fieller)
---------------------------------------------
e₁ and e_N are estimated from the *same* reference, so their errors are
correlated. Linearised in the reference noise η (variance v, Gaussian) a texel's
term is e_i + α η + β (η² − v) − β (v̂ − v) with α = h'(R), β = ½ h''(R),
h(x) = w(x) (M − x)², w(x) = 1 / (x² + ε) (the taylor estimator of
:mod:`harness.metrics.excess`), so per texel and channel pair (c, c')

    Cov(t₁, t_N) = ρ α₁ α_N σ σ' + ρ² · 2 β₁ β_N v v' K / (K − 1),

with that module's second-order corrections of the plug-in coefficients
(:func:`harness.metrics.excess.relmse_covariance`, which for one method is that
module's variance of independent texels); the correlation r of (e₁, e_N) is the cross
term over the square root of the two. With V₁, V_N the excesses' squared standard errors and
C = r √(V₁ V_N), Fieller's interval is the set of ratios ρ* for which
e₁ − ρ* e_N is within t √(V₁ − 2 ρ* C + ρ*² V_N) of 0 (t: Student's quantile at
the smaller of the two Satterthwaite degrees of freedom): the roots of

    (e_N² − t² V_N) ρ*² − 2 (e₁ e_N − t² C) ρ* + (e₁² − t² V₁) = 0.

Why Fieller and not the delta method's e₁/e_N ± t σ_δ or a bootstrap over texel
blocks: (1) the ratio of two noisy numbers is skewed when e_N's relative error is
not small, which a symmetric interval ignores; Fieller's is exact for a bivariate
normal (e₁, e_N) and tends to the delta method's as e_N / σ_N grows; (2) when e_N
is not distinguishable from 0 the ratio's interval is rightly unbounded (the
claim is then undecided), which no finite ± can say; (3) a bootstrap over texel
blocks resamples the *bias pattern* across the region, which is fixed, not noise:
it measures how the ratio would vary over other regions, not over other
references, and its width would not shrink as the reference's noise does. The
ratio's true value is non-negative (both excesses are), so the set is intersected
with [0, ∞) and reported as its hull. ``standard_error`` is the delta method's
σ_δ = √(V₁ − 2 q C + q² V_N) / e_N at q = e₁ / e_N, for display.
Texels are independent given the photon tracer's nearest-texel deposit, as in
:mod:`harness.metrics.excess`; the coverage is checked by simulation in
``tests/harness/studies/test_claims.py``.

The scored region is the scene's caustic region
(:func:`harness.compare.regions.scene_caustic_region`: thresholded on a reference
*independent* of the one scored), the texels every method and study of the scene is
scored on, so the claim quotes the convergence table's excess relMSEs exactly. A region
thresholded on the reference being scored keeps the texels its noise pushed up and
biases the excess (``harness.metrics.excess``); one taken from the method's own maps
would let the method move its own denominator.

Interval of the five-iteration p95 (block bootstrap)
----------------------------------------------------
The p95 hit-distance error (texels) is a sample quantile over the grid's rays.
Neighbouring grid vertices sample one smooth surface, so their errors are
correlated and the rays are fewer independent samples than their count: a
bootstrap that resamples single rays treats them as independent and its interval
is too narrow. We resample **tiles of the vertex grid** instead (a moving-block
bootstrap's non-overlapping variant): each traced sheet (light sample, channel
pass, object view) is cut into square tiles of ``ceil(grid / BLOCKS_PER_SIDE)``
vertices a side, the tiles holding scored rays are drawn with replacement as many
times as there are, and each resample's 95th percentile is taken; the interval is
the 2.5th and 97.5th percentiles of ``BOOTSTRAP_DRAWS`` resampled p95s (the
percentile bootstrap), σ their standard deviation. The tile is a fixed fraction of
the grid because the correlation comes from the surface's shape, which is fixed in
object space: at twice the grid a feature spans twice the vertices. The
reference's noise does not enter (the error is against exact ray casts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import stdtrit

from harness.metrics.excess import ExcessError, excess_relative_mse, relmse_covariance
from harness.metrics.scores import RELMSE_EPSILON, MetricInputError
from harness.raycast import ReceiverTracer
from harness.studies.convergence import classify
from harness.studies.convergence_study import texel_footprint
from renderers.caustics_mapping.caustic_trace import STATUS
from reports.records import ClaimVerdict

__all__ = ["BLOCKS_PER_SIDE", "BOOTSTRAP_DRAWS", "CONFIDENCE", "FIVE_ITERATIONS",
           "NEGLIGIBLE_TEXELS", "ONE_ITERATION", "ONE_ITERATION_MARGIN", "ExcessRatio",
           "PercentileInterval", "block_percentile_interval", "check_five_iterations",
           "check_one_iteration", "claim_verdict", "excess_ratio",
           "five_iterations_verdict", "hit_error_grid", "hit_errors_texels",
           "normal_interval", "one_iteration_verdict", "paper_claims"]

NEGLIGIBLE_TEXELS = 1.0
ONE_ITERATION_MARGIN = 0.10
#: Two-sided confidence of every interval a verdict is read from.
CONFIDENCE = 0.95
#: Resampled p95s of the block bootstrap: its 2.5th and 97.5th percentiles then rest
#: on 10 draws beyond each end.
BOOTSTRAP_DRAWS = 400
#: Tiles per side of the vertex grid in the p95's block bootstrap (module docstring).
BLOCKS_PER_SIDE = 8
FIVE_ITERATIONS = "error negligible after five iterations (modified estimator)"
ONE_ITERATION = "one iteration is enough for rendering (modified estimator)"

_Z = 1.959963984540054  # the normal's 97.5th percentile


# ---- verdicts ------------------------------------------------------------------------


def normal_interval(value: float, standard_error: float | None) -> tuple[float, float] | None:
    """value ± z₀.₉₇₅ σ, the 95 % interval of a normal error; None without a finite σ."""
    if standard_error is None or not math.isfinite(standard_error):
        return None
    return (value - _Z * standard_error, value + _Z * standard_error)


def _known(ci95) -> bool:
    return ci95 is not None and not any(math.isnan(x) for x in ci95)


def claim_verdict(value: float, bound: float, ci95: tuple[float, float] | None) -> str:
    """``holds``, ``does not hold`` or ``undecided at this noise`` for the claim
    "value <= bound" from the value's 95 % interval (module docstring, "Verdict");
    ``not measured`` for a NaN value. An infinite value does not hold whatever its
    interval; without an interval the sign of bound − value decides."""
    if value is None or math.isnan(value):
        return "not measured"
    if math.isinf(value):
        return "does not hold" if value > 0 else "holds"
    if _known(ci95):
        low, high = ci95
        if high <= bound:
            return "holds"
        if low > bound:
            return "does not hold"
        return "undecided at this noise"
    return "holds" if value <= bound else "does not hold"


def _interval_parts(se: float | None, ci95, fmt: str, source: str, *,
                    se_fmt: str | None = None) -> tuple[str, str, str]:
    """(" ± σ", ", 95 % interval [lo, hi]", what they are and where they come from)."""
    se_fmt = se_fmt or fmt
    spread = "" if se is None or not math.isfinite(se) else f" ± {se:{se_fmt}}"
    if not _known(ci95):
        return spread, "", "uncertainty not known"
    low, high = ci95
    note = ("± is one standard error; " if spread else "") + f"the interval is {source}"
    return spread, f", 95 % interval [{low:{fmt}}, {high:{fmt}}]", note


def five_iterations_verdict(p95_error_texels_by_iteration: dict[int, float], *,
                            standard_error: float | None = None,
                            ci95: tuple[float, float] | None = None) -> ClaimVerdict:
    """The five-iteration claim: p95 hit error after 5 iterations <= 1 texel.
    ``ci95`` defaults to the normal interval of ``standard_error``."""
    quantity = "p95 hit-distance error after 5 iterations (caustic-map texels)"
    source = (f"a bootstrap over tiles of the vertex grid, {BLOCKS_PER_SIDE} a side"
              if ci95 is not None else "normal, from the standard error")
    if 5 not in p95_error_texels_by_iteration:
        return ClaimVerdict(FIVE_ITERATIONS, "not measured", math.nan, NEGLIGIBLE_TEXELS,
                            None, quantity, source,
                            "not measured: fewer than 5 iterations were run")
    value = float(p95_error_texels_by_iteration[5])
    if ci95 is None:
        ci95 = normal_interval(value, standard_error)
    verdict = claim_verdict(value, NEGLIGIBLE_TEXELS, ci95)
    spread, interval, note = _interval_parts(standard_error, ci95, ".3g", source,
                                             se_fmt=".2g")
    text = (f"{verdict}: p95 hit-distance error after 5 iterations is {value:.3g}{spread} "
            f"texels{interval} (negligible means <= {NEGLIGIBLE_TEXELS:g} texel; {note})")
    return ClaimVerdict(FIVE_ITERATIONS, verdict, value, NEGLIGIBLE_TEXELS, standard_error,
                        quantity, source, text, ci95=_plain(ci95))


def _plain(ci95) -> tuple[float, float] | None:
    return None if ci95 is None else (float(ci95[0]), float(ci95[1]))


def one_iteration_verdict(error_by_iteration: dict[int, float], *,
                          standard_error: float | None = None,
                          ci95: tuple[float, float] | None = None,
                          excess: bool = False) -> ClaimVerdict:
    """The one-iteration claim: error(1) / error(last) <= 1.10.

    Parameters
    ----------
    error_by_iteration : dict of int to float
        Receiver relMSE by iteration count: excess (``excess=True``, the reference's
        noise removed) or raw (against the noisy reference, whose noise pulls the
        ratio towards 1; module docstring).
    standard_error, ci95
        The ratio's standard error and 95 % interval (:func:`excess_ratio`);
        ``ci95`` defaults to the normal interval of ``standard_error``.
    """
    bound = 1 + ONE_ITERATION_MARGIN
    name = "excess receiver relMSE" if excess else "receiver relMSE"
    quantity = f"{name} after 1 iteration / after the most iterations"
    source = ("Fieller's, from the two excesses' standard errors and their correlation "
              "under the reference's noise" if excess and ci95 is not None
              else "normal, from the standard error")
    if 1 not in error_by_iteration or len(error_by_iteration) < 2:
        return ClaimVerdict(ONE_ITERATION, "not measured", math.nan, bound, None, quantity,
                            source, "not measured: need iteration 1 and a later one")
    last = max(error_by_iteration)
    one, best = error_by_iteration[1], error_by_iteration[last]
    if math.isnan(one) or math.isnan(best):
        return ClaimVerdict(ONE_ITERATION, "not measured", math.nan, bound, None, quantity,
                            source, f"not measured: the relMSE after 1 or {last} iterations is "
                            "not a number (no caustic region to score)")
    if not math.isfinite(one):
        ratio = math.inf
    else:
        ratio = one / best if best > 0 else (1.0 if one == best else math.inf)
    if ci95 is None:
        ci95 = normal_interval(ratio, standard_error)
    verdict = claim_verdict(ratio, bound, ci95)
    noise = ("the reference's noise removed" if excess else
             "raw, against the noisy reference: its noise pulls the ratio towards 1")
    spread, interval, note = _interval_parts(standard_error, ci95, ".3f", source)
    text = (f"{verdict}: {name} after 1 iteration is {one:.4g}, after {last} it is "
            f"{best:.4g} ({noise}); ratio {ratio:.3f}{spread}{interval}, claim allows "
            f"{bound:.2f} ({note})")
    return ClaimVerdict(ONE_ITERATION, verdict, ratio, bound, standard_error, quantity,
                        source, text, ci95=_plain(ci95))


def check_five_iterations(p95_error_texels_by_iteration: dict[int, float], *,
                          standard_error: float | None = None,
                          ci95: tuple[float, float] | None = None) -> tuple[bool, str]:
    """Does the p95 hit error fall to ≤ 1 texel by iteration 5? (holds, sentence)"""
    v = five_iterations_verdict(p95_error_texels_by_iteration, standard_error=standard_error,
                                ci95=ci95)
    return v.verdict == "holds", v.text


def check_one_iteration(error_by_iteration: dict[int, float], *,
                        standard_error: float | None = None,
                        ci95: tuple[float, float] | None = None,
                        excess: bool = False) -> tuple[bool, str]:
    """Is the image error after 1 iteration within 10 % of the most-iterated one?
    (holds, sentence)"""
    v = one_iteration_verdict(error_by_iteration, standard_error=standard_error, ci95=ci95,
                              excess=excess)
    return v.verdict == "holds", v.text


# ---- the one-iteration ratio of excess errors ----------------------------------------


@dataclass(frozen=True)
class ExcessRatio:
    """e₁ / e_N of two excess relMSEs against one reference, with its uncertainty.

    Attributes
    ----------
    ratio : float
        e₁ / e_N (inf when e_N <= 0 < e₁, NaN when both are <= 0).
    standard_error : float
        The delta method's σ of the ratio (module docstring).
    ci95 : tuple of float
        Fieller's 95 % interval intersected with [0, ∞) (its hull; ``high`` is inf
        when e_N is not distinguishable from 0).
    one, last : ExcessError
        The two excesses (:func:`harness.metrics.excess.excess_relative_mse`).
    correlation : float
        Correlation of their errors under the reference's noise.
    """

    ratio: float
    standard_error: float
    ci95: tuple[float, float]
    one: ExcessError
    last: ExcessError
    correlation: float


def _fieller(num: float, den: float, *, v_num: float, v_den: float, cov: float,
             t: float) -> tuple[float, float]:
    """Hull of Fieller's interval for num / den intersected with [0, ∞) (module
    docstring): {q >= 0 : (num − q den)² <= t² (v_num − 2 q cov + q² v_den)}."""
    t2 = t * t
    a = den * den - t2 * v_den
    b = num * den - t2 * cov
    c = num * num - t2 * v_num
    disc = b * b - a * c
    if a > 0:  # den distinguishable from 0: a bounded interval
        root = math.sqrt(max(disc, 0.0))
        low, high = (b - root) / a, (b + root) / a
        return max(low, 0.0), max(high, 0.0)
    if disc <= 0 or a == 0:  # every ratio is consistent with the data
        return 0.0, math.inf
    # a < 0: the set is (−∞, q₁] ∪ [q₂, ∞), q₁ < q₂; within [0, ∞) its hull is
    # [q₂, ∞) when q₁ < 0, else [0, ∞).
    root = math.sqrt(disc)
    q1, q2 = (b + root) / a, (b - root) / a
    return (max(q2, 0.0), math.inf) if q1 < 0 else (0.0, math.inf)


def excess_ratio(method_one: np.ndarray, method_last: np.ndarray, reference: np.ndarray,
                 variance: np.ndarray, *, seeds: int, mask: np.ndarray,
                 channel_correlation: float = 1.0,
                 epsilon: float = RELMSE_EPSILON,
                 seed_estimates: np.ndarray | None = None) -> ExcessRatio:
    """e₁ / e_N of two method images' excess relMSEs against one reference, with
    Fieller's 95 % interval (module docstring).

    Parameters
    ----------
    method_one, method_last, reference : ndarray (H, W, 3)
        The method's maps after 1 and N iterations and the reference's K-seed mean
        (W/m²).
    variance : ndarray (H, W, 3)
        The reference's variance of the mean per texel and channel ((W/m²)²).
    seeds : int
        K, the seeds behind ``variance`` (at least 2).
    mask : ndarray (H, W) of bool
        The scored region; it must not be derived from ``reference``.
    channel_correlation : float
        Correlation of one texel's channel noises: 1 when the same photons carry all
        three channels, 0 for one pass per channel (dispersion).
    epsilon : float
        relMSE's regulariser ((W/m²)²).
    seed_estimates : ndarray (K, H, W, 3), optional
        The reference's per-seed maps: each excess uses them as the comparison's
        records do (``harness.metrics.excess``); their correlation stays the model's.

    Raises
    ------
    MetricInputError
        An empty region, fewer than 2 seeds, or mismatched shapes.
    """
    mask = np.asarray(mask, bool)
    if not mask.any():
        raise MetricInputError("the scored region is empty")
    one, last = (excess_relative_mse(m, reference, variance, seeds=seeds, mask=mask,
                                     channel_correlation=channel_correlation,
                                     epsilon=epsilon, seed_estimates=seed_estimates)
                 for m in (method_one, method_last))
    def covariance(x, y):
        return relmse_covariance(x, y, reference, variance, seeds=seeds, mask=mask,
                                 channel_correlation=channel_correlation, epsilon=epsilon)

    cross = covariance(method_one, method_last)     # symmetric: one evaluation
    cov = np.array([[covariance(method_one, method_one), cross],
                    [cross, covariance(method_last, method_last)]])
    scale = math.sqrt(cov[0, 0] * cov[1, 1]) if cov[0, 0] > 0 and cov[1, 1] > 0 else 0.0
    correlation = float(np.clip(cov[0, 1] / scale, -1.0, 1.0)) if scale > 0 else 0.0
    e1, en = one.excess, last.excess
    v1, vn = one.excess_stderr**2, last.excess_stderr**2
    c = correlation * one.excess_stderr * last.excess_stderr
    df = min(one.degrees_of_freedom, last.degrees_of_freedom)
    t = float(stdtrit(df, 0.5 + CONFIDENCE / 2)) if math.isfinite(df) else _Z
    if en > 0:
        ratio = e1 / en
        # σ_δ in the form that stays finite at e₁ = 0: Var(e₁ − q e_N) / e_N².
        se = math.sqrt(max(v1 - 2 * ratio * c + ratio * ratio * vn, 0.0)) / en
    else:
        ratio = math.inf if e1 > 0 else math.nan
        se = math.inf
    interval = _fieller(e1, en, v_num=v1, v_den=vn, cov=c, t=t)
    return ExcessRatio(ratio, float(se), interval, one, last, correlation)


# ---- the five-iteration p95 ----------------------------------------------------------


@dataclass(frozen=True)
class PercentileInterval:
    """A percentile of values on a vertex grid, with its block-bootstrap uncertainty.

    Attributes
    ----------
    value : float
        The percentile of every finite value (``np.percentile``, linear).
    standard_error : float
        Standard deviation of the resampled percentiles.
    ci95 : tuple of float
        Their 2.5th and 97.5th percentiles (the percentile bootstrap).
    block : int
        Tile side (vertices); 1 resamples single rays.
    blocks : int
        Tiles holding at least one finite value (the units resampled).
    """

    value: float
    standard_error: float
    ci95: tuple[float, float]
    block: int
    blocks: int


def block_percentile_interval(values: np.ndarray, *, percentile: float = 95.0,
                              block: int | None = None, draws: int = BOOTSTRAP_DRAWS,
                              seed: int = 0) -> PercentileInterval:
    """Block bootstrap of a percentile of values on a vertex grid (module docstring).

    Parameters
    ----------
    values : ndarray (..., G, G)
        One value per grid vertex (e.g. the hit-distance error in texels), NaN where
        nothing is scored; leading axes are separate sheets (light samples, channel
        passes, object views), tiled separately.
    block : int, optional
        Tile side in vertices; default ``ceil(G / BLOCKS_PER_SIDE)``. 1 resamples
        single rays (the bootstrap that ignores their correlation).
    draws, seed
        Bootstrap resamples and the generator's seed.

    Returns
    -------
    PercentileInterval
        NaN standard error and interval for fewer than two tiles.
    """
    values = np.asarray(values, np.float64)
    if values.ndim < 2:
        raise MetricInputError(f"expected values on a grid (..., G, G), got {values.shape}")
    rows, cols = values.shape[-2:]
    side = block if block is not None else math.ceil(max(rows, cols) / BLOCKS_PER_SIDE)
    if side < 1:
        raise MetricInputError(f"block side must be at least 1, got {side}")
    sheets = values.reshape(-1, rows, cols)
    sheet, row, col = np.indices(sheets.shape)
    keep = np.isfinite(sheets)
    flat = sheets[keep]
    if flat.size == 0:
        return PercentileInterval(math.nan, math.nan, (math.nan, math.nan), side, 0)
    tiles_r, tiles_c = -(-rows // side), -(-cols // side)
    tile = (sheet[keep] * tiles_r + row[keep] // side) * tiles_c + col[keep] // side
    _, group = np.unique(tile, return_inverse=True)
    count = int(group.max()) + 1
    point = float(np.percentile(flat, percentile))
    if count < 2:
        return PercentileInterval(point, math.nan, (math.nan, math.nan), side, count)
    order = np.argsort(flat, kind="stable")
    ordered, ordered_group = flat[order], group[order]
    rng = np.random.default_rng(seed)
    picks = np.empty(draws)
    for i in range(draws):
        # A resample's values are each drawn tile's values, as often as it is drawn:
        # its percentile is the weighted inverse CDF of the sorted values.
        weight = np.bincount(rng.integers(0, count, count), minlength=count)[ordered_group]
        cumulative = np.cumsum(weight)
        at = np.searchsorted(cumulative, percentile / 100.0 * cumulative[-1], side="left")
        picks[i] = ordered[min(at, ordered.size - 1)]
    tail = 50.0 * (1.0 - CONFIDENCE)
    low, high = np.percentile(picks, [tail, 100.0 - tail])
    return PercentileInterval(point, float(np.std(picks, ddof=1)), (float(low), float(high)),
                              side, count)


def _hit_errors(runner, iterations: int) -> tuple[np.ndarray, np.ndarray, int, int]:
    """(errors in texels, their indices into the frame's hits, the hits' count, the
    grid side)."""
    frame = runner.render(estimator="modified", safeguarded=False, iterations=iterations)
    hits = frame.hits
    status = hits["status"].astype(int)
    traced = np.flatnonzero(np.isin(status, [STATUS["hit"], STATUS["lost"],
                                             STATUS["diverged"], STATUS["unconverged"]]))
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
    return (error / texel)[ok], traced[ok], status.size, int(runner.settings.grid)


def hit_errors_texels(runner, iterations: int) -> np.ndarray:
    """Per-ray hit-distance errors (texels) of the modified estimator after
    ``iterations``: the rays and the definition the convergence table's p95 uses
    (:func:`harness.studies.convergence.iteration_stats`)."""
    return _hit_errors(runner, iterations)[0]


def hit_error_grid(runner, iterations: int) -> np.ndarray:
    """:func:`hit_errors_texels` on the vertex grid: (S, G, G) texels, NaN where a
    vertex is not scored, one sheet per traced (light sample, channel pass, object
    view). A trace lays its records out as view × row × column of the G × G grid
    (``caustic_trace.glsl``), and the frame concatenates whole traces."""
    errors, index, total, grid = _hit_errors(runner, iterations)
    if total % (grid * grid):
        raise MetricInputError(f"{total} hit records are not whole {grid} x {grid} grids")
    out = np.full(total, np.nan)
    out[index] = errors
    return out.reshape(-1, grid, grid)


# ---- both claims from the convergence study ------------------------------------------


def paper_claims(convergence, *, runner=None, reference=None, caustic=None,
                 seeds: int | None = None
                 ) -> tuple[dict[str, str], tuple[ClaimVerdict, ...]]:
    """Both claims from the convergence study (rows of the plain modified estimator).

    Parameters
    ----------
    convergence : Table
        The convergence table (its p95 hit errors and raw relMSEs by iteration).
    runner : RealtimeRunner, optional
        The study's runner (:class:`~harness.studies.runner.RealtimeRunner`): the maps
        and rays are rendered again (the renders are deterministic) for the
        intervals; its scene's ``settings.seeds`` is the reference's K.
    reference : ReceiverMap, optional
        Receiver 0's reference, with ``variance`` (of the mean, per texel and channel):
        needed for the excess relMSEs.
    caustic : ndarray (H, W) of bool, optional
        The scene's caustic region (:func:`harness.compare.regions.scene_caustic_region`),
        the one the convergence table is scored over; the excess ratio is taken over
        it too. Without it, ``runner`` or the variance, the one-iteration claim falls
        back to the table's relMSEs, with no interval.
    seeds : int, optional
        K, the seeds behind ``reference.variance`` (default the runner's scene's
        ``settings.seeds``).

    Returns
    -------
    claims, verdicts
        The claim sentences by claim (``SceneComparison.claims``) and the verdicts.
    """
    rows = [r for r in convergence.records()
            if r["estimator"] == "modified" and not r["safeguarded"]]
    p95 = {r["iteration"]: r["p95_error_texels"] for r in rows}
    relmse = {r["iteration"]: r["relmse"] for r in rows}
    five = five_iterations_verdict(p95)
    one = one_iteration_verdict(relmse)
    if runner is not None:
        if 5 in p95:
            interval = block_percentile_interval(hit_error_grid(runner, 5))
            five = five_iterations_verdict(p95, standard_error=interval.standard_error,
                                           ci95=interval.ci95)
        k = int(seeds if seeds is not None else runner.scene.settings.seeds)
        ratio = _excess_ratio_of(runner, reference, relmse, seeds=k, region=caustic)
        if ratio is not None:
            last = max(relmse)
            one = one_iteration_verdict({1: ratio.one.excess, last: ratio.last.excess},
                                        standard_error=ratio.standard_error,
                                        ci95=ratio.ci95, excess=True)
    verdicts = (five, one)
    return {v.claim: v.text for v in verdicts}, verdicts


def _excess_ratio_of(runner, reference, relmse: dict[int, float], *, seeds: int,
                     region=None) -> ExcessRatio | None:
    """:func:`excess_ratio` of the maps after 1 and the most iterations over the scene's
    ``region``, or None when it cannot be measured (no variance, fewer than 2 seeds,
    no caustic region, NaN table relMSEs)."""
    variance = getattr(reference, "variance", None)
    if (1 not in relmse or len(relmse) < 2 or variance is None or seeds < 2
            or any(math.isnan(relmse[k]) for k in (1, max(relmse)))):
        return None
    frames = [runner.render(estimator="modified", safeguarded=False, iterations=k)
              for k in (1, max(relmse))]
    maps = [f.result.receivers[0].irradiance for f in frames]
    if region is None or not np.asarray(region, bool).any():
        return None
    # A dispersion scene's reference traces one photon pass per channel.
    rho = 0.0 if "dispersion" in frames[0].result.effects else 1.0
    return excess_ratio(maps[0], maps[1], reference.irradiance, variance, seeds=seeds,
                        mask=region, channel_correlation=rho,
                        seed_estimates=getattr(reference, "seed_maps", None))
