"""Temporal metrics: how a method's image sequence changes from frame to frame,
against how the reference's changes.

Every function takes ``reference`` and ``method`` (scikit-image's order) as
sequences of T frames, (T, H, W, 3) arrays in the same linear units (W/m² for
receiver maps), and keyword-only options. Frame differences are
ΔI_t = I_t − I_{t−1} for t = 1 … T−1.

Flicker (the relMSE of the frame-to-frame differences)
    F_t = mean over the masked pixels and channels of
    (ΔM_t − ΔR_t)² / (R̄_t² + ε),  with R̄_t = (R_t + R_{t−1}) / 2 and ε = 0.01
    (relMSE's regulariser, in the image's units squared); F = mean over t of F_t
    (each frame pair counts once).

    ΔM_t − ΔR_t = e_t − e_{t−1}, with e_t = M_t − R_t the frame's error: F measures
    how much the error *changes* from one frame to the next. An error that stays put
    (a bias that moves with the scene) is no flicker; an error that jumps between
    frames is, and so is a change the method misses or invents. The normaliser is the
    reference's level R̄_t, not ΔR_t: relMSE's own normaliser ΔR_t² + ε would vanish
    wherever the reference does not change and blow a still pixel's error up, while
    R̄_t² + ε keeps F in relMSE's units (F = 0.01: the frame-to-frame change is wrong by
    10 % of the local level, RMS). Since (a − b)² ≤ 2 a² + 2 b²,
    F_t ≤ 2 (relMSE_t + relMSE_{t−1}) up to the change of normaliser; F much below
    that means the method's error is coherent in time.

    Noise. With a reference R = R* + n (R* noise-free, n its Monte Carlo noise, of
    variance σ_Δ² per frame difference after normalisation) independent of the method,
    E[F(R, M)] = F(R*, M) + σ_Δ², and an independent reference R' (other seeds) gives
    E[F(R, R')] = 2 σ_Δ²: the noise floor. The excess flicker
    F(R, M) − F(R, R') / 2 estimates the flicker against the noise-free reference.

Temporal high-frequency energy
    Per pixel, of the luminance Y (``scenes.colour.luminance``):
    E(x) = Σ_{t=1}^{T−2} (Y_{t+1}(x) − 2 Y_t(x) + Y_{t−1}(x))².
    The second difference is a high-pass filter with power response
    |H(f)|² = 16 sin⁴(π f / fps): zero for a constant pixel and for one that changes
    linearly (steady motion), 1 at f = fps / 6 and 16 at the Nyquist rate fps / 2 (a
    pixel that alternates every frame: flicker).

    Ratio: ρ = Σ_x E_M(x) / Σ_x E_R(x) over the mask (undefined when Σ E_R is no more
    than rounding makes: second differences of 64 float32 ulps of the largest
    luminance, a still or steadily changing reference); per pixel
    ρ(x) = (E_M(x) + δ) / (E_R(x) + δ) with δ = 0.01 · mean_x E_R(x), and at least
    that rounding energy, so pixels where neither sequence changes read 1. ρ > 1: the
    method has more temporal high-frequency energy than the reference (flicker,
    shimmer); ρ < 1: it is steadier than the truth (it misses or smooths real
    changes).

    Noise. E is quadratic, so a noisy reference's is biased up:
    E[E_R] = E_R* + N, and with an independent reference R', E[E_{R − R'}] = 2 N
    (the noises are independent). The noise-corrected ratio is
    Σ E_M / (Σ E_R − ½ Σ E_{R − R'}).

References
----------
Wyman, C., Nichols, G. 2009. Adaptive caustic maps using deferred shading.
Computer Graphics Forum 28(2) (temporal incoherence of caustic-map splats).
"""

from __future__ import annotations

import numpy as np

from harness.metrics.scores import RELMSE_EPSILON, MetricInputError
from scenes.colour import luminance

__all__ = [
    "HF_DELTA_FRACTION",
    "ROUNDING_ULPS",
    "flicker_map",
    "flicker_series",
    "frame_differences",
    "high_frequency_energy",
    "high_frequency_energy_ratio",
    "high_frequency_energy_ratio_map",
    "temporal_flicker",
]

