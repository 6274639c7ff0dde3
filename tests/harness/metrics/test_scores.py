"""Metric implementations against hand-computed values and known cases: identical
images, a constant offset, a one-pixel shift, noise of known variance."""

from __future__ import annotations

import numpy as np
import pytest

from harness.metrics import (
    MetricInputError,
    absolute_difference,
    false_colour,
    flip_error,
    flux_ratio,
    peak_signal_to_noise_ratio,
    relative_difference,
    relative_mse,
    signed_difference,
    structural_similarity,
    tonemap,
    white_point,
)


@pytest.fixture
def reference():
    """A smooth caustic-like blob on a dim floor, 64x64 RGB, linear units."""
    y, x = np.mgrid[0:64, 0:64]
    blob = 4.0 * np.exp(-((x - 30) ** 2 + (y - 34) ** 2) / (2 * 6.0**2))
    return np.repeat((0.2 + blob)[..., None], 3, axis=2)


def test_identical_images(reference):
    assert relative_mse(reference, reference) == 0.0
    assert peak_signal_to_noise_ratio(reference, reference) == float("inf")
    assert structural_similarity(reference, reference, white=1.0) == pytest.approx(1.0)
    assert flip_error(reference, reference, start_exposure=-3, stop_exposure=2) == 0.0
    assert flux_ratio(reference, reference) == 1.0


def test_constant_offset_hand_computed():
    """ref = 1, method = 1.1: relMSE = 0.1² / (1² + 0.01) = 0.00990099...;
    PSNR = 10 log10(1 / 0.01) = 20 dB; flux ratio 1.1."""
    ref = np.ones((8, 8, 3))
    method = ref + 0.1
    assert relative_mse(method, ref) == pytest.approx(0.01 / 1.01, rel=1e-12)
    assert peak_signal_to_noise_ratio(method, ref) == pytest.approx(20.0, rel=1e-12)
    assert flux_ratio(method, ref) == pytest.approx(1.1, rel=1e-12)
    np.testing.assert_allclose(signed_difference(method, ref), 0.1)
    np.testing.assert_allclose(relative_difference(method, ref), 0.1 / 1.01)


def test_trimmed_relmse_drops_outliers():
    """One firefly of 100 among 10 000 values: trimming 0.1 % (10 values) removes it;
    untrimmed it contributes 100² / 1.01 / 30 000 per channel mean."""
    ref = np.ones((100, 100, 1)).repeat(3, axis=2)
    method = ref.copy()
    method[5, 7, :] = 101.0
    assert relative_mse(method, ref, trim=0.001) == 0.0
    assert relative_mse(method, ref) == pytest.approx(3 * 100.0**2 / 1.01 / 30_000)


def test_one_pixel_shift(reference):
    """A one-pixel shift of the blob: every score moves the right way, and relMSE
    equals the value computed directly from the shifted arrays."""
    shifted = np.roll(reference, 1, axis=1)
    direct = np.mean((shifted - reference) ** 2 / (reference**2 + 0.01))
    assert relative_mse(shifted, reference) == pytest.approx(direct, rel=1e-12)
    white = white_point(reference)
    ssim = structural_similarity(shifted, reference, white=white)
    assert 0.9 < ssim < 1.0
    assert flip_error(shifted, reference, start_exposure=-3, stop_exposure=2) > 0.0
    assert flux_ratio(shifted, reference) == pytest.approx(1.0, rel=1e-12)  # roll keeps energy


def test_noise_of_known_variance():
    """method = ref + N(0, σ²) on ref = 1: E[relMSE] = σ² / 1.01 and
    E[PSNR] = 10 log10(1/σ²). With 3·256² = 196 608 samples the relative standard
    error of the mean of χ²₁ terms is √(2/196 608) = 0.32 %; 2 % is > 6 SE."""
    rng = np.random.default_rng(1234)
    sigma = 0.05
    ref = np.ones((256, 256, 3))
    method = ref + rng.normal(0.0, sigma, ref.shape)
    assert relative_mse(method, ref) == pytest.approx(sigma**2 / 1.01, rel=0.02)
    assert peak_signal_to_noise_ratio(method, ref) == pytest.approx(
        10 * np.log10(1 / sigma**2), abs=0.1)


def test_masks_restrict_the_score(reference):
    """Errors outside the mask do not count."""
    method = reference.copy()
    method[:10] += 5.0
    mask = np.zeros(reference.shape[:2], bool)
    mask[20:] = True
    assert relative_mse(method, reference, mask=mask) == 0.0
    assert relative_mse(method, reference) > 0.0


def test_ssim_uses_tonemapped_images(reference):
    """Scaling both images by 1000 changes nothing when the white point scales too:
    SSIM is computed on tone-mapped values, never on linear HDR."""
    method = reference * 1.2
    a = structural_similarity(method, reference, white=white_point(reference))
    b = structural_similarity(method * 1000, reference * 1000, white=white_point(reference * 1000))
    assert a == pytest.approx(b, abs=1e-9)
    mapped = tonemap(reference * 1e6, white=1.0)
    assert mapped.max() <= 1.0 and mapped.min() >= 0.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"start_exposure": 2, "stop_exposure": -2}, "exceeds stop"),
        ({"start_exposure": float("nan"), "stop_exposure": 1}, "finite"),
    ],
)
def test_flip_rejects_bad_exposures(reference, kwargs, message):
    """flip-evaluator would sys.exit; we raise a typed error first."""
    with pytest.raises(MetricInputError, match=message):
        flip_error(reference, reference, **kwargs)


def test_flip_rejects_negative_hdr(reference):
    with pytest.raises(MetricInputError, match="non-negative"):
        flip_error(reference - 1.0, reference, start_exposure=-1, stop_exposure=1)


@pytest.mark.parametrize("bad", [np.ones((4, 4)), np.full((4, 4, 3), np.nan)])
def test_bad_inputs_are_typed_errors(bad):
    with pytest.raises(MetricInputError):
        relative_mse(bad, np.ones((4, 4, 3)))


def test_false_colour_ends_of_the_scale():
    values = np.array([[-1.0, 0.0, 1.0]])
    rgb = false_colour(values, vmin=-1, vmax=1, colormap="RdBu_r")
    assert rgb.dtype == np.uint8 and rgb.shape == (1, 3, 3)
    assert rgb[0, 0, 2] > rgb[0, 0, 0]  # negative end is blue
    assert rgb[0, 2, 0] > rgb[0, 2, 2]  # positive end is red
    np.testing.assert_array_equal(absolute_difference(values, 0 * values), np.abs(values))
