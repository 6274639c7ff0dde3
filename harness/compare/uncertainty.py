"""The method's own error per metric, with its uncertainty (``docs/statistics.md``).

The raw metric of the method against the reference mixes the method's error with the
reference's noise. For each metric that has an estimator this module gives what a
perfect method would score against this reference (``baseline``), the method's
*excess* over it, its standard error and 95 % interval, and whether the interval
excludes 0 (``distinguishable``: the method is measurably off the noise-free image).

==============  ==========================================  =============================
metric          excess                                      estimator and interval
==============  ==========================================  =============================
relmse          relMSE against the noise-free image         :func:`harness.metrics.excess.
                                                            excess_relative_mse` (Taylor-
                                                            corrected, third-moment term
                                                            and neighbour covariance from
                                                            the per-seed images, model-
                                                            based SE, Satterthwaite t)
ssim            baseline − value (a deficit > 0)            :func:`harness.metrics.
                                                            baselines.perceptual_baseline`
                                                            (the seeds' own noise, or
                                                            photon-like noise at the
                                                            reference's variance), over
                                                            well-sampled texels; 8 × 8
                                                            block bootstrap and the
                                                            baseline's Monte Carlo error
flip            value − baseline                            as SSIM
flux_ratio      ratio − 1                                   delta method: Var Σ lum(R)
                                                            from the K seeds' region
                                                            totals (t, K − 1 dof), or
                                                            the per-texel variance
relmse_trimmed  none (trimming is not linear in the noise)  –
psnr            none (a transform of the raw MSE)           –
==============  ==========================================  =============================

The texel is the unit: a texel's channels are one sample (their noises perfectly
correlated when the same photons carry all three channels, independent when each
channel is traced on its own, as for dispersion: ``channel_correlation``). Texels'
noise is independent only up to what the per-seed images measure (a stratified launch
anticorrelates neighbours); a view whose pixels share noise by construction (the
camera image, read bilinearly from lookup maps) gets no interval without per-seed
images (``ExcessInputs.independent_texels``).

A perceptual baseline depends on the reference alone, so it is computed once per
reference image and view and shared by every method compared with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from harness.metrics import MetricInputError
from harness.metrics.baselines import (
    BLOCK,
    RESAMPLES,
    WELL_SAMPLED,
    block_bootstrap,
    flip_map,
    perceptual_baseline,
    photons_per_texel,
    ssim_map,
)
from harness.metrics.excess import excess_relative_mse, t_interval
from scenes.colour import LUMA

__all__ = ["BASELINE_TRIALS", "ExcessInputs", "flux_ratio_interval", "metric_excess",
           "seed_luminance_totals"]

#: Simulated noisy references per perceptual baseline: SSIM is cheap (0.25 s at 512²
#: here), FLIP is not (3.7 s at 512², 1.3 s at 256² on this 2-core machine).
BASELINE_TRIALS = {"ssim": 8, "flip": 4}


@dataclass(frozen=True, eq=False)
class ExcessInputs:
    """What the excess estimators need beside the two images.

    Attributes
    ----------
    variance : ndarray (H, W, 3)
        Variance of the reference's mean per texel and channel (squared image units).
    seeds : int
        K, the seeds the variance was estimated from.
    channel_correlation : float
        1 when the same photons carry all three channels, 0 for one pass per channel.
    white, flip_start, flip_stop : float
        The view's fixed exposure (SSIM's tone curve; FLIP's stops).
    seed_estimates : ndarray (K, H, W, 3), optional
        The reference's K per-seed images of the view (their mean is the reference).
        With them the relMSE's third-moment bias is removed and its standard error
        includes neighbouring texels' covariance; the flux ratio's standard error
        comes from the K seeds' region totals; the perceptual baselines draw
        photon-like noise. Without them texels are taken as independent and the noise
        as symmetric.
    independent_texels : bool
        Whether the view's noise is independent from texel to texel apart from what
        ``seed_estimates`` measures (a receiver map: each photon lands in one texel).
        False for the camera image, whose pixels read the lookup maps bilinearly at a
        footprint of several pixels, so neighbouring pixels share lookup texels and
        their noise: such a view gets no interval unless ``seed_estimates`` are given.
    """

    variance: np.ndarray
    seeds: int
    channel_correlation: float
    white: float
    flip_start: float
    flip_stop: float
    seed_estimates: np.ndarray | None = None
    independent_texels: bool = True


def _interval(excess: float, stderr: float, dof: float = math.inf) -> dict:
    low, high = t_interval(excess, stderr, dof)
    return {"excess": excess, "excess_stderr": stderr, "excess_ci95": (low, high),
            "distinguishable": bool(stderr > 0 and (low > 0 or high < 0))}


@lru_cache(maxsize=16)
def _baseline_maps(metric: str, *, reference: bytes, variance: bytes, shape: tuple,
                   exposure: tuple[float, float, float], rho: float,
                   seeds: bytes | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A perfect method's metric maps against the reference, one per trial (T, H, W)
    (photon-like noise, :func:`~harness.metrics.baselines.perceptual_baseline`), and
    the texels well sampled enough to be scored (H, W), memoised by the reference's
    bytes: every method of a scene shares them. With the per-seed images (``seeds``,
    an even number K of them) the simulated noise is the seeds' own (``noise="seeds"``:
    stratified launches' anticorrelated neighbours included, which SSIM's window and
    FLIP's filters see less of than independent noise); otherwise photon-like."""
    ref = np.frombuffer(reference, np.float32).reshape(shape)
    var = np.frombuffer(variance, np.float32).reshape(shape)
    white, start, stop = exposure
    function = (ssim_map(white=white) if metric == "ssim"
                else flip_map(start_exposure=start, stop_exposure=stop))
    per_seed = None if seeds is None else np.frombuffer(seeds, np.float32).reshape(-1, *shape)
    # The seeds' own noise where they are given and come in pairs; photon-like noise
    # fitted per texel otherwise.
    noise = "seeds" if per_seed is not None and per_seed.shape[0] % 2 == 0 else "photon"
    maps = perceptual_baseline(ref, var, metric=function, trials=BASELINE_TRIALS[metric],
                               channel_correlation=rho, keep_trials=True, noise=noise,
                               seed_estimates=per_seed).trial_maps
    photons = photons_per_texel(ref, var).min(axis=-1)
    return maps.astype(np.float32), photons >= WELL_SAMPLED


