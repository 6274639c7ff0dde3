"""Light a method puts outside the scene's caustic region: the ``stray_flux`` record.

The caustic region belongs to the scene (``harness.compare.regions``), so every method
is scored on the same texels; a method that spreads dim light around the caustic is
not rewarded by a larger denominator, and the light it puts outside is measured here:

    s(X) = Σ_{outside} L(X) / Σ_{all} L(R)            (L the luminance, R the reference)

value = s(M), baseline = s(R) (the reference's own light there: dim tails, the
threshold's cut), excess = s(M) − s(R) = (m − A) / (A + B) with m = Σ_out L(M),
A = Σ_out L(R), B = Σ_in L(R). Under the reference's noise A and B are sums of
independent texels' noise, so by the delta method

    Var = (∂e/∂A)² Var A + (∂e/∂B)² Var B,   ∂e/∂A = −1/S − e/S,  ∂e/∂B = −e/S,  S = A + B,

with Var A, Var B the sums of the texels' luminance variances (channels correlated by
ρ as in ``harness.compare.uncertainty``), and a t interval with Satterthwaite's degrees
of freedom (each texel's variance is estimated from the K seeds).
"""

from __future__ import annotations

import math

import numpy as np

from harness.metrics import MetricInputError, stray_flux
from harness.metrics.excess import t_interval
from reports.records import MetricValue
from scenes.colour import LUMA

__all__ = ["stray_flux_value"]


def _luminance_variance(variance: np.ndarray, rho: float) -> np.ndarray:
    """(H, W) variance of each texel's luminance from its channels' variances
    (W/m²)², their noises correlated by ``rho``."""
    sigma = np.sqrt(np.maximum(np.asarray(variance, np.float64), 0.0)) * LUMA
    return rho * sigma.sum(axis=-1) ** 2 + (1.0 - rho) * (sigma**2).sum(axis=-1)


def stray_flux_value(view: str, method: np.ndarray, reference: np.ndarray,
                     region: np.ndarray, *, variance: np.ndarray | None = None,
                     seeds: int | None = None, channel_correlation: float = 1.0
                     ) -> MetricValue | None:
    """The ``stray_flux`` record of one receiver map (module docstring), over the
    ``outside`` region; None when the reference holds no light.

    Parameters
    ----------
    view : str
        ``receiver<i>``.
    method, reference : ndarray (H, W, 3)
        Caustic irradiance, W/m².
    region : ndarray (H, W) of bool
        The scene's caustic region.
    variance, seeds : ndarray (H, W, 3) and int, optional
        The reference's variance of the mean per texel and channel, and its K seeds
        (none: no interval).
    channel_correlation : float
        1 when the same photons carry all three channels, 0 for one pass per channel.
    """
    inside = np.asarray(region, bool)
    try:
        value = stray_flux(method, reference, region=inside)
        baseline = stray_flux(reference, reference, region=inside)
    except MetricInputError:
        return None
    outside = int((~inside).sum())
    record = {"baseline": baseline, "excess": value - baseline}
    if variance is not None and seeds is not None and seeds >= 2:
        lum = np.asarray(reference, np.float64) @ LUMA
        total = float(lum.sum())
        excess = value - baseline
        texel = _luminance_variance(variance, channel_correlation)
        d_out = -1.0 / total - excess / total
        d_in = -excess / total
        terms = np.where(inside, d_in**2, d_out**2) * texel
        stderr = math.sqrt(float(terms.sum()))
        # Each texel's variance has K − 1 degrees of freedom; their weighted sum has
        # Satterthwaite's (Σ a_i)² / Σ (a_i² / (K − 1)), many more than K − 1.
        square = float((terms**2).sum())
        dof = float(terms.sum()) ** 2 * (seeds - 1) / square if square > 0 else seeds - 1
        low, high = t_interval(excess, stderr, dof)
        record |= {"excess_stderr": stderr, "excess_ci95": (low, high),
                   "distinguishable": bool(stderr > 0 and (low > 0 or high < 0))}
    return MetricValue(view, "outside", "stray_flux", value, pixels=outside, **record)
