"""The cost study (harness/studies/cost_study.py) end to end on the real photon
tracer, with a stand-in for the real-time renderer: the cost table carries raw and
noise-corrected errors on both sides, and the speedups their intervals."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from harness.studies.cost_study import COLUMNS, cost_study
from harness.studies.timing import OneOffCosts
from renderers.mitsuba.noise import caustic_region
from renderers.mitsuba.photons import PhotonTracer
from scenes import load_scene, with_settings
from tests.conftest import SCENES

PHOTONS = 1 << 18  # per reference seed; the quick curve traces 1/64 .. 1/4 of it
SEEDS = 4


class _Runner:
    """Renders every configuration as the noise-free map's stand-in (the mean of
    the reference's seeds) times a 5 % ripple, in 1 ms warm, 50 ms cold."""

    def __init__(self, scene, image):
        self.scene, self.settings, self.repeats = scene, scene.settings, 1
        self._image = image

    def timed(self, *, clock, **config):
        del clock, config
        receiver = SimpleNamespace(irradiance=self._image)
        return SimpleNamespace(result=SimpleNamespace(receivers=[receiver])), 1e-3

    def one_off(self, *, clock):
        del clock
        return OneOffCosts(build_s=0.04, compile_s=0.009)


def test_cost_table_and_speedups_carry_the_correction_and_intervals():
    scene = with_settings(load_scene(SCENES / "glass_sphere.toml"),
                          {"receiver_map": [64, 64]})
    tracer = PhotonTracer(scene, caustic_only=True)
    maps = np.stack([np.asarray(s.caustic[0] / s.photons, np.float64) for s in (
        tracer.trace(PHOTONS, seed=700 + k) for k in range(SEEDS))])
    reference, variance = maps.mean(0), maps.var(0, ddof=1) / SEEDS
    ripple = 1.0 + 0.05 * np.sin(np.arange(reference.shape[1]) / 3.0)[None, :, None]
    runner = _Runner(scene, reference * ripple)
    outcome = cost_study(runner, reference, caustic_region(reference),
                         reference_photons=PHOTONS, quick=True,
                         reference_variance=variance, reference_seeds=SEEDS)
    assert outcome.table.columns == COLUMNS
    rows = outcome.table.records()
    curve = [r for r in rows if r["series"] == "reference"]
    assert len(curve) == 3
    for r in rows:
        # The noise term is the reference's share of the raw error; the excess
        # interval brackets the excess.
        assert r["noise"] > 0 and r["excess_low"] <= r["excess"] <= r["excess_high"]
    for r in curve:
        assert r["excess"] < r["relmse"]
    warm, cold = outcome.warm, outcome.cold
    assert warm is not None and cold is not None
    assert warm.low <= warm.speedup <= warm.high
    assert math.isfinite(warm.slope) and warm.slope < 0 and warm.slope_stderr > 0
    assert warm.slope == outcome.fit.slope
    # Cold against cold: the reference's one-off seconds on top of its warm time,
    # over the method's 1 ms + 49 ms.
    one_off = outcome.reference.build_s + outcome.reference.compile_s
    assert cold.reference_time == warm.reference_time + one_off
    assert cold.speedup * 0.05 == pytest.approx(warm.reference_time + one_off)
    assert outcome.point == (1e-3, rows[0]["relmse"])
    assert outcome.timing()["method"] == {"build_s": 0.04, "compile_s": 0.009}
