"""The halo of glass_sphere's caustic: the strong preset's triangles near a refracting
object's silhouette left it in radial streaks; quads there that are long slivers go
to round Gaussians (``splat_kernels.glsl``), and the quads at the silhouette are
traced again as rim patches (``rim_patches.glsl``). Held against the golden
reference (64 M photons at 128², harness.checks.golden) and, in a slow test, against
a reference at the scene's bundled settings, with the excess relMSE estimator
(harness.metrics.excess): the method's error with the reference's noise taken out.
Kind: physical requirement unless marked (the reference is ray optics; nothing here
is calibrated on the method's output beyond the stated measurements)."""

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


@pytest.fixture
def glass_sphere(ctx):
    """(method map, golden irradiance, full-map excess, caustic-region excess) of
    glass_sphere under the strong preset at the golden settings (128² receiver)."""
    golden = load_golden(GOLDEN_DIR, "glass_sphere").receivers[0]
    scene = with_settings(load_scene(ROOT / "scenes" / "glass_sphere.toml"),
                          {"preset": "strong", "receiver_map": [128, 128]})
    method = render_frame(scene, ctx=ctx, lookups=False).result.receivers[0].irradiance
    seeds = GOLDEN_SETTINGS["seeds"]
    full = excess_relative_mse(method, golden.irradiance, golden.variance, seeds=seeds)
    caustic = excess_relative_mse(method, golden.irradiance, golden.variance, seeds=seeds,
                                  mask=caustic_region(golden.irradiance))
    return method, golden.irradiance, full, caustic


def test_the_halo_has_no_streaks(glass_sphere):
    """Over the whole receiver the excess relMSE is at most 4.5e-4 (measured 3.8e-4
    with constant triangles, 2.8e-4 with linear ones; 5.1e-4 with slivers drawn, its
    95 % interval [5.11e-4, 5.17e-4]), and the flux is kept."""
    method, golden, full, _ = glass_sphere
    assert full.excess_ci95[1] <= 4.5e-4, full
    assert np.isclose(method.sum(), golden.sum(), rtol=2e-3)


@pytest.mark.method_target
def test_rim_patches_take_the_halos_error_away(glass_sphere):
    """Method target: the whole receiver's excess relMSE at most 2e-4, its whole 95 %
    interval, where the grid alone (``rim_patches = 1``) measures 2.79e-4 [2.77e-4,
    2.82e-4]: the patches take at least 28 % of the halo's error away (measured 1.43e-4
    [1.41e-4, 1.44e-4], 49 %)."""
    _, _, full, _ = glass_sphere
    assert full.excess_ci95[1] <= 2e-4, full


@pytest.mark.slow
@pytest.mark.method_target
def test_glass_sphere_meets_the_whole_receiver_bound(tmp_path):
    """Method target at the scene's bundled settings (256² receiver map, its own
    photon budget, a reference rendered here): excess relMSE at most 3e-4 over the
    whole receiver and at most 1e-4 over the caustic region, each whole 95 %
    interval (measured against the cached reference of the same budget: 2.36e-4
    [2.31e-4, 2.40e-4] and 5.8e-5 [4.9e-5, 6.7e-5]; 5.61e-4 and 4.8e-5 without rim
    patches)."""
    from renderers.mitsuba.reference import render_reference  # noqa: PLC0415 - slow only

    scene = with_settings(load_scene(ROOT / "scenes" / "glass_sphere.toml"),
                          {"preset": "strong"})
    reference = render_reference(scene, cache=tmp_path, progress=False).receivers[0]
    method = render_frame(scene, lookups=False).result.receivers[0].irradiance
    seeds = scene.settings.seeds
    full = excess_relative_mse(method, reference.irradiance, reference.variance, seeds=seeds)
    caustic = excess_relative_mse(method, reference.irradiance, reference.variance,
                                  seeds=seeds, mask=caustic_region(reference.irradiance))
    assert full.excess_ci95[1] <= 3e-4, full
    assert caustic.excess_ci95[1] <= 1e-4, caustic


@pytest.mark.method_target
def test_linear_triangles_reach_the_caustic_target(glass_sphere):
    """Method target of the strong preset: glass_sphere's caustic-region excess
    relMSE at most 1e-4, its whole 95 % interval. Constant triangles gave 1.24e-4
    here (4.1e-4 at the bundled 256² map): a sawtooth of one grid cell's period that
    the texels sampled into moiré; triangles whose irradiance is linear between
    their corners' estimates give 2.5e-5 (5.2e-5 at 256²)."""
    _, _, _, caustic = glass_sphere
    assert caustic.excess_ci95[1] <= 1e-4, caustic