def _perceptual(metric: str, value_map: np.ndarray, reference: np.ndarray, mask: np.ndarray,
                *, inputs: ExcessInputs) -> dict:
    """SSIM's or FLIP's excess over the region's well-sampled texels: the block
    bootstrap's SE of the excess map's mean and the baseline's own Monte Carlo error
    (the trials' region means' spread / √trials) in quadrature. Empty where no texel
    of the region is well sampled."""
    ref = np.ascontiguousarray(reference, np.float32)
    var = np.ascontiguousarray(inputs.variance, np.float32)
    trials, sampled = _baseline_maps(
        metric, reference=ref.tobytes(), variance=var.tobytes(), shape=ref.shape,
        exposure=(inputs.white, inputs.flip_start, inputs.flip_stop),
        rho=inputs.channel_correlation,
        seeds=(None if inputs.seed_estimates is None
               else np.ascontiguousarray(inputs.seed_estimates, np.float32).tobytes()))
    scored = np.asarray(mask, bool) & sampled
    if not scored.any():
        return {}
    base = trials.mean(axis=0, dtype=np.float64)
    sign = 1.0 if metric == "ssim" else -1.0  # SSIM: higher is better
    excess_map = sign * (base - value_map)
    excess = float(excess_map[scored].mean())
    boot = block_bootstrap(excess_map, scored, block=BLOCK, resamples=RESAMPLES,
                           rng=np.random.default_rng(0))
    means = trials[:, scored].mean(axis=1, dtype=np.float64)
    monte_carlo = float(means.std(ddof=1)) / math.sqrt(means.size)
    return {"baseline": float(base[scored].mean()),
            **_interval(excess, math.hypot(float(boot.std(ddof=1)), monte_carlo))}


def seed_luminance_totals(seed_maps, mask=None) -> np.ndarray:
    """(K,) S_k = Σ over ``mask``'s texels (default all) of seed k's luminance, for
    per-seed maps (K, H, W, 3): the reference total's K independent estimates."""
    x = np.asarray(seed_maps, np.float64)
    if mask is not None:
        x = x[:, np.asarray(mask, bool)]
    luminance = x @ LUMA
    return luminance.reshape(luminance.shape[0], -1).sum(axis=1)


