"""Temporal metrics (``harness.metrics.temporal``) against answers worked out by hand
from their definitions: a bias that stays put, an error that alternates, a change
the method misses, a sinusoid of known frequency, and Monte Carlo-like noise of known
variance for the noise corrections (tolerances from the number of terms averaged)."""

from __future__ import annotations

import numpy as np
import pytest

from harness.metrics import (
    MetricInputError,
    flicker_map,
    flicker_series,
    frame_differences,
    high_frequency_energy,
    high_frequency_energy_ratio,
    high_frequency_energy_ratio_map,
    relative_mse,
    temporal_flicker,
)

EPS = 0.01  # relMSE's regulariser


def moving_blob(frames: int = 8, size: int = 48, *, speed: float = 1.5) -> np.ndarray:
    """A Gaussian caustic travelling ``speed`` pixels per frame along x over a floor
    of level 1: a (T, H, W, 3) sequence that changes everywhere it passes."""
    y, x = np.mgrid[0:size, 0:size].astype(np.float64)
    out = []
    for t in range(frames):
        blob = 6.0 * np.exp(-((x - 10 - speed * t) ** 2 + (y - size / 2) ** 2) / (2 * 3.0**2))
        out.append(np.repeat((1.0 + blob)[..., None], 3, axis=2))
    return np.stack(out)


def test_identical_sequences_do_not_flicker():
    """M = R: every frame difference agrees, so F = 0, the per-pixel map is 0 and the
    high-frequency energy ratio is exactly 1."""
    reference = moving_blob()
    assert temporal_flicker(reference, reference) == 0.0
    assert not flicker_map(reference, reference).any()
    assert high_frequency_energy_ratio(reference, reference) == 1.0
    np.testing.assert_array_equal(high_frequency_energy_ratio_map(reference, reference), 1.0)


def test_an_error_that_stays_put_is_no_flicker():
    """A bias that is the same in every frame (here +0.3 everywhere) changes no frame
    difference: F = 0 (up to float64 rounding) although each frame's relMSE is
    0.3² / (R² + 0.01) > 0."""
    reference = moving_blob()
    method = reference + 0.3
    assert temporal_flicker(reference, method) == pytest.approx(0.0, abs=1e-25)  # rounding
    assert relative_mse(method[0], reference[0]) > 0.01


def test_an_alternating_error_has_the_hand_computed_flicker():
    """R = 1 everywhere, M_t = R + (−1)^t a: ΔM_t − ΔR_t = ±2a, so
    F_t = (2a)² / (1² + 0.01) for every pair, and the per-pixel map is that too. The
    luminance alternates by ±a, whose second difference is ∓4a: E_M = 16 a² (T − 2)."""
    frames, a = 7, 0.05
    reference = np.ones((frames, 6, 5, 3))
    sign = (-1.0) ** np.arange(frames)
    method = reference + a * sign[:, None, None, None]
    expected = (2 * a) ** 2 / (1.0 + EPS)
    np.testing.assert_allclose(flicker_series(reference, method), expected, rtol=1e-12)
    np.testing.assert_allclose(flicker_map(reference, method), expected, rtol=1e-12)
    np.testing.assert_allclose(high_frequency_energy(method), 16 * a**2 * (frames - 2),
                               rtol=1e-12)
    assert not high_frequency_energy(reference).any()


def test_a_change_the_method_misses_is_flicker_and_steady_change_has_no_hf_energy():
    """R_t = 1 + t / 8 (a steady brightening, exact in binary), M_t = 1 (still):
    ΔM − ΔR = −1/8, so F_t = (1/8)² / (R̄_t² + 0.01) with R̄_t = 1 + (t − ½) / 8. A
    linear change has no second difference: E_R = 0, and the ratio of energies is
    undefined (refused)."""
    frames = 5
    t = np.arange(frames, dtype=np.float64)
    reference = np.ones((frames, 4, 4, 3)) * (1.0 + t / 8)[:, None, None, None]
    method = np.ones_like(reference)
    level = 1.0 + (t[1:] - 0.5) / 8
    np.testing.assert_allclose(flicker_series(reference, method),
                               (1 / 8) ** 2 / (level**2 + EPS), rtol=1e-12)
    np.testing.assert_allclose(high_frequency_energy(reference), 0.0, atol=1e-28)  # rounding
    with pytest.raises(MetricInputError, match="no temporal high-frequency energy"):
        high_frequency_energy_ratio(reference, method)