#: δ of the per-pixel high-frequency ratio, as a fraction of the reference's mean energy.
HF_DELTA_FRACTION = 0.01
#: Second differences up to this many float32 ulps of the largest luminance are rounding.
ROUNDING_ULPS = 64


def _sequence(values, name: str, *, min_frames: int = 2) -> np.ndarray:
    values = np.asarray(values, np.float64)
    if values.ndim != 4 or values.shape[3] != 3:
        raise MetricInputError(f"{name}: expected a (T, H, W, 3) sequence, got {values.shape}")
    if values.shape[0] < min_frames:
        raise MetricInputError(f"{name}: needs at least {min_frames} frames, "
                               f"got {values.shape[0]}")
    if not np.isfinite(values).all():
        raise MetricInputError(f"{name}: holds NaN or Inf")
    return values


def _pair(reference, method, *, min_frames: int = 2) -> tuple[np.ndarray, np.ndarray]:
    reference = _sequence(reference, "reference", min_frames=min_frames)
    method = _sequence(method, "method", min_frames=min_frames)
    if reference.shape != method.shape:
        raise MetricInputError(f"shapes differ: reference {reference.shape}, "
                               f"method {method.shape}")
    return reference, method


def _pair_masks(mask, shape: tuple[int, ...]) -> np.ndarray:
    """(T − 1, H, W) masks of the frame pairs: a static (H, W) mask for every pair, or
    per frame (T, H, W), a pair taking the union of its two frames' masks."""
    frames, height, width = shape[:3]
    if mask is None:
        return np.ones((frames - 1, height, width), bool)
    mask = np.asarray(mask, bool)
    if mask.shape == (height, width):
        masks = np.broadcast_to(mask, (frames - 1, height, width))
    elif mask.shape == (frames, height, width):
        masks = mask[1:] | mask[:-1]
    else:
        raise MetricInputError(f"mask shape {mask.shape} matches neither (H, W) = "
                               f"{(height, width)} nor (T, H, W) = {(frames, height, width)}")
    if not masks.any(axis=(1, 2)).all():
        raise MetricInputError("mask selects no pixels in some frame pair")
    return masks


def frame_differences(sequence) -> np.ndarray:
    """ΔI_t = I_t − I_{t−1}, t = 1 … T−1: a (T − 1, H, W, 3) array."""
    return np.diff(_sequence(sequence, "sequence"), axis=0)


def _flicker_terms(reference: np.ndarray, method: np.ndarray, epsilon: float) -> np.ndarray:
    """(ΔM_t − ΔR_t)² / (R̄_t² + ε), (T − 1, H, W, 3)."""
    if not (np.isfinite(epsilon) and epsilon > 0):
        raise MetricInputError(f"epsilon must be a positive number, got {epsilon!r}")
    change_error = np.diff(method - reference, axis=0)  # = ΔM_t − ΔR_t
    level = 0.5 * (reference[1:] + reference[:-1])
    return change_error**2 / (level**2 + epsilon)


def flicker_series(reference, method, *, mask=None,
                   epsilon: float = RELMSE_EPSILON) -> np.ndarray:
    """F_t of each frame pair t = 1 … T−1 (see the module docstring).

    Parameters
    ----------
    reference, method : array_like, (T, H, W, 3)
        Linear sequences of T ≥ 2 frames in the same units.
    mask : array_like of bool, (H, W) or (T, H, W), optional
        Pixels scored: one mask for every frame, or one per frame (a pair scores the
        union of its two frames' masks). Default: every pixel.
    epsilon : float
        Regulariser of the normaliser R̄_t² + ε, in the image's units squared.

    Returns
    -------
    ndarray, (T − 1,)
        Dimensionless, ≥ 0.
    """
    reference, method = _pair(reference, method)
    terms = _flicker_terms(reference, method, epsilon).mean(axis=-1)
    masks = _pair_masks(mask, reference.shape)
    return np.array([float(t[m].mean()) for t, m in zip(terms, masks, strict=True)])


def temporal_flicker(reference, method, *, mask=None, epsilon: float = RELMSE_EPSILON) -> float:
    """Flicker F: the mean over frame pairs of :func:`flicker_series` (dimensionless)."""
    return float(flicker_series(reference, method, mask=mask, epsilon=epsilon).mean())


