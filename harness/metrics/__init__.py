"""Image metrics: differences, relMSE, PSNR, SSIM (tone-mapped), HDR-FLIP, flux ratio."""

from harness.metrics.differences import (
    absolute_difference,
    relative_difference,
    signed_difference,
)
from harness.metrics.scores import (
    MetricInputError,
    flip_error,
    flux_ratio,
    peak_signal_to_noise_ratio,
    relative_mse,
    structural_similarity,
)
from reports.display import false_colour, luminance, tonemap, white_point

__all__ = [
    "MetricInputError",
    "absolute_difference",
    "false_colour",
    "flip_error",
    "flux_ratio",
    "luminance",
    "peak_signal_to_noise_ratio",
    "relative_difference",
    "relative_mse",
    "signed_difference",
    "structural_similarity",
    "tonemap",
    "white_point",
]