@pytest.mark.parametrize("cycles_per_frame", [1 / 2, 1 / 4, 1 / 6, 1 / 12])
def test_the_second_difference_is_the_documented_high_pass(cycles_per_frame):
    """For Y_t = cos(2π f t / fps + φ) the discrete identity
    cos(a + b) + cos(a − b) − 2 cos a = −4 sin²(b / 2) cos a gives
    E = 16 sin⁴(π f / fps) Σ_{t=1}^{T−2} Y_t² exactly: the power response of the
    module docstring (16 at the Nyquist rate, 1 at fps / 6)."""
    frames = 40
    t = np.arange(frames)
    y = 2.0 + np.cos(2 * np.pi * cycles_per_frame * t + 0.3)
    sequence = np.repeat(y[:, None, None, None], 3, axis=3) * np.ones((1, 2, 2, 1))
    oscillation = y[1:-1] - 2.0
    expected = 16 * np.sin(np.pi * cycles_per_frame) ** 4 * float((oscillation**2).sum())
    np.testing.assert_allclose(high_frequency_energy(sequence), expected, rtol=1e-9)


def test_the_normaliser_is_the_first_argument_the_reference():
    """scikit-image's order, (reference, method): F is normalised by the reference's
    level. R = 1, M = 3 ± 0.1 alternating: F(R, M) = 0.2² / 1.01, while swapped the
    level is M's (about 3): 0.2² / (3² + 0.01) up to the alternation."""
    reference = np.ones((3, 2, 2, 3))
    method = 3.0 + 0.1 * ((-1.0) ** np.arange(3))[:, None, None, None] * np.ones((3, 2, 2, 3))
    assert temporal_flicker(reference, method) == pytest.approx(0.04 / 1.01, rel=1e-12)
    assert temporal_flicker(method, reference) == pytest.approx(0.04 / (9 + EPS), rel=1e-3)


def test_noise_floor_and_corrections_follow_the_noise_model():
    """Monte Carlo-like noise of 2 % of the level on R and on an independent R'
    (the truth R* a caustic moving 2 px per frame), and a method with a coherent error
    (5 % too bright) plus a flickering one (alternating ±2 % of the level):

    * E[F(R, R')] = 2 σ_Δ² and E[F(R, M)] = F(R*, M) + σ_Δ², so the excess flicker
      F(R, M) − F(R, R') / 2 recovers F(R*, M);
    * the noise-corrected energy ratio Σ E_M / (Σ E_R − ½ Σ E_{R−R'}) recovers
      Σ E_M / Σ E_{R*}, which the raw ratio underestimates (the noise adds energy).

    Tolerances: each flicker averages 7 × 96² × 3 ≈ 190 000 χ²-like terms (relative
    spread about 0.3 %; the normaliser's noise shifts means by about 3 σ² ≈ 0.1 %); the
    corrected energy ratio came out within 1.1 % of the truth over five seeds, so 3 %.
    """
    rng = np.random.default_rng(7)
    truth = moving_blob(frames=8, size=96, speed=2.0)

    def noisy():
        return truth * (1 + 0.02 * rng.standard_normal(truth.shape))

    reference, independent = noisy(), noisy()
    sign = (-1.0) ** np.arange(truth.shape[0])
    method = truth * (1.05 + 0.02 * sign[:, None, None, None])

    true_flicker = temporal_flicker(truth, method)
    floor = temporal_flicker(reference, independent)
    measured = temporal_flicker(reference, method)
    assert floor == pytest.approx(2 * 2 * 0.02**2, rel=0.03)  # 2 σ_Δ², σ_Δ² = 2 (2 %)²
    assert measured - floor / 2 == pytest.approx(true_flicker, rel=0.03)
    assert measured > 1.3 * true_flicker  # the raw value is biased up by the noise

    true_ratio = high_frequency_energy_ratio(truth, method)
    raw = high_frequency_energy_ratio(reference, method)
    corrected = high_frequency_energy_ratio(reference, method, independent=independent)
    assert corrected == pytest.approx(true_ratio, rel=0.03)
    assert raw < 0.95 * true_ratio


