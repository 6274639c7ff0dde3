"""Slow: re-render every golden reference on disjoint seeds and check the committed
maps still agree within their combined noise (a change in the photon tracer, the
scene files or Mitsuba would show here). Run with ``tox -e slow``."""

from __future__ import annotations

import numpy as np
import pytest

from harness.checks import GOLDEN_DIR
from harness.checks.golden import GOLDEN_SCENES, golden_scene, load_golden
from renderers.mitsuba.reference import estimate_receivers
from scenes import with_settings
from tests.conftest import SCENES

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("name", GOLDEN_SCENES)
def test_golden_matches_a_fresh_render(name):
    """Per texel z = (fresh − golden) / √(var_fresh + var_golden) over texels with
    light. Both variances are estimated from K = 4 seeds, so z follows Student's t
    with ν ≈ 2(K − 1) = 6 degrees of freedom: E[z²] = ν / (ν − 2) = 1.5 (measured
    1.37 .. 1.53) and P(|z| > 8) = 2e-4. Bounds: mean z² in [0.75, 2.25] (±50 %),
    at most 0.5 % of values beyond |z| = 8."""
    golden = load_golden(GOLDEN_DIR, name)
    scene = golden_scene(SCENES, name)
    fresh = estimate_receivers(with_settings(scene, {"seed": scene.settings.seed + 100}),
                               target_noise=1e-12)
    for old, new in zip(golden.receivers, fresh.caustic, strict=True):
        var = old.variance + new.variance
        lit = var > 0
        z = (new.irradiance - old.irradiance)[lit] / np.sqrt(var[lit])
        mean_z2, tail = float(np.mean(z**2)), float(np.mean(np.abs(z) > 8))
        print(f"{name}: mean z² {mean_z2:.3f}, |z| > 8 in {tail:.2%} of {z.size} values")
        assert 0.75 <= mean_z2 <= 2.25
        assert tail <= 0.005
