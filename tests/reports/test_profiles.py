"""Line profiles (``reports.profiles``): the pixels of a line, the samples along it,
the caustic's default profile and its CSV, with known answers carried in the tests;
and the default profile a report writes beside each receiver map."""

from __future__ import annotations

import csv
import io

import numpy as np
import pytest

from reports import build_report
from reports.profiles import (
    PROFILE_COLUMNS,
    default_profile,
    line_pixels,
    peak_pixel,
    profile_csv,
    sample_profile,
)
from scenes.colour import LUMA


@pytest.mark.parametrize(("start", "end", "xs", "ys"), [
    ((2, 3), (6, 3), [2, 3, 4, 5, 6], [3, 3, 3, 3, 3]),           # horizontal
    ((1, 4), (1, 1), [1, 1, 1, 1], [4, 3, 2, 1]),                 # vertical, upwards
    ((0, 0), (3, 3), [0, 1, 2, 3], [0, 1, 2, 3]),                 # diagonal
    ((0, 0), (4, 2), [0, 1, 2, 3, 4], [0, 1, 1, 2, 2]),           # y = x / 2, halves up
    ((4, 2), (0, 0), [4, 3, 2, 1, 0], [2, 2, 1, 1, 0]),           # the same line backwards
    ((5, 5), (5, 5), [5], [5]),                                   # one point
])
def test_line_pixels_known_answers(start, end, xs, ys):
    """One sample per column or row of the longer axis, ends included, rounding
    halves up (floor(t + 1/2), as the page's Math.floor(t + 0.5))."""
    x, y = line_pixels(start, end)
    assert x.tolist() == xs and y.tolist() == ys


def test_line_pixels_step_one_pixel_along_the_longer_axis():
    """Steep and shallow lines in every octant: n = max(|dx|, |dy|) + 1 samples, the
    longer axis moves by exactly one pixel per sample, the other by at most one."""
    rng = np.random.default_rng(5)
    for _ in range(200):
        (x0, y0), (x1, y1) = rng.integers(-50, 50, (2, 2))
        x, y = line_pixels((x0, y0), (x1, y1))
        n = max(abs(x1 - x0), abs(y1 - y0)) + 1
        assert len(x) == n and (x[0], y[0], x[-1], y[-1]) == (x0, y0, x1, y1)
        if n > 1:
            steps = np.abs(np.diff(x)), np.abs(np.diff(y))
            major = 0 if abs(x1 - x0) >= abs(y1 - y0) else 1
            assert np.all(steps[major] == 1) and np.all(steps[1 - major] <= 1)


def test_samples_are_the_pixels_and_the_error_is_the_root_of_the_variance():
    """Every sample is the array's value at its pixel (no interpolation); the
    standard error is sqrt(Var); the luminance's error is Σ w_c σ_c."""
    rng = np.random.default_rng(1)
    method = rng.uniform(0, 10, (20, 30, 3)).astype(np.float32)
    reference = rng.uniform(0, 10, (20, 30, 3)).astype(np.float32)
    variance = rng.uniform(0, 0.5, (20, 30, 3)).astype(np.float32)
    p = sample_profile(method, reference, variance, start=(3, 17), end=(25, 2))
    assert len(p.x) == 23
    assert np.array_equal(p.method, method[p.y, p.x])
    assert np.array_equal(p.reference, reference[p.y, p.x])
    assert np.allclose(p.reference_se, np.sqrt(variance[p.y, p.x].astype(np.float64)))
    assert np.allclose(p.method_luminance, method[p.y, p.x] @ LUMA)
    se = np.sqrt(variance[p.y, p.x].astype(np.float64))
    assert np.allclose(p.reference_se_luminance, se[:, 0] * 0.2126 + se[:, 1] * 0.7152
                       + se[:, 2] * 0.0722)


def test_luminance_error_is_exact_for_perfectly_correlated_channels():
    """Channels that are one estimate times fixed colours (a grey light through a
    non-dispersive object) have σ_L = Σ w_c σ_c: checked on 20 000 simulated seeds."""
    rng = np.random.default_rng(2)
    colour = np.array([1.0, 0.8, 0.5])
    seeds = (4.0 + rng.standard_normal(20_000))[:, None] * colour   # (seeds, 3)
    variance = seeds.var(axis=0)
    p = sample_profile(np.zeros((1, 1, 3)), np.zeros((1, 1, 3)), variance[None, None],
                       start=(0, 0), end=(0, 0))
    assert p.reference_se_luminance[0] == pytest.approx((seeds @ LUMA).std(), rel=1e-9)


