"""Scalar image metrics with optional region masks.

Every function takes ``method`` and ``reference`` as (H, W, 3) arrays in the same
linear units and an optional boolean ``mask`` (H, W) selecting the pixels scored.

relMSE        mean over pixels and channels of d² / (reference² + ε), ε = 0.01;
              the trimmed form drops the largest 0.1 % of the per-value terms first
              (outliers from fireflies or single-texel splats).
PSNR          10 log10(peak² / MSE), peak = the reference's maximum in the mask.
SSIM          Wang et al. 2004 on tone-mapped images (``scenes.colour.tonemap``):
              Gaussian weights σ = 1.5, population covariance, K1 = 0.01, K2 = 0.03,
              data_range = 1; the mean of the SSIM map over the mask.
FLIP          HDR-FLIP (Andersson et al. 2021) through ``flip-evaluator`` with a
              fixed exposure range [start, stop] so a series is comparable;
              the mean of the FLIP map over the mask.
flux ratio    Σ method / Σ reference (luminance-weighted), the energy check.
stray flux    Σ method outside a region / Σ reference over the whole map
              (luminance-weighted): light put where the scene's caustic is not.
"""

from __future__ import annotations

import flip_evaluator
import numpy as np
from skimage.metrics import structural_similarity as ssim

from scenes.colour import luminance, tonemap
from scenes.errors import HarnessError

__all__ = [
    "MetricInputError",
    "flip_error",
    "flux_ratio",
    "peak_signal_to_noise_ratio",
    "relative_mse",
    "stray_flux",
    "structural_similarity",
]

RELMSE_EPSILON = 0.01
TRIM_FRACTION = 0.001


class MetricInputError(HarnessError, ValueError):
    """Images or options a metric cannot use (shape, NaN, negative HDR, bad range)."""


def _check(method, reference, mask) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    method = np.asarray(method, np.float64)
    reference = np.asarray(reference, np.float64)
    if method.shape != reference.shape:
        raise MetricInputError(f"shapes differ: method {method.shape}, reference {reference.shape}")
    if method.ndim != 3 or method.shape[2] != 3:
        raise MetricInputError(f"expected (H, W, 3) images, got {method.shape}")
    if not (np.isfinite(method).all() and np.isfinite(reference).all()):
        raise MetricInputError("images hold NaN or Inf")
    if mask is None:
        mask = np.ones(method.shape[:2], bool)
    mask = np.asarray(mask, bool)
    if mask.shape != method.shape[:2]:
        raise MetricInputError(f"mask shape {mask.shape} does not match {method.shape[:2]}")
    if not mask.any():
        raise MetricInputError("mask selects no pixels")
    return method, reference, mask


def relative_mse(method, reference, *, mask=None, epsilon: float = RELMSE_EPSILON,
                 trim: float = 0.0) -> float:
    """Mean of (method − ref)² / (ref² + ε) over masked pixels and channels.

    Parameters
    ----------
    epsilon
        Regulariser in the image's squared units (0.01, as in the rendering
        literature's relMSE).
    trim
        Fraction of the largest terms to drop before averaging (0.001 for the
        trimmed variant).
    """
    method, reference, mask = _check(method, reference, mask)
    terms = ((method - reference) ** 2 / (reference**2 + epsilon))[mask].ravel()
    if trim > 0:
        keep = terms.size - int(np.floor(trim * terms.size))
        terms = np.partition(terms, keep - 1)[:keep] if keep < terms.size else terms
    return float(terms.mean())


def peak_signal_to_noise_ratio(method, reference, *, mask=None) -> float:
    """10 log10(peak² / MSE) in dB, peak = max reference value in the mask; inf if equal."""
    method, reference, mask = _check(method, reference, mask)
    mse = float(((method - reference) ** 2)[mask].mean())
    peak = float(reference[mask].max())
    if mse == 0:
        return float("inf")
    if peak <= 0:
        raise MetricInputError("reference is black in the mask: PSNR undefined")
    return 10.0 * np.log10(peak**2 / mse)


def structural_similarity(method, reference, *, white: float, mask=None,
                          return_map: bool = False):
    """Mean SSIM of tone-mapped images over ``mask`` (and the (H, W) map if asked).

    Parameters
    ----------
    white
        White point of the tone curve, from the reference (``white_point``).
    """

    method, reference, mask = _check(method, reference, mask)
    a, b = tonemap(method, white=white), tonemap(reference, white=white)
    _, full = ssim(a, b, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                   K1=0.01, K2=0.03, data_range=1.0, channel_axis=-1, full=True)
    ssim_map = full.mean(axis=-1)
    value = float(ssim_map[mask].mean())
    return (value, ssim_map) if return_map else value


def flip_error(method, reference, *, start_exposure: float, stop_exposure: float,
               mask=None, pixels_per_degree: float = 67.0, return_map: bool = False):
    """Mean HDR-FLIP over ``mask`` (and the (H, W) map if asked).

    ``flip-evaluator`` calls ``sys.exit`` on arguments it dislikes, so everything is
    checked here first and a :class:`MetricInputError` raised instead.
    """

    method, reference, mask = _check(method, reference, mask)
    if (method < 0).any() or (reference < 0).any():
        raise MetricInputError("HDR-FLIP needs non-negative images")
    if not (np.isfinite(start_exposure) and np.isfinite(stop_exposure)):
        raise MetricInputError("exposures must be finite")
    if start_exposure > stop_exposure:
        raise MetricInputError(
            f"start exposure {start_exposure} exceeds stop exposure {stop_exposure}")
    if min(method.shape[:2]) < 2:
        raise MetricInputError("FLIP needs images of at least 2x2 pixels")
    flip_map, _, _ = flip_evaluator.evaluate(
        np.ascontiguousarray(reference, np.float32), np.ascontiguousarray(method, np.float32),
        "HDR", inputsRGB=False, applyMagma=False, computeMeanError=False,
        parameters={"startExposure": float(start_exposure),
                    "stopExposure": float(stop_exposure), "ppd": float(pixels_per_degree)},
    )
    flip_map = np.asarray(flip_map, np.float64)
    if flip_map.ndim == 3:
        flip_map = flip_map[..., 0]
    value = float(flip_map[mask].mean())
    return (value, flip_map) if return_map else value


def flux_ratio(method, reference, *, mask=None) -> float:
    """Σ luminance(method) / Σ luminance(reference) over the mask (1 = energy conserved)."""
    method, reference, mask = _check(method, reference, mask)
    ref_sum = float(luminance(reference)[mask].sum())
    if ref_sum <= 0:
        raise MetricInputError("reference holds no energy in the mask")
    return float(luminance(method)[mask].sum()) / ref_sum


def stray_flux(method, reference, *, region) -> float:
    """Σ luminance(method) outside ``region`` / Σ luminance(reference) over the whole map.

    The share of the reference's flux that the method puts where the caustic region
    is not (the reference's own share there is :func:`stray_flux` of the reference
    against itself). The region is the scene's (``harness.compare.regions``), so a
    method that spreads dim light cannot hide it by widening its own region.

    Parameters
    ----------
    method, reference : ndarray (H, W, 3)
        Irradiance maps in the same units (W/m²).
    region : ndarray (H, W) of bool
        The caustic region; its complement is scored.
    """
    method, reference, inside = _check(method, reference, region)
    total = float(luminance(reference).sum())
    if total <= 0:
        raise MetricInputError("reference holds no energy")
    return float(luminance(method)[~inside].sum()) / total