def flicker_map(reference, method, *, epsilon: float = RELMSE_EPSILON) -> np.ndarray:
    """Per-pixel flicker: the mean over frame pairs and channels of
    (ΔM_t − ΔR_t)² / (R̄_t² + ε), an (H, W) map whose mean is F over every pixel."""
    reference, method = _pair(reference, method)
    return _flicker_terms(reference, method, epsilon).mean(axis=(0, 3))


def high_frequency_energy(sequence) -> np.ndarray:
    """E(x) = Σ_t (Y_{t+1} − 2 Y_t + Y_{t−1})² of the luminance Y, an (H, W) map in
    the image's units squared (T ≥ 3 frames)."""
    y = luminance(_sequence(sequence, "sequence", min_frames=3))
    second = y[2:] - 2.0 * y[1:-1] + y[:-2]
    return (second**2).sum(axis=0)


def high_frequency_energy_ratio(reference, method, *, mask=None, independent=None) -> float:
    """ρ = Σ E_M / Σ E_R over ``mask`` (module docstring); noise-corrected,
    Σ E_M / (Σ E_R − ½ Σ E_{R − R'}), when ``independent`` (R', another reference
    of independent noise) is given.

    Raises
    ------
    MetricInputError
        Bad sequences, an empty mask, or a reference with no high-frequency energy
        (above its noise, when corrected): the ratio is then undefined, as for a still
        scene.
    """
    reference, method = _pair(reference, method, min_frames=3)
    height, width = reference.shape[1:3]
    mask = np.ones((height, width), bool) if mask is None else np.asarray(mask, bool)
    if mask.shape != (height, width):
        raise MetricInputError(f"mask shape {mask.shape} does not match {(height, width)}")
    if not mask.any():
        raise MetricInputError("mask selects no pixels")
    energy_reference = float(high_frequency_energy(reference)[mask].sum())
    if independent is not None:
        other = _sequence(independent, "independent", min_frames=3)
        if other.shape != reference.shape:
            raise MetricInputError(f"shapes differ: reference {reference.shape}, "
                                   f"independent {other.shape}")
        energy_reference -= 0.5 * float(high_frequency_energy(reference - other)[mask].sum())
    if not energy_reference > _rounding_energy(reference, mask):
        raise MetricInputError("the reference has no temporal high-frequency energy"
                               + (" above its noise" if independent is not None else ""))
    return float(high_frequency_energy(method)[mask].sum()) / energy_reference


def _rounding_energy(reference: np.ndarray, mask: np.ndarray) -> float:
    """Σ E over ``mask`` that rounding alone can make: every second difference
    :data:`ROUNDING_ULPS` float32 ulps of the largest luminance (the renderers compute
    in float32; a reference's float atomics sum in any order). A reference at or below
    it has no high-frequency energy: a still or steadily changing sequence."""
    terms = (reference.shape[0] - 2) * int(mask.sum())
    return terms * _rounding_step(reference[:, mask]) ** 2


def _rounding_step(values: np.ndarray) -> float:
    """:data:`ROUNDING_ULPS` float32 ulps of the largest |luminance| of ``values``."""
    scale = float(np.abs(luminance(values)).max()) if values.size else 0.0
    return ROUNDING_ULPS * float(np.finfo(np.float32).eps) * scale


def high_frequency_energy_ratio_map(reference, method, *, delta: float | None = None
                                    ) -> np.ndarray:
    """ρ(x) = (E_M(x) + δ) / (E_R(x) + δ), an (H, W) map; δ defaults to
    :data:`HF_DELTA_FRACTION` × the mean of E_R, and at least the energy of
    :data:`ROUNDING_ULPS` float32 ulps of the largest luminance per second difference
    (1 where neither sequence changes beyond rounding)."""
    reference, method = _pair(reference, method, min_frames=3)
    energy_reference = high_frequency_energy(reference)
    energy_method = high_frequency_energy(method)
    if delta is None:
        rounding = (reference.shape[0] - 2) * _rounding_step(reference) ** 2
        delta = max(HF_DELTA_FRACTION * float(energy_reference.mean()), rounding)
    if not (np.isfinite(delta) and delta >= 0):
        raise MetricInputError(f"delta must be a non-negative number, got {delta!r}")
    if delta == 0:
        # Both energies zero: no change on either side, a ratio of one.
        delta = np.finfo(np.float64).tiny
    return (energy_method + delta) / (energy_reference + delta)