def test_masks_select_pixels_per_frame_pair():
    """A static (H, W) mask scores the same pixels in every pair; a (T, H, W) mask
    scores, for pair t, the union of frames t − 1 and t. The error alternates ±a
    in column 0 only, so a pair's F is (2a)²/1.01 times the share of column 0 in its
    mask."""
    frames, a = 4, 0.1
    reference = np.ones((frames, 2, 4, 3))
    method = reference.copy()
    method[:, :, 0] += a * ((-1.0) ** np.arange(frames))[:, None, None]
    full = (2 * a) ** 2 / (1 + EPS)
    column0 = np.zeros((2, 4), bool)
    column0[:, 0] = True
    np.testing.assert_allclose(flicker_series(reference, method, mask=column0), full)
    per_frame = np.zeros((frames, 2, 4), bool)
    per_frame[0, :, 0] = True   # pair 1: columns {0, 1}
    per_frame[1, :, 1] = True   # pair 2: columns {1, 2}
    per_frame[2, :, 2] = True   # pair 3: columns {2, 3}
    per_frame[3, :, 3] = True
    np.testing.assert_allclose(flicker_series(reference, method, mask=per_frame),
                               [full / 2, 0.0, 0.0], atol=1e-15)
    assert temporal_flicker(reference, method) == pytest.approx(full / 4, rel=1e-12)
    assert flicker_map(reference, method).mean() == pytest.approx(full / 4, rel=1e-12)


def test_the_per_pixel_energy_ratio_marks_where_the_method_flickers():
    """The method adds an alternating ±0.5 to one pixel of a moving caustic: there
    ρ(x) > 1 (more energy than the reference); pixels where neither sequence changes
    read exactly 1 (δ regularises them)."""
    reference = moving_blob(frames=6, size=32, speed=1.0)
    method = reference.copy()
    method[:, 5, 28] += 0.5 * ((-1.0) ** np.arange(6))[:, None]
    ratio = high_frequency_energy_ratio_map(reference, method)
    assert ratio[5, 28] > 10
    assert ratio[0, 0] == 1.0
    assert np.allclose(np.delete(ratio.ravel(), 5 * 32 + 28), 1.0)


def test_frame_differences_are_consecutive():
    sequence = np.arange(3 * 2 * 2 * 3, dtype=float).reshape(3, 2, 2, 3) ** 2
    np.testing.assert_array_equal(frame_differences(sequence), sequence[1:] - sequence[:-1])


@pytest.mark.parametrize(("call", "message"), [
    (lambda r, m: temporal_flicker(r, m[:, :-1]), "shapes differ"),
    (lambda r, m: temporal_flicker(r[:1], m[:1]), "at least 2 frames"),
    (lambda r, m: temporal_flicker(r[..., :2], m[..., :2]), r"\(T, H, W, 3\)"),
    (lambda r, m: temporal_flicker(r, np.where(m > 1.5, np.nan, m)), "NaN or Inf"),
    (lambda r, m: temporal_flicker(r, m, epsilon=0.0), "epsilon must be a positive"),
    (lambda r, m: temporal_flicker(r, m, mask=np.ones((3, 3), bool)), "mask shape"),
    (lambda r, m: temporal_flicker(r, m, mask=np.zeros((8, 8), bool)), "selects no pixels"),
    (lambda r, m: high_frequency_energy_ratio(r[:2], m[:2]), "at least 3 frames"),
    (lambda r, m: high_frequency_energy_ratio(r, m, independent=r[:, 1:]), "shapes differ"),
    (lambda r, m: high_frequency_energy_ratio_map(r, m, delta=-1.0), "delta must be"),
])
def test_unusable_input_is_a_metric_error(call, message):
    """Every misuse is a MetricInputError saying what is wrong (no NaN result)."""
    reference = moving_blob(frames=4, size=8)
    with pytest.raises(MetricInputError, match=message):
        call(reference, reference * 1.1)
