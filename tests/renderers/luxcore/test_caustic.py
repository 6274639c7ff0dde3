"""Physical requirement: the glass-minus-black difference is exactly the light that
passed the objects.

Expected value: a "glass" sphere of IOR 1 bends nothing and reflects nothing
(Fresnel F = 0), so the caustic is the direct light the black sphere blocks: the
flux I Omega_sphere of its shadow, Omega_sphere = 2 pi (1 - sqrt(1 - R^2 / d^2))
for a sphere of radius R at distance d from the light (the shadow lies inside
the plane). The icosphere (subdivision 4, vertices on the sphere) subtends ~0.2 %
less; that is far below the tolerance.

Noise model: K seeds; the flux's standard error is the seeds' sample standard
deviation / sqrt(K); |flux / (I Omega) - 1| must stay within t standard errors, t
the two-sided Student-t quantile at 1e-3 with K - 1 degrees of freedom (6.9 for
K = 6). Non-vacuity: the standard error must be below 1.5 %, so a missing or
doubled term (the whole blocked flux) or a normalisation off by the share of
direct light is far outside.
"""

from __future__ import annotations

import numpy as np
from scipy import stats

from renderers.luxcore import render_receiver_caustic
from tests.renderers.luxcore.conftest import make_scene

K = 6
LIGHT = np.array([0.3, -0.2, 4.0])
INTENSITY = 10.0
CENTER, RADIUS = np.array([0.0, 0.0, 1.5]), 0.5
IOR_ONE = f"""
[[objects]]
type = "sphere"
center = {CENTER.tolist()}
radius = {RADIUS}
subdivisions = 4
material = {{ type = "dielectric", ior = 1.0, fresnel = true }}
"""


def test_ior_one_caustic_is_the_blocked_direct_light(luxcore):
    scene = make_scene(light=f'type = "point"\nposition = {LIGHT.tolist()}\n'
                             f"intensity = [{INTENSITY}, {INTENSITY}, {INTENSITY}]",
                       objects=IOR_ONE)
    maps = [render_receiver_caustic(scene, photons=400_000, seeds=[s], resolution=(32, 32),
                                    check_units=False)[0] for s in range(1, K + 1)]
    flux = np.array([m.total_flux()[0] for m in maps])
    d = np.linalg.norm(LIGHT - CENTER)
    expected = INTENSITY * 2 * np.pi * (1 - np.sqrt(1 - RADIUS**2 / d**2))
    ratio = flux.mean() / expected
    se = flux.std(ddof=1) / np.sqrt(K) / expected
    t = stats.t.ppf(1 - 1e-3 / 2, K - 1)
    print(f"IOR 1 caustic / (I Omega) = {ratio:.4f} ± {se:.4f}")
    assert se < 0.015
    assert abs(ratio - 1) < t * se
