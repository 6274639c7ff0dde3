"""Image metrics: differences, relMSE, PSNR, SSIM (tone-mapped), HDR-FLIP, flux ratio;
over time (``temporal``): flicker and temporal high-frequency energy."""

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
    stray_flux,
    structural_similarity,
)
from harness.metrics.temporal import (
    flicker_map,
    flicker_series,
    frame_differences,
    high_frequency_energy,
    high_frequency_energy_ratio,
    high_frequency_energy_ratio_map,
    temporal_flicker,
)
from reports.display import false_colour
from scenes.colour import luminance, tonemap, white_point

__all__ = [
    "MetricInputError",
    "absolute_difference",
    "false_colour",
    "flicker_map",
    "flicker_series",
    "flip_error",
    "flux_ratio",
    "frame_differences",
    "high_frequency_energy",
    "high_frequency_energy_ratio",
    "high_frequency_energy_ratio_map",
    "luminance",
    "peak_signal_to_noise_ratio",
    "relative_difference",
    "relative_mse",
    "signed_difference",
    "stray_flux",
    "structural_similarity",
    "temporal_flicker",
    "tonemap",
    "white_point",
]
