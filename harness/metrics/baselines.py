"""What SSIM and HDR-FLIP a perfect method would score against a noisy reference, and
the method's excess over it with a block-bootstrap interval.

A perfect method M = T is compared with the reference R = T + η, so it scores
metric(T, T + η), not the metric's ideal value (SSIM 1, FLIP 0). Neither metric is a
mean of per-texel squares, so no closed form removes the noise as for relMSE
(:mod:`harness.metrics.excess`); the baseline is simulated instead:

    baseline = mean over trials of  metric(T̃, T̃ + ε),   ε = √v̂ Z per texel,

with the reference's per-texel, per-channel variance of the mean v̂, Z photon-like by
default: (N − n) / √n with N ~ Poisson(n) and n the photons the texel's mean holds
(:func:`photons_per_texel`: n = T̃ / q, q = G * v̂ / G * R the photons' weight), so ε
has the tracer's skew 1 / √n and its discreteness where photons are few (Z standard
normal with ``noise="gaussian"``); the channels' noise correlated as the tracer makes
it (``channel_correlation``: 1 when one photon carries all three channels, one Z per
texel; 0 for per-channel passes), and T̃ an estimate of the noise-free image. With the
reference's K per-seed images (K even) ε is instead the seeds' own noise,
(1/K) Σ_k s_k x_k with K/2 random signs +1 and K/2 −1 (``noise="seeds"``): the truth
cancels and ε has the mean's covariance, neighbouring texels' included (a stratified
launch makes them anticorrelate, noise that SSIM's window and FLIP's filters see less
of than independent noise). T̃ = R would be wrong: R's own noise then counts as image
structure that the noisy copy matches, and SSIM's structure term (2σ_xy + C₂)/(σ_x² + σ_y² + C₂)
reads too high. T̃ is R shrunk towards its local mean by Wiener's factor,

    μ = G * R,   s² = G * (R − μ)²,   T̃ = μ + max(0, 1 − (G * v̂) / s²) (R − μ),

with G the Gaussian window of SSIM (σ = 1.5 texels), so T̃'s local variance is R's
minus the noise's (method of moments); the simulated pair then has the local
statistics of (T, T + η). The baseline's own Monte Carlo error is its spread over
trials / √trials.

Excess: baseline − value for SSIM (higher is better), value − baseline for FLIP. Its
interval: SSIM and FLIP maps are spatially correlated (windows of a few texels), so the
texels are resampled in blocks (8 × 8 by default): the mean excess map over the region
is recomputed on B resamples of the blocks, and its standard deviation, combined in
quadrature with the baseline's Monte Carlo error, gives a normal 95 % interval.
Resampling blocks measures the spatial spread of the excess map, which includes the
method's bias pattern: for a biased method the interval is conservative (wider than
the reference noise alone would make it), for a perfect one it is the noise.
``distinguishable`` when the interval excludes 0.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import gaussian_filter

from harness.metrics.scores import MetricInputError, flip_error, structural_similarity

__all__ = ["WELL_SAMPLED", "PerceptualBaseline", "PerceptualExcess", "block_bootstrap",
           "denoised_reference", "flip_map", "perceptual_baseline", "perceptual_excess",
           "photons_per_texel", "ssim_map"]

#: A metric map: (method, reference), both (H, W, 3) linear, to an (H, W) map.
MetricMap = Callable[[np.ndarray, np.ndarray], np.ndarray]
#: Gaussian window of SSIM (texels): the scale of T̃'s local statistics.
WINDOW_SIGMA = 1.5
#: Normal quantile of the two-sided 95 % interval.
Z95 = 1.959963984540054
#: Side of the bootstrap's square blocks (texels): larger than SSIM's Gaussian window
#: (σ = 1.5, 11 × 11) and FLIP's filters at these resolutions, so blocks are nearly
#: independent.
BLOCK = 8
#: Bootstrap resamples.
RESAMPLES = 400
#: Photons a texel's reference mean must hold (:func:`photons_per_texel`) for SSIM and
#: FLIP to be scored there: 25, a relative noise of 20 %. Below it a texel holds a
#: handful of photons per seed (a caustic's fringe), where SSIM and FLIP of a perfect
#: method swing with the photons' discreteness and the denoised reference T̃ is least
#: reliable. The count comes from the scored reference's own variance, so the rule
#: selects on its noise where texels lie near the threshold (low v̂, few photons'
#: worth of noise in the baseline, a perfect method called off): at 100 photons a 10 %
#: Poisson reference, whose texels all hold 100–340, had a perfect method's SSIM called
#: off in 53–60 % of 60 simulations against 28–30 % unrestricted; the lower threshold
#: keeps the rule to the fringe, far from a caustic's core.
WELL_SAMPLED = 25.0


def ssim_map(*, white: float) -> MetricMap:
    """SSIM map of tone-mapped images (:func:`structural_similarity`), white point
    ``white`` (from the reference, fixed across trials)."""
    def metric(method, reference):
        return structural_similarity(method, reference, white=white, return_map=True)[1]
    return metric


def flip_map(*, start_exposure: float, stop_exposure: float) -> MetricMap:
    """HDR-FLIP map (:func:`flip_error`) over a fixed exposure range (stops)."""
    def metric(method, reference):
        return flip_error(method, reference, start_exposure=start_exposure,
                          stop_exposure=stop_exposure, return_map=True)[1]
    return metric


@dataclass(frozen=True, eq=False)
class PerceptualBaseline:
    """Simulated score of a perfect method against the reference.

    Attributes
    ----------
    baseline : float
        Mean over trials of the region's mean metric.
    spread : float
        Standard deviation over trials of that mean (one trial's scatter; the
        baseline's own error is ``spread / sqrt(trials)``).
    trials : int
    baseline_map : ndarray (H, W)
        The metric map averaged over trials.
    trial_maps : ndarray (trials, H, W) or None
        Each trial's map (``keep_trials``), for the Monte Carlo error over any region.
    """

    baseline: float
    spread: float
    trials: int
    baseline_map: np.ndarray = field(repr=False)
    trial_maps: np.ndarray | None = field(default=None, repr=False)


@dataclass(frozen=True)
class PerceptualExcess:
    """A perceptual metric, its noise baseline and the method's excess over it
    (``excess`` > 0 means worse than a perfect method would score)."""

    value: float
    baseline: float
    baseline_spread: float
    excess: float
    excess_stderr: float
    excess_ci95: tuple[float, float]
    distinguishable: bool

    def as_dict(self) -> dict:
        """Plain JSON-able fields (the names users script against in metrics.json)."""
        return {"value": self.value, "baseline": self.baseline,
                "baseline_spread": self.baseline_spread, "excess": self.excess,
                "excess_stderr": self.excess_stderr, "excess_ci95": list(self.excess_ci95),
                "distinguishable": self.distinguishable}


def _check(reference, variance, mask):
    reference = np.asarray(reference, np.float64)
    variance = np.asarray(variance, np.float64)
    if reference.ndim != 3 or variance.shape != reference.shape:
        raise MetricInputError(f"expected (H, W, C) reference and variance, got "
                               f"{reference.shape} and {variance.shape}")
    if (variance < 0).any() or not np.isfinite(variance).all():
        raise MetricInputError("variance must be finite and non-negative")
    mask = np.ones(reference.shape[:2], bool) if mask is None else np.asarray(mask, bool)
    if mask.shape != reference.shape[:2] or not mask.any():
        raise MetricInputError(f"mask {mask.shape} must select texels of "
                               f"{reference.shape[:2]}")
    return reference, variance, mask


def denoised_reference(reference, variance, *, sigma: float = WINDOW_SIGMA) -> np.ndarray:
    """T̃: the reference shrunk towards its local Gaussian mean by Wiener's factor
    (module docstring), per channel, clipped at 0; (H, W, C) like ``reference``."""
    reference, variance, _ = _check(reference, variance, None)
    spatial = (sigma, sigma, 0)
    mean = gaussian_filter(reference, spatial)
    local = gaussian_filter((reference - mean) ** 2, spatial)
    noise = gaussian_filter(variance, spatial)
    with np.errstate(divide="ignore", invalid="ignore"):
        keep = np.where(local > 0, np.clip(1.0 - noise / local, 0.0, 1.0), 0.0)
    return np.maximum(mean + keep * (reference - mean), 0.0)


def _noise(rng, shape, variance, rho):
    """ε ~ N(0, variance) per texel and channel, channels correlated with ρ."""
    common = rng.standard_normal(shape[:2])[..., None]
    own = rng.standard_normal(shape)
    return np.sqrt(variance) * (np.sqrt(rho) * common + np.sqrt(1.0 - rho) * own)


def photons_per_texel(reference, variance, *, sigma: float = WINDOW_SIGMA) -> np.ndarray:
    """n: the photons a texel's reference mean is made of, per channel, as a photon
    tracer's noise implies them: a mean of photons of weight q has variance q · mean, so
    q = (G * v̂) / (G * R) (the Gaussian window G pools neighbours: v̂ alone has K − 1
    degrees of freedom) and n = T̃ / q with T̃ the denoised reference
    (:func:`denoised_reference`); (H, W, C). Infinite where the reference has no
    variance (no noise), 0 where it is black."""
    reference, variance, _ = _check(reference, variance, None)
    truth = denoised_reference(reference, variance, sigma=sigma)
    spatial = (sigma, sigma, 0)
    weight_num = gaussian_filter(variance, spatial)
    weight_den = gaussian_filter(reference, spatial)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(weight_den > 0, weight_num / weight_den, 0.0)
        return np.where(q > 0, truth / q, np.where(truth > 0, np.inf, 0.0))


def _photon_noise(rng, variance, photons, rho):
    """ε_c = √v̂_c Z with Z = (N − n) / √n, N ~ Poisson(n): the reference's own variance
    per texel and channel (as the Gaussian model has it, so a texel without variance
    gets no noise), with a photon count's skew 1 / √n and discreteness where n is small.
    With correlated channels (ρ > 0: one photon carries all three) one count per texel,
    n the mean of its channels' n_c (all equal for photons whose colour ratio is
    fixed); with ρ = 0 one count per channel, n = n_c. Where n is infinite (no
    variance) Z is irrelevant and taken as 0."""
    finite = np.isfinite(photons) & (photons > 0)
    n_c = np.where(finite, photons, 1.0)
    if rho > 0:
        n = n_c.mean(axis=-1, keepdims=True)
    else:
        n = n_c
    z = (rng.poisson(n) - n) / np.sqrt(n)
    return np.sqrt(variance) * np.where(finite, z, 0.0)


def _seed_noise(rng, seed_estimates):
    """ε = (1/K) Σ_k s_k x_k with K/2 signs +1 and K/2 signs −1 drawn at random over the
    K per-seed images x_k (K even): the truth cancels (Σ s_k = 0), and for independent
    seeds ε has the mean's covariance exactly, Var = K σ² / K² = σ² / K per texel and
    the seeds' own covariance between texels and channels (a stratified launch's
    anticorrelated neighbours, which a texel-by-texel model misses); its distribution is
    symmetric (no skew)."""
    k = seed_estimates.shape[0]
    signs = np.where(rng.permutation(k) < k // 2, 1.0, -1.0)
    return np.tensordot(signs, seed_estimates, axes=1) / k


def perceptual_baseline(reference, variance, *, metric: MetricMap, trials: int = 8,
                        seed: int = 0, mask=None, channel_correlation: float = 1.0,
                        noise: str = "photon", keep_trials: bool = False,
                        seed_estimates=None) -> PerceptualBaseline:
    """Expected metric of a perfect method against ``reference`` (module docstring).

    Parameters
    ----------
    reference, variance : ndarray (H, W, 3)
        The reference mean and the variance of that mean (squared image units).
    metric : callable
        ``(method, reference) -> (H, W) map`` (:func:`ssim_map`, :func:`flip_map`).
    trials : int
        Simulated noisy references (each one metric evaluation).
    seed : int
        Seed of the simulated noise.
    mask : ndarray (H, W) of bool, optional
        Region over which the map is averaged.
    channel_correlation : float
        Correlation of a texel's channel noises (1: one photon carries all three).
    noise : str
        ``"photon"`` (default): T̃ + √v̂ Z, Z a standardised Poisson count at the
        texel's photons (:func:`photons_per_texel`, :func:`_photon_noise`): the
        reference's variance, skewed and discrete like the tracer's noise.
        ``"gaussian"``: T̃ + ε, ε ~ N(0, v̂), correlated across channels by ρ.
        ``"seeds"``: T̃ + ε with ε a balanced signed combination of the per-seed images
        (:func:`_seed_noise`): the reference's own noise covariance, neighbours
        included; needs ``seed_estimates`` with an even K.
    keep_trials : bool
        Keep each trial's map (``trial_maps``).
    seed_estimates : ndarray (K, H, W, 3), optional
        The reference's per-seed images (``noise="seeds"``).
    """
    reference, variance, mask = _check(reference, variance, mask)
    if noise not in ("photon", "gaussian", "seeds"):
        raise MetricInputError(f"noise must be 'photon', 'gaussian' or 'seeds', got {noise!r}")
    if noise == "seeds":
        seed_estimates = np.asarray(seed_estimates, np.float64)
        k = seed_estimates.shape[0] if seed_estimates.ndim == 4 else 0
        if seed_estimates.shape[1:] != reference.shape or k < 2 or k % 2:
            raise MetricInputError(f"noise='seeds' needs an even number of per-seed images "
                                   f"of {reference.shape}, got {seed_estimates.shape}")
    if trials < 2:
        raise MetricInputError(f"a spread needs at least 2 trials, got {trials}")
    if not 0.0 <= channel_correlation <= 1.0:
        raise MetricInputError(f"channel_correlation must be in [0, 1], got "
                               f"{channel_correlation}")
    truth = denoised_reference(reference, variance)
    photons = photons_per_texel(reference, variance) if noise == "photon" else None
    rng = np.random.default_rng(seed)
    maps = []
    for _ in range(trials):
        if noise == "seeds":
            noisy = np.maximum(truth + _seed_noise(rng, seed_estimates), 0.0)
        elif photons is None:
            noisy = np.maximum(truth + _noise(rng, truth.shape, variance,
                                              channel_correlation), 0.0)
        else:
            noisy = np.maximum(truth + _photon_noise(rng, variance, photons,
                                                     channel_correlation), 0.0)
        maps.append(np.asarray(metric(truth, noisy), np.float64))
    stack = np.stack(maps)
    means = stack[:, mask].mean(axis=1)
    return PerceptualBaseline(baseline=float(means.mean()), spread=float(means.std(ddof=1)),
                              trials=trials, baseline_map=stack.mean(axis=0),
                              trial_maps=stack if keep_trials else None)


def block_bootstrap(values: np.ndarray, mask: np.ndarray, *, block: int, resamples: int,
                     rng) -> np.ndarray:
    """Means of ``values`` over ``mask`` on ``resamples`` resamples of block × block
    tiles (with replacement, as many tiles as hold a masked texel)."""
    h, w = values.shape
    rows, cols = -(-h // block), -(-w // block)
    sums = np.zeros((rows, cols))
    counts = np.zeros((rows, cols))
    tile_r = (np.arange(h) // block)[:, None].repeat(w, 1)
    tile_c = (np.arange(w) // block)[None, :].repeat(h, 0)
    np.add.at(sums, (tile_r[mask], tile_c[mask]), values[mask])
    np.add.at(counts, (tile_r[mask], tile_c[mask]), 1.0)
    used = counts.ravel() > 0
    sums, counts = sums.ravel()[used], counts.ravel()[used]
    pick = rng.integers(0, sums.size, size=(resamples, sums.size))
    return sums[pick].sum(axis=1) / counts[pick].sum(axis=1)


def perceptual_excess(method, reference, variance, *, metric: MetricMap,
                      higher_is_better: bool, mask=None, trials: int = 8, block: int = BLOCK,
                      resamples: int = RESAMPLES, seed: int = 0,
                      channel_correlation: float = 1.0, noise: str = "photon",
                      seed_estimates=None) -> PerceptualExcess:
    """The method's excess over a perfect method's score, with a block-bootstrap
    interval (module docstring).

    Parameters
    ----------
    method, reference, variance : ndarray (H, W, 3)
        Method image, reference mean and the variance of that mean.
    metric : callable
        ``(method, reference) -> (H, W) map``.
    higher_is_better : bool
        True for SSIM (excess = baseline − value), False for FLIP (value − baseline).
    block : int
        Side of the resampled square blocks (texels); larger than the metric's window.
    resamples : int
        Bootstrap resamples.
    trials, seed, mask, channel_correlation, noise, seed_estimates
        As for :func:`perceptual_baseline`.
    """
    reference, variance, mask = _check(reference, variance, mask)
    method = np.asarray(method, np.float64)
    if method.shape != reference.shape:
        raise MetricInputError(f"shapes differ: method {method.shape}, "
                               f"reference {reference.shape}")
    if block < 1 or resamples < 2:
        raise MetricInputError(f"block {block} and resamples {resamples} must be positive")
    base = perceptual_baseline(reference, variance, metric=metric, trials=trials, seed=seed,
                               mask=mask, channel_correlation=channel_correlation,
                               noise=noise, seed_estimates=seed_estimates)
    value_map = np.asarray(metric(method, reference), np.float64)
    sign = 1.0 if higher_is_better else -1.0
    excess_map = sign * (base.baseline_map - value_map)
    excess = float(excess_map[mask].mean())
    rng = np.random.default_rng(seed + 1)
    boot = block_bootstrap(excess_map, mask, block=block, resamples=resamples, rng=rng)
    stderr = float(np.hypot(boot.std(ddof=1), base.spread / np.sqrt(base.trials)))
    low, high = excess - Z95 * stderr, excess + Z95 * stderr
    return PerceptualExcess(value=float(value_map[mask].mean()), baseline=base.baseline,
                            baseline_spread=base.spread, excess=excess,
                            excess_stderr=stderr, excess_ci95=(low, high),
                            distinguishable=bool(low > 0 or high < 0))
