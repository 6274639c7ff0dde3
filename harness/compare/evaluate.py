"""Score one view (camera image or receiver map) of the real-time render.

Each metric of the caustics-mapping image against the reference is paired with the
same metric of an *independent* reference (other seeds) against the reference: the
noise floor, the error that reference noise alone produces. An error near its floor
is not the method's.

Exposure is fixed per scene from the reference alone: the tone curve's white point
is the reference's 99th-percentile luminance w, and HDR-FLIP spans the exposures
[−log2 w − 3, −log2 w + 3] stops, so that every configuration of a sweep is scored
on the same scale.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.compare.stray import stray_flux_value
from harness.compare.uncertainty import ExcessInputs, metric_excess
from harness.metrics import (
    MetricInputError,
    flip_error,
    flux_ratio,
    peak_signal_to_noise_ratio,
    relative_mse,
    signed_difference,
    structural_similarity,
    white_point,
)
from reports.records import MetricValue

__all__ = ["Exposure", "exposure_for", "flip_input", "score_value", "score_view"]

FLIP_STOPS = 3.0


@dataclass(frozen=True)
class Exposure:
    """Fixed per-scene exposure: tone-curve white and FLIP's exposure range (stops)."""

    white: float
    flip_start: float
    flip_stop: float


def exposure_for(reference: np.ndarray, *, mask: np.ndarray | None = None) -> Exposure:
    """Exposure derived from the reference only (see the module docstring)."""
    white = white_point(reference, mask=mask, percentile=99.0)
    centre = -np.log2(white)
    return Exposure(white, centre - FLIP_STOPS, centre + FLIP_STOPS)


def flip_input(image) -> np.ndarray:
    """The image HDR-FLIP scores: ``image`` itself, or a copy clamped at 0 where it holds
    negative values (FLIP is defined on non-negative images only). Radiance is never
    negative, so a method that writes negatives fails the ``non-negative`` physical
    requirement (:mod:`harness.checks.physical`), which records them; its other
    metrics score the image as written."""
    image = np.asarray(image)
    return np.maximum(image, 0.0) if (image < 0).any() else image


def score_value(metric: str, method, reference, *, mask, exposure: Exposure) -> float:
    """One metric of ``method`` against ``reference`` over ``mask``; NaN when undefined
    (e.g. PSNR of a black region, or a flux ratio where the reference has no energy).
    FLIP scores :func:`flip_input` of ``method``."""
    try:
        if metric == "relmse":
            return relative_mse(method, reference, mask=mask)
        if metric == "relmse_trimmed":
            return relative_mse(method, reference, mask=mask, trim=0.001)
        if metric == "psnr":
            return peak_signal_to_noise_ratio(method, reference, mask=mask)
        if metric == "ssim":
            return structural_similarity(method, reference, white=exposure.white, mask=mask)
        if metric == "flip":
            return flip_error(flip_input(method), reference, start_exposure=exposure.flip_start,
                              stop_exposure=exposure.flip_stop, mask=mask)
        if metric == "flux_ratio":
            return flux_ratio(method, reference, mask=mask)
    except MetricInputError:
        return float("nan")
    raise KeyError(f"unknown metric {metric!r}")


METRICS = ("relmse", "relmse_trimmed", "psnr", "ssim", "flip", "flux_ratio")


def _perceptual_maps(method, reference, exposure: Exposure) -> tuple[np.ndarray, np.ndarray]:
    """The full-image SSIM and FLIP maps (H, W) of ``method`` against ``reference``, as
    :func:`score_value` computes them (FLIP of :func:`flip_input` of ``method``)."""
    _, ssim_map = structural_similarity(method, reference, white=exposure.white, return_map=True)
    _, flip_map = flip_error(flip_input(method), reference, start_exposure=exposure.flip_start,
                             stop_exposure=exposure.flip_stop, return_map=True)
    return ssim_map, flip_map


