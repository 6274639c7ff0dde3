"""A method that writes negative radiance is still compared: it fails the
``non-negative`` physical requirement (radiance is a sum of non-negative terms), and
every metric is scored, HDR-FLIP on a copy of its image clamped at 0 (FLIP is defined
on non-negative images only and used to fail the whole scene), and its page is built.

Kind: physical requirement of the harness (it must hold for any method)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.compare.evaluate import flip_input
from harness.compare.pipeline import (
    CheckOptions,
    CompareOptions,
    render_references,
    run_comparison,
)
from renderers.mitsuba.reference import render_reference
from reports import build_report
from scenes import load_scene, parse_override, with_settings
from tests.harness.commands.test_compare import SMALL, _small_scene

#: The tool's failure this reproduces: 6-9 camera pixels at -4e-5 W m^-2 sr^-1 just
#: inside a spot's cutoff.
NEGATIVE = -4e-5
PIXELS = 8


class WithNegatives:
    """A test plug-in method: the reference on other seeds with ``PIXELS`` camera
    pixels of one row set to ``NEGATIVE`` in every channel."""

    name = "negatives"
    description = "an independent reference with a few negative camera pixels"

    def __init__(self, *, cache: str | None):
        self.cache = cache

    def configure(self, scene):
        return scene

    def render(self, scene):
        s = scene.settings
        result = render_reference(with_settings(scene, {"seed": s.seed + 100 * s.seeds}),
                                  cache=self.cache, progress=False)
        camera = np.array(result.camera, np.float32)
        camera[camera.shape[0] // 2, :PIXELS] = NEGATIVE
        return dataclasses.replace(result, camera=camera, receivers=tuple(
            dataclasses.replace(r, variance=None) for r in result.receivers))


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    """The plug-in compared on the small glass sphere (metrics only, checks on)."""
    folder = tmp_path_factory.mktemp("negatives")
    overrides = dict(parse_override(v) for v in SMALL[1::2])
    scene = with_settings(load_scene(_small_scene(folder)), overrides)
    options = CompareOptions(studies=("metrics",), quick=True, progress=False)
    references = render_references(scene, options)
    comparison = run_comparison(scene, WithNegatives(cache=options.cache), options=options,
                                references=references, checks=CheckOptions())
    return comparison, folder


def test_negative_pixels_fail_the_non_negative_requirement(compared):
    """The check is present, failed, and counts exactly the injected values (8 pixels
    x 3 channels: the reference itself has none)."""
    comparison, _ = compared
    (check,) = [c for c in comparison.checks if c.metric == "non-negative"]
    assert not check.passed
    assert check.value == PIXELS * 3
    assert comparison.stability["min_value"] == pytest.approx(NEGATIVE)


def test_flip_is_scored_on_the_clamped_image_and_the_page_is_built(compared):
    """The camera's FLIP is a finite number (not NaN: the scene is not failed), and
    the page and metrics exist."""
    comparison, folder = compared
    flip = comparison.metric("camera", "full", "flip")
    assert math.isfinite(flip.value), flip
    assert math.isfinite(comparison.metric("camera", "full", "relmse").value)
    out = folder / "report"
    build_report(out, [comparison])
    assert any(p.name == "index.html" for p in out.rglob("*.html"))
    assert len(list(out.rglob("*.html"))) >= 2


def test_flip_input_clamps_only_an_image_with_negatives():
    """A non-negative image is passed as is; one with negatives is copied, clamped at
    0, and the caller's array is not changed."""
    image = np.full((4, 4, 3), 0.5, np.float32)
    assert flip_input(image) is image
    image[0, 0] = NEGATIVE
    clamped = flip_input(image)
    assert clamped.min() == 0.0 and image.min() == np.float32(NEGATIVE)
