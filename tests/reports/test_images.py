"""Pixel helpers of the report: RGBE packing, downsampling, colour bars, PNG bytes."""

from __future__ import annotations

import io

import numpy as np
from PIL import Image

from harness.metrics import false_colour
from reports import images


def test_rgbe_round_trip_keeps_hdr_values_within_its_precision():
    """Values over twelve orders of magnitude come back within 2⁻⁷ of the pixel's
    largest channel (Ward's RGBE keeps 8 mantissa bits per channel)."""
    rng = np.random.default_rng(3)
    image = (10.0 ** rng.uniform(-6, 6, (32, 48, 1)) * rng.uniform(0, 1, (32, 48, 3)))
    decoded = images.decode_rgbe_stack(images.encode_rgbe_stack(image))
    peak = image.max(axis=-1, keepdims=True)
    assert np.all(np.abs(decoded - image) <= peak * 2.0**-7)


def test_rgbe_black_negative_and_non_finite_become_zero():
    image = np.array([[[0.0, 0.0, 0.0], [-1.0, -2.0, -3.0], [np.nan, np.inf, -np.inf]]])
    stack = images.encode_rgbe_stack(image)
    assert stack.shape == (2, 3, 3) and stack.dtype == np.uint8
    assert np.all(images.decode_rgbe_stack(stack) == 0.0)


def test_rgbe_png_is_rgb_without_alpha():
    """No alpha channel: a canvas premultiplies alpha and would corrupt mantissas."""
    png = images.encode_png(images.encode_rgbe_stack(np.ones((4, 5, 3))))
    decoded = Image.open(io.BytesIO(png))
    assert decoded.mode == "RGB" and decoded.size == (5, 8)


def test_downsample_keeps_the_mean_and_reports_the_factor():
    rng = np.random.default_rng(0)
    image = rng.uniform(0, 100, (600, 300, 3))
    small, factor = images.downsample(image, max_size=256)
    assert factor == 3 and small.shape == (200, 100, 3)
    assert np.isclose(small.mean(), image.mean(), rtol=1e-12)
    same, one = images.downsample(image, max_size=600)
    assert one == 1 and same is image


def test_colour_bar_ends_match_the_map_colours():
    """The bar's left and right columns are the colours of vmin and vmax."""
    png = images.colour_bar_png(kind="signed", vmin=-2.0, vmax=2.0, width=64, height=4)
    bar = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    ends = false_colour(np.array([[-2.0, 2.0]]), vmin=-2.0, vmax=2.0, colormap="RdBu_r")
    assert np.array_equal(bar[0, 0], ends[0, 0]) and np.array_equal(bar[0, -1], ends[0, 1])


def test_signed_rgb_difference_keeps_its_sign_in_false_colour():
    """A positive difference is drawn red and a negative one blue (RdBu_r)."""
    values = np.zeros((1, 2, 3))
    values[0, 0] = 1.0
    values[0, 1] = -1.0
    rgb = np.asarray(Image.open(io.BytesIO(
        images.false_colour_png(values, kind="signed", vmin=-1, vmax=1))).convert("RGB"))
    assert rgb[0, 0, 0] > rgb[0, 0, 2] and rgb[0, 1, 2] > rgb[0, 1, 0]


def test_a_marked_false_colour_map_is_a_lossless_palette_png():
    """Regression lock on the page's weight: a map with clip markers has at most 256
    colours (:data:`reports.display.MARKED_LEVELS` levels and three markers), so it is
    stored as a palette PNG that decodes to exactly the same pixels, in fewer bytes
    than the RGB encoding."""
    rng = np.random.default_rng(5)
    values = rng.normal(0.0, 1.0, (96, 128))
    values[0, 0] = np.nan
    rgb = false_colour(values, vmin=-2.0, vmax=2.0, colormap="coolwarm", mark_clipped=True)
    assert 200 < len(np.unique(rgb.reshape(-1, 3), axis=0)) <= 256
    png = images.encode_png(rgb, palette=True)
    decoded = Image.open(io.BytesIO(png))
    assert decoded.mode == "P"
    assert np.array_equal(np.asarray(decoded.convert("RGB")), rgb)
    assert len(png) < len(images.encode_png(rgb))


def test_an_image_of_many_colours_stays_rgb_under_palette():
    """Physical requirement of the encoding: no colour is ever merged. An image of
    more than 256 colours is written as RGB, pixels unchanged."""
    rgb = np.random.default_rng(6).integers(0, 256, (20, 30, 3), dtype=np.uint8)
    decoded = Image.open(io.BytesIO(images.encode_png(rgb, palette=True)))
    assert decoded.mode == "RGB" and np.array_equal(np.asarray(decoded), rgb)
