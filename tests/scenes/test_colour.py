"""Luminance and the tone curve (scenes.colour), the one copy the renderers, the
metrics and the report use, against hand-derived values.

Kind: physical requirements of the definitions (Rec. 709 weights, Reinhard + sRGB),
each value worked out by hand in the test's docstring or comment.
"""

from __future__ import annotations

import numpy as np
import pytest

from scenes.colour import LUMA, luminance, srgb_encode, tonemap, white_point


def test_luminance_weighs_rgb_with_rec_709():
    """Pure red, green and blue give their weights 0.2126, 0.7152, 0.0722; grey of
    value g gives g (the weights sum to 1); a (H, W) map is luminance already."""
    primaries = np.eye(3).reshape(1, 3, 3)
    np.testing.assert_array_equal(luminance(primaries)[0], [0.2126, 0.7152, 0.0722])
    assert luminance(np.full((1, 1, 3), 2.5))[0, 0] == pytest.approx(2.5, rel=1e-15)
    scalar = np.arange(6.0).reshape(2, 3)
    np.testing.assert_array_equal(luminance(scalar), scalar)
    assert LUMA.sum() == pytest.approx(1.0, rel=1e-15)


def test_tone_curve_hand_values():
    """t(x) = srgb(x / (w + x)): at x = w the Reinhard part is 1/2 and
    srgb(1/2) = 1.055 · 0.5^(1/2.4) − 0.055 = 0.735357; at x = 0.002 w it is
    0.002 / 1.002 < 0.0031308, on sRGB's linear segment: 12.92 · 0.002 / 1.002 =
    0.0257884; negative radiance counts as 0; any finite x stays below 1."""
    white = 4.0
    values = np.array([white, 0.002 * white, -1.0, 0.0, 1e12])
    mapped = tonemap(values, white=white)
    np.testing.assert_allclose(mapped[:2], [0.7353569830524495, 0.025788423153692615],
                               rtol=1e-14)
    assert mapped[2] == 0.0 and mapped[3] == 0.0
    assert 0.999 < mapped[4] <= 1.0
    # The sRGB part alone clips to [0, 1] and meets its two segments at 0.0031308.
    np.testing.assert_allclose(srgb_encode(np.array([-0.5, 0.0031308, 2.0])),
                               [0.0, 12.92 * 0.0031308, 1.0], rtol=1e-12)


@pytest.mark.parametrize("white", [0.0, -1.0, float("nan")])
def test_tone_curve_refuses_a_white_that_is_not_positive(white):
    with pytest.raises(ValueError, match="white point must be positive"):
        tonemap(np.ones((2, 2, 3)), white=white)


def test_white_point_is_the_reference_percentile_luminance():
    """Grey values 1 .. 100 (one pixel each): numpy's linear-interpolated 99th
    percentile is 1 + 0.99 · 99 = 99.01; a mask restricts it (the lowest 10 pixels:
    1 + 0.99 · 9 = 9.91); NaN and Inf are left out; an all-black image gives 1.0,
    so the curve stays defined."""
    grey = np.repeat(np.arange(1.0, 101.0).reshape(10, 10, 1), 3, axis=2)
    assert white_point(grey) == pytest.approx(99.01, rel=1e-12)
    mask = np.zeros((10, 10), bool)
    mask[0] = True
    assert white_point(grey, mask=mask) == pytest.approx(9.91, rel=1e-12)
    spoiled = grey.copy()
    spoiled[9, 9] = np.nan
    spoiled[9, 8] = np.inf
    assert white_point(spoiled) == pytest.approx(np.percentile(np.arange(1.0, 99.0), 99))
    assert white_point(np.zeros((4, 4, 3))) == 1.0