def flux_ratio_interval(ratio: float, seed_totals) -> dict:
    """``baseline`` 1 and the :func:`_interval` fields of ratio − 1 from the reference's
    K per-seed totals S_k (:func:`seed_luminance_totals`; their mean is the reference's
    total): SE = ratio · √(s²(S_k) / K) / mean S_k, Student t with K − 1 degrees of
    freedom (:func:`_flux_ratio`)."""
    totals = np.asarray(seed_totals, np.float64).ravel()
    if totals.size < 2 or not np.isfinite(totals).all() or totals.mean() <= 0:
        raise MetricInputError(f"a flux ratio's interval needs at least 2 finite seed "
                               f"totals of a lit reference, got {totals.size} totals")
    stderr = ratio * math.sqrt(float(totals.var(ddof=1)) / totals.size) / totals.mean()
    return {"baseline": 1.0, **_interval(ratio - 1.0, stderr, dof=totals.size - 1)}


def _flux_ratio(method: np.ndarray, reference: np.ndarray, mask: np.ndarray,
                inputs: ExcessInputs) -> dict:
    """ratio − 1 with the delta method's standard error, ratio = ΣL(M) / ΣL(R) with L
    the luminance: SE = ratio · √Var ΣL(R) / ΣL(R).

    With the per-seed images, Var ΣL(R) = s²(S_k) / K, S_k = ΣL(R_k) the K seeds' region
    totals (s² their unbiased variance): exact whatever the texels' covariance (a
    stratified launch's total is far less noisy than its texels), Student t with K − 1
    degrees of freedom. Without them, texels are taken as independent:
    Var ΣL(R) = Σ_texels Σ_c Σ_c' a_c a_c' ρ_cc' σ_c σ_c' (a the luminance weights)."""
    m = float((np.asarray(method, np.float64)[mask] @ LUMA).sum())
    r = float((np.asarray(reference, np.float64)[mask] @ LUMA).sum())
    if r <= 0:
        return {}
    ratio = m / r
    dof = max(inputs.seeds - 1, 1)
    if inputs.seed_estimates is not None:
        return flux_ratio_interval(ratio, seed_luminance_totals(inputs.seed_estimates, mask))
    sigma = np.sqrt(np.maximum(np.asarray(inputs.variance, np.float64)[mask], 0.0)) * LUMA
    rho = inputs.channel_correlation
    texel = rho * sigma.sum(axis=1) ** 2 + (1.0 - rho) * (sigma**2).sum(axis=1)
    stderr = ratio * math.sqrt(float(texel.sum())) / r
    return {"baseline": 1.0, **_interval(ratio - 1.0, stderr, dof=dof)}


def metric_excess(metric: str, method: np.ndarray, reference: np.ndarray, mask: np.ndarray,
                  inputs: ExcessInputs | None, *, maps: dict[str, np.ndarray]) -> dict:
    """``baseline``, ``excess``, ``excess_stderr``, ``excess_ci95`` and
    ``distinguishable`` of one metric over ``mask`` (module docstring); empty where the
    metric has no estimator, the reference no variance, or the region no texel.

    Parameters
    ----------
    maps : dict of str to ndarray (H, W)
        ``ssim`` and ``flip``: the method's metric maps against the reference.
    """
    if inputs is None or not np.asarray(mask).any():
        return {}
    if not inputs.independent_texels and inputs.seed_estimates is None:
        # Pixels that share noise, with nothing to measure how: no interval.
        return {}
    try:
        if metric == "relmse":
            e = excess_relative_mse(method, reference, inputs.variance, seeds=inputs.seeds,
                                    mask=mask, channel_correlation=inputs.channel_correlation,
                                    seed_estimates=inputs.seed_estimates)
            return {"baseline": e.baseline, "excess": e.excess,
                    "excess_stderr": e.excess_stderr, "excess_ci95": e.excess_ci95,
                    "distinguishable": e.distinguishable}
        if metric in ("ssim", "flip"):
            return _perceptual(metric, maps[metric], reference, mask, inputs=inputs)
        if metric == "flux_ratio":
            return _flux_ratio(method, reference, mask, inputs)
    except MetricInputError:
        return {}
    return {}