def test_samples_outside_the_image_are_refused():
    image = np.zeros((4, 5, 3))
    with pytest.raises(ValueError, match="outside the 5×4 image"):
        sample_profile(image, image, start=(0, 0), end=(5, 1))
    with pytest.raises(ValueError, match="shapes differ"):
        sample_profile(image, np.zeros((4, 4, 3)), start=(0, 0), end=(1, 1))


def test_the_default_profile_goes_through_the_caustic_peak():
    """The hottest pixel outside the caustic region (a firefly) is ignored; NaN is
    ignored; the line is horizontal, across the whole map, through the peak."""
    reference = np.full((16, 24, 3), 0.1)
    reference[9, 7] = 5.0         # the caustic's peak
    reference[2, 20] = 50.0       # a firefly outside the region
    reference[10, 8] = np.nan
    mask = np.zeros((16, 24), bool)
    mask[6:13, 4:12] = True
    method = reference * 0.5
    assert peak_pixel(reference, mask=mask) == (7, 9)
    assert peak_pixel(reference) == (20, 2)
    assert peak_pixel(reference, mask=np.zeros_like(mask)) == (20, 2)
    p = default_profile(method, reference, mask=mask)
    assert p.x.tolist() == list(range(24)) and set(p.y.tolist()) == {9}
    assert p.reference_se is None and p.reference_se_luminance is None


def test_csv_restores_the_float32_values():
    """Columns as documented; 9 significant digits give every float32 back exactly;
    without variance the error columns are empty."""
    rng = np.random.default_rng(3)
    method = (10.0 ** rng.uniform(-6, 4, (8, 8, 3))).astype(np.float32)
    reference = (10.0 ** rng.uniform(-6, 4, (8, 8, 3))).astype(np.float32)
    variance = (10.0 ** rng.uniform(-12, 2, (8, 8, 3))).astype(np.float32)
    p = sample_profile(method, reference, variance, start=(0, 7), end=(7, 0))
    rows = list(csv.reader(io.StringIO(profile_csv(p).decode())))
    assert tuple(rows[0]) == PROFILE_COLUMNS
    table = np.array(rows[1:], dtype=np.float64)
    assert table[:, 0].tolist() == list(range(8))
    assert np.array_equal(table[:, 1:3].astype(int), np.stack([p.x, p.y], axis=1))
    assert np.array_equal(table[:, 3:6].astype(np.float32), method[p.y, p.x])
    assert np.array_equal(table[:, 7:10].astype(np.float32), reference[p.y, p.x])
    assert np.allclose(table[:, 11:14], np.sqrt(variance[p.y, p.x].astype(np.float64)),
                       rtol=1e-8)
    assert np.allclose(table[:, 6], p.method_luminance, rtol=1e-8)
    bare = list(csv.reader(io.StringIO(profile_csv(
        sample_profile(method, reference, start=(0, 0), end=(2, 0))).decode())))
    assert all(row[11:] == ["", "", "", ""] for row in bare[1:])


def test_a_report_writes_the_default_profile_of_each_receiver_map(tmp_path, comparison_factory):
    """``profile_<view>.csv`` beside the page: the default profile of the receiver map
    at full resolution, linked from the page; the page's line is the same row shown
    flipped; no profile for the camera."""
    c = comparison_factory(variance=True)
    build_report(tmp_path, [c])
    folder = tmp_path / "glass_sphere-paper"
    assert not (folder / "profile_camera.csv").exists()
    expected = default_profile(c.images["receiver0/method"], c.images["receiver0/reference"],
                               c.images["receiver0/reference_variance"],
                               mask=c.images["receiver0/mask_caustic"])
    assert (folder / "profile_receiver0.csv").read_bytes() == profile_csv(expected)
    html = (folder / "index.html").read_text("utf-8")
    height = c.images["receiver0/reference"].shape[0]
    row = height - 1 - int(expected.y[0])
    assert f'data-profile="0 {row} {len(expected.x) - 1} {row}"' in html
    assert 'href="profile_receiver0.csv" download="profile_receiver0.csv"' in html
