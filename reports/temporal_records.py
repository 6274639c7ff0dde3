"""What the temporal study produced for one scene and method: the record the
report's temporal section and ``temporal.csv`` are made from
(``harness.studies.temporal`` fills it; nothing in here computes).

Formulas (:data:`TEMPORAL_FORMULAS`, shown in ``metrics.json`` and on the page) are
those of ``harness.metrics.temporal``; sequences are receiver irradiance maps in W/m²,
(T, H, W, 3) float32, row 0 at vmin.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from reports.records import Table

__all__ = ["TEMPORAL_FORMULAS", "TemporalComparison"]

#: Human-readable formula of each temporal metric (ε = 0.01, the relMSE's).
TEMPORAL_FORMULAS: dict[str, str] = {
    "flicker": "F = mean over frame pairs t of the mean over pixels and channels of "
               "(ΔM_t − ΔR_t)² / (R̄_t² + ε), ΔI_t = I_t − I_{t−1}, R̄_t = (R_t + R_{t−1}) / 2: "
               "the relMSE of the frame-to-frame differences, normalised by the "
               "reference's level",
    "flicker_noise_floor": "F of an independent reference sequence (disjoint seeds, also "
                           "with common random numbers) against the reference: 2 σ_Δ²",
    "flicker_excess": "F − floor / 2: the flicker against the noise-free reference "
                      "(E[F] = F* + σ_Δ², E[floor] = 2 σ_Δ²)",
    "hf_energy_ratio": "ρ = Σ_x E_M(x) / Σ_x E_R(x), E(x) = Σ_t (Y_{t+1} − 2 Y_t + Y_{t−1})² "
                       "of the luminance Y: temporal high-pass energy, power response "
                       "16 sin⁴(π f / fps)",
    "hf_energy_ratio_noise_corrected": "Σ E_M / (Σ E_R − ½ Σ E_{R−R'}), R' the independent "
                                       "reference: the reference's noise energy removed",
    "hf_energy_ratio_map": "ρ(x) = (E_M(x) + δ) / (E_R(x) + δ), δ = 0.01 mean_x E_R(x); "
                           "shown as log2",
}


@dataclass(frozen=True, eq=False)
class TemporalComparison:
    """One scene's animation, both renderers, compared frame by frame.

    Attributes
    ----------
    view : str
        The view compared: ``receiver0`` (receiver 0's caustic irradiance).
    times : tuple of float
        τ of each frame, seconds after the scene as written.
    fps : float
        Frames per second of the animation.
    method, reference : ndarray, (T, H, W, 3), float32
        The method's and the reference's sequences (W/m², row 0 at vmin).
    table : Table
        One row per frame (``temporal.csv``; columns in
        ``harness.studies.temporal.COLUMNS``).
    summary : dict
        The flicker metrics (``metrics.json``'s ``temporal``): ``flicker`` and
        ``hf_energy_ratio`` per region (``caustic``, ``full``) with their noise floors
        and noise corrections, per-frame means, frame times, the reference's seeds,
        run times, :data:`TEMPORAL_FORMULAS`.
    maps : dict of str to ndarray (H, W)
        ``flicker`` (per-pixel flicker, method), ``flicker_floor`` (the independent
        reference's), ``hf_ratio`` (per-pixel ρ(x)).
    white : float
        Tone-curve white point of the whole sequence (the reference's 99th-percentile
        luminance over every frame), W/m².
    diff_range : float
        Symmetric range of the signed-difference panel, W/m² (99.5th percentile of
        |luminance(M − R)| over every frame).
    files : dict of str to str
        Data files written beside the page: ``table`` (temporal.csv), ``flicker``,
        ``flicker_floor``, ``hf_ratio`` (EXR maps).
    """

    view: str
    times: tuple[float, ...]
    fps: float
    method: np.ndarray
    reference: np.ndarray
    table: Table
    summary: dict[str, Any]
    maps: dict[str, np.ndarray]
    white: float
    diff_range: float
    files: dict[str, str] = field(default_factory=dict)

    @property
    def frames(self) -> int:
        """Number of frames T."""
        return len(self.times)