def score_view(view: str, method, reference, independent, *, regions: dict[str, np.ndarray],
               exposure: Exposure, variance=None, seeds: int | None = None,
               channel_correlation: float = 1.0, seed_estimates=None,
               independent_texels: bool = True,
               ) -> tuple[list[MetricValue], dict[str, np.ndarray]]:
    """All metrics of one view over each region, with noise floors, the method's
    excess error with its interval where the reference has a variance
    (:mod:`harness.compare.uncertainty`), and the maps.

    Parameters
    ----------
    view
        ``camera`` or ``receiver<i>``.
    method, reference, independent
        (H, W, 3) linear images: the method, the reference mean, and an independent
        reference of other seeds (``None`` skips the noise floor).
    regions
        Region name to boolean (H, W) mask; empty masks are skipped. A ``caustic``
        region (the scene's, ``harness.compare.regions``) adds the ``stray_flux``
        record over its complement (:mod:`harness.compare.stray`).
    variance, seeds
        The variance of the reference's mean per texel and channel, and the seeds K
        it comes from (None: no excess errors).
    channel_correlation
        1 when the same photons carry all three channels, 0 for one pass per channel.
    seed_estimates, independent_texels
        The reference's per-seed images (K, H, W, 3) or None, and whether the view's
        texels carry independent noise (:class:`~harness.compare.uncertainty.ExcessInputs`).

    Returns
    -------
    values, maps
        The metric values, and ``{"<view>/signed", "<view>/ssim", "<view>/flip"}``
        maps over the full image (float32; SSIM and FLIP rounded to half precision).
    """
    # SSIM and FLIP maps made once for every region (a region's value is its map's mean
    # over the mask, as score_value computes it): the method's, and the noise floor's.
    ssim_map, flip_map = _perceptual_maps(method, reference, exposure)
    maps = {"ssim": ssim_map, "flip": flip_map}
    floor_maps = {}
    if independent is not None:
        try:
            floor_maps = dict(zip(maps, _perceptual_maps(independent, reference, exposure),
                                  strict=True))
        except MetricInputError:
            pass  # score_value's NaN, region by region
    inputs = None
    if variance is not None and seeds is not None and seeds >= 2:
        inputs = ExcessInputs(np.asarray(variance), int(seeds), channel_correlation,
                              exposure.white, exposure.flip_start, exposure.flip_stop,
                              seed_estimates=seed_estimates,
                              independent_texels=independent_texels)
    values = []
    for region, region_mask in regions.items():
        mask = np.asarray(region_mask, bool)
        if not mask.any():
            continue
        for metric in METRICS:
            if metric in maps:
                value = float(maps[metric][mask].mean())
            else:
                value = score_value(metric, method, reference, mask=mask, exposure=exposure)
            floor = None
            if metric in floor_maps:
                floor = float(floor_maps[metric][mask].mean())
            elif independent is not None:
                floor = score_value(metric, independent, reference, mask=mask,
                                    exposure=exposure)
            excess = metric_excess(metric, method, reference, mask, inputs, maps=maps)
            values.append(MetricValue(view, region, metric, value, floor, **excess,
                                      pixels=int(mask.sum())))
    caustic = regions.get("caustic")
    if caustic is not None and np.asarray(caustic, bool).any():
        stray = stray_flux_value(view, method, reference, caustic, variance=variance,
                                 seeds=seeds, channel_correlation=channel_correlation)
        if stray is not None:
            values.append(stray)
    # SSIM and FLIP lie in [-1, 1] and [0, 1]: their maps are kept (and written,
    # ``harness.compare.outputs``) at half precision, absolute error at most 2.4e-4,
    # so the file, the page's data and the record hold the same values. The metrics
    # above used the full-precision maps.
    maps = {f"{view}/signed": signed_difference(method, reference).astype(np.float32),
            f"{view}/ssim": ssim_map.astype(np.float16).astype(np.float32),
            f"{view}/flip": flip_map.astype(np.float16).astype(np.float32)}
    return values, maps
