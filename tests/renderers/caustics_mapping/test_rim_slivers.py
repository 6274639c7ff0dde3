"""Rim slivers (``splat_kernels.glsl``): the strong preset's triangles near a refracting
object's silhouette left glass_sphere's halo in radial streaks; quads there that are
long slivers go to round Gaussians. Held against the golden reference (64 M photons
at 128², harness.checks.golden) with the excess relMSE estimator
(harness.metrics.excess): the method's error with the reference's noise taken out.
Kind: physical requirement (the reference is ray optics; nothing here is calibrated
on the method's output beyond the stated measurements)."""

from __future__ import annotations

import numpy as np
import pytest

from harness.checks import GOLDEN_DIR
from harness.checks.golden import GOLDEN_SETTINGS, load_golden
from harness.compare.regions import caustic_region
from harness.metrics.excess import excess_relative_mse
from renderers.caustics_mapping import render_frame
from scenes import load_scene, with_settings
from tests.renderers.caustics_mapping.conftest import ROOT

pytestmark = pytest.mark.physical_requirement


def test_the_halo_has_no_streaks(ctx):
    """Over the whole receiver the excess relMSE is at most 4.5e-4 (measured 3.8e-4;
    5.1e-4 with slivers drawn, its 95 % interval [5.11e-4, 5.17e-4]), and the
    caustic region keeps its 1.24e-4 within 1.5e-4 (1.23e-4 before: the slivers lie
    outside it)."""
    golden = load_golden(GOLDEN_DIR, "glass_sphere").receivers[0]
    scene = with_settings(load_scene(ROOT / "scenes" / "glass_sphere.toml"),
                          {"preset": "strong", "receiver_map": [128, 128]})
    method = render_frame(scene, ctx=ctx, lookups=False).result.receivers[0].irradiance
    seeds = GOLDEN_SETTINGS["seeds"]
    full = excess_relative_mse(method, golden.irradiance, golden.variance, seeds=seeds)
    region = caustic_region(golden.irradiance)
    caustic = excess_relative_mse(method, golden.irradiance, golden.variance, seeds=seeds,
                                  mask=region)
    assert full.excess_ci95[1] <= 4.5e-4, full
    assert caustic.excess_ci95[1] <= 1.5e-4, caustic
    assert np.isclose(method.sum(), golden.irradiance.sum(), rtol=2e-3)
