"""The reference obeys the radiometric contract: its receiver maps hold caustic
irradiance only (the counted chains), never the direct light."""

from __future__ import annotations

import numpy as np
import pytest

from renderers.mitsuba.reference import estimate_receivers, render_reference
from tests.renderers.mitsuba.scenes import make_scene

SPHERE = """
[[objects]]
type = "sphere"
center = [0.0, 0.0, 1.5]
radius = 0.5
material = { type = "dielectric", ior = 1.5 }
"""
LIGHT = 'type = "directional"\ndirection = [0.0, 0.0, -1.0]\nirradiance = [2.0, 2.0, 2.0]'


def test_receiver_maps_are_caustic_only(tmp_path):
    """Directional light E0 = 2 W/m² straight down, direct lighting on. The total map
    carries E0 far from the sphere; the result's receiver map (what is compared)
    carries only the few rim rays that the sphere bends that far (measured
    ≈ 0.005 W/m², below 1 % of E0). The two differ by exactly the direct light:
    total flux − caustic flux = E0 (A − π R²) = 2 (16 − π/4) = 30.43 W, the whole
    shadow lying on the receiver. Same settings and seeds give the same photons in
    both calls, so only the direct light's own Monte Carlo noise remains (≈ 0.3 %
    here; 1 % allowed)."""
    scene = make_scene(light=LIGHT, objects=SPHERE,
                       settings="photons = 200000\nseeds = 2\nspp = 1\nreceiver_map = [32, 32]")
    est = estimate_receivers(scene)
    corner = (slice(0, 4), slice(0, 4))
    assert est.maps[0].irradiance[corner].mean() == pytest.approx(2.0, rel=0.1)
    result = render_reference(scene, cache=tmp_path, progress=False)
    caustic = result.receivers[0]
    assert caustic.irradiance[corner].mean() < 0.01 * 2.0
    assert caustic.variance is not None and np.isfinite(caustic.variance).all()
    direct = est.maps[0].total_flux() - caustic.total_flux()
    print(f"direct flux {direct} W, noise {result.metadata['relative_noise']:.4f}")
    assert direct[0] == pytest.approx(2.0 * (16 - np.pi * 0.25), rel=0.01)
