"""score_view pairs each metric with its noise floor, per region."""

from __future__ import annotations

import numpy as np
import pytest

from harness.compare.evaluate import exposure_for, score_view


def test_scores_and_noise_floor():
    """The method image is the reference scaled by 1.2; the independent reference
    differs by small noise. Then the flux ratio is 1.2 and its floor ≈ 1, and every
    error metric is worse than its floor."""
    rng = np.random.default_rng(5)
    y, x = np.mgrid[0:48, 0:48]
    ref = np.repeat((0.1 + 3 * np.exp(-((x - 24) ** 2 + (y - 24) ** 2) / 50.0))[..., None], 3, 2)
    independent = ref * (1 + rng.normal(0, 0.01, ref.shape))
    method = ref * 1.2
    regions = {"full": np.ones((48, 48), bool), "caustic": ref[..., 0] > 0.5,
               "empty": np.zeros((48, 48), bool)}
    values, maps = score_view("receiver0", method, ref, independent, regions=regions,
                              exposure=exposure_for(ref))
    by_key = {(v.region, v.metric): v for v in values}
    # Empty regions are skipped; the caustic region adds the stray flux outside it.
    assert {r for r, _ in by_key} == {"full", "caustic", "outside"}
    assert {m for r, m in by_key if r == "outside"} == {"stray_flux"}
    outside = ~regions["caustic"]
    stray = by_key["outside", "stray_flux"]
    assert stray.pixels == int(outside.sum())
    # Every channel of both maps is the same grey: luminance is the channel's value.
    assert stray.value == pytest.approx(1.2 * ref[outside, 0].sum() / ref[..., 0].sum())
    assert stray.excess == pytest.approx(0.2 * ref[outside, 0].sum() / ref[..., 0].sum())
    assert by_key["caustic", "relmse"].pixels == int(regions["caustic"].sum())
    assert by_key["full", "flux_ratio"].value == pytest.approx(1.2)
    assert by_key["full", "flux_ratio"].noise_floor == pytest.approx(1.0, abs=0.01)
    for metric in ("relmse", "flip"):
        v = by_key["caustic", metric]
        assert v.value > v.noise_floor
    assert by_key["caustic", "ssim"].value < by_key["caustic", "ssim"].noise_floor
    assert set(maps) == {"receiver0/signed", "receiver0/ssim", "receiver0/flip"}
    assert maps["receiver0/flip"].shape == (48, 48)
