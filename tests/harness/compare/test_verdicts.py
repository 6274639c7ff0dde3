"""Verdicts from intervals, end to end through the pipeline, with two test plug-in
methods on the small glass sphere: a "perfect" method (an independent Mitsuba
reference with 64 times the photons, so its own variance is about 1/64 of the
reference's) is not called off, its excess interval containing 0; the same image
× 1.02 is called off, with an excess within 2 standard errors of its exact value.
The reference keeps its 4 per-seed maps, so the intervals carry the photon noise's skew
and its neighbouring texels' covariance (``harness.metrics.excess``).

Kind: physical requirement of the harness's statistics (they must hold for any
method; nothing here is calibrated from a method's output)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.compare.pipeline import CompareOptions, render_references, run_comparison
from harness.metrics import relative_mse
from renderers.mitsuba.reference import render_reference
from scenes import load_scene, parse_override, with_settings
from tests.harness.commands.test_compare import SMALL, _small_scene

#: The reference of the test: 4 seeds (3 degrees of freedom for its variance) of
#: 100,000 photons each on a 64² receiver map (about 170 caustic texels, each with
#: enough photons that the noise is near Gaussian), traced exactly: a noise target
#: out of reach and a time cap already spent stop every reference at its budget.
REFERENCE = {"photons": 100_000, "seeds": 4, "receiver_map": [64, 64],
             "target_noise": 1e-9, "reference_time_cap": 1e-3}
#: The perfect method's photons over the reference's: its variance is 1/64 of the
#: reference's, so its own-noise excess is about baseline / 64, well inside the
#: interval (half-width about 2 baseline sqrt(2 / n) = 0.2 baseline for n = 170).
PERFECT_FACTOR = 64


class FromReference:
    """A test plug-in method: a high-photon Mitsuba reference on other seeds,
    optionally scaled (``scale`` 1.02: a 2 % bias); its camera image is Mitsuba's
    ptracer's (only receiver 0 is judged here)."""

    def __init__(self, *, scale: float, cache: str | None):
        self.scale, self.cache = scale, cache
        self.name = f"reference-x{scale:g}"
        self.description = "a 64x-photon reference on other seeds, scaled"

    def configure(self, scene):
        return scene

    def render(self, scene):
        s = scene.settings
        high = with_settings(scene, {"photons": s.photons * PERFECT_FACTOR,
                                     "seed": s.seed + 100 * s.seeds})
        # Mitsuba's ptracer for its camera: the verdicts here are receiver 0's (the
        # camera tracer's lookup maps would scale with the 64x photons).
        result = render_reference(high, cache=self.cache, progress=False, camera="ptracer")
        return dataclasses.replace(result, receivers=tuple(
            dataclasses.replace(r, irradiance=r.irradiance * self.scale, variance=None,
                                seed_maps=None)
            for r in result.receivers), camera=result.camera * self.scale)


@pytest.fixture(scope="module")
def verdicts(tmp_path_factory):
    """Both plug-ins compared on the small glass sphere (metrics only)."""
    folder = tmp_path_factory.mktemp("verdicts")
    overrides = {**dict(parse_override(v) for v in SMALL[1::2]), **REFERENCE}
    scene = with_settings(load_scene(_small_scene(folder)), overrides)
    options = CompareOptions(studies=("metrics",), quick=True, progress=False)
    references = render_references(scene, options)
    # The per-seed maps reach the scoring (non-vacuity of the photon-noise terms).
    assert references.reference.receivers[0].seed_maps.shape == (4, 64, 64, 3)
    return {scale: run_comparison(scene, FromReference(scale=scale, cache=options.cache),
                                  options=options, references=references)
            for scale in (1.0, 1.02)}


def test_a_perfect_method_is_not_called_off(verdicts):
    """Its excess relMSE interval (receiver 0, caustic region) contains 0, and the
    verdict headline says "not measurably off"."""
    m = verdicts[1.0].metric("receiver0", "caustic", "relmse")
    low, high = m.excess_ci95
    assert low <= 0.0 <= high and not m.distinguishable
    assert m.baseline > 0 and m.value == pytest.approx(m.baseline, rel=0.5)
    (verdict,) = [h for h in verdicts[1.0].headlines if h.kind == "verdict"]
    assert verdict.text.startswith("Not measurably off")


def test_a_two_percent_bias_is_called_off_with_its_exact_excess(verdicts):
    """The same image × 1.02 is measurably off; its excess is within 2 standard errors
    of the exact value, relMSE(1.02 P, P) over the same region with P the perfect
    method's image (its variance, 1/64 of the reference's, is small here)."""
    biased, perfect = verdicts[1.02], verdicts[1.0]
    m = biased.metric("receiver0", "caustic", "relmse")
    assert m.distinguishable and m.excess_ci95[0] > 0
    image = perfect.images["receiver0/method"]
    region = biased.images["receiver0/mask_caustic"]
    exact = relative_mse(1.02 * image, image, mask=region)
    assert abs(m.excess - exact) <= 2 * m.excess_stderr, (m.excess, exact, m.excess_stderr)
    (verdict,) = [h for h in biased.headlines if h.kind == "verdict"]
    assert verdict.text.startswith("Measurably off")


def test_every_metric_says_what_it_estimates(verdicts):
    """metrics.json's names exist for every metric with an estimator, on every view
    and region; a flux ratio 2 % high is called off, its excess within 2 SE of 0.02."""
    c = verdicts[1.02]
    for m in c.metrics:
        if m.metric in ("relmse", "ssim", "flip", "flux_ratio") and m.view.startswith("receiver"):
            assert m.excess is not None and m.excess_ci95 is not None, m
            assert np.isfinite(m.excess_stderr) and m.excess_stderr >= 0, m
    flux = c.metric("receiver0", "full", "flux_ratio")
    assert flux.distinguishable and abs(flux.excess - 0.02) <= 2 * flux.excess_stderr
