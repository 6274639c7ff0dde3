"""Photons that leak through a mesh (``renderers.mitsuba.photons.PhotonTracer._leaked``):
the ray cast is not watertight, and a segment through a shared edge or vertex of a
mesh can miss both triangles. Kind: physical requirement on the reference (light
does not pass through an opaque mirror).
"""

from __future__ import annotations

import numpy as np

from renderers.mitsuba import photons
from renderers.mitsuba.reference import estimate_receivers
from scenes import load_scene, with_settings
from tests.conftest import SCENES

#: The shallow bowl (meshes/bowl_shallow.obj, resting on the floor at z = 0): a
#: spherical cap of rim radius 1 m and depth 0.5 m, on the sphere of radius 1.25 m
#: centred 1.25 m above the floor.
CENTRE, RADIUS, RIM = np.array([0.0, 0.0, 1.25]), 1.25, 0.5


def _crosses_cap(origin, direction, length):
    """Whether the segment origin + s direction, s in (1 cm, length), crosses the
    bowl's sphere below its rim (the exact surface the mesh approximates within
    0.6 mm)."""
    oc = origin - CENTRE
    b = oc @ direction
    disc = b * b - (oc @ oc - RADIUS * RADIUS)
    if disc < 0:
        return False
    for s in (-b - np.sqrt(disc), -b + np.sqrt(disc)):
        if 0.01 < s < length and (origin + s * direction)[2] <= RIM:
            return True
    return False


def test_no_photon_reaches_the_floor_through_the_bowl(monkeypatch):
    """Physical requirement: under a 60 deg sun the shallow bowl's one reflection
    leaves the floor dark (its inside reflects upwards and onto itself; its outside is
    not lit). Without the leak test the reference (4 x 2^20 photons, 128² map) put 2
    photons there (6 with 4 x 2^22), each of whose last segments, from the inside
    wall, crosses the cap's exact sphere, under the bowl or through its wall: light
    through a mirror. With it the floor gets none. The deposits are read from the
    tracer itself (every segment it deposits, with its direction and length)."""
    scene = with_settings(
        load_scene(SCENES / "hard" / "concave" / "bowl_shallow_sun60.toml"),
        {"receiver_map": [128, 128]})
    deposits = []
    deposit = photons.PhotonTracer._deposit

    def recording(self, si, d, weight, mask, **kwargs):
        done = deposit(self, si, d, weight, mask, **kwargs)
        kept = np.asarray(done)
        if kwargs["caustic"] is not None and kept.any():
            p, v, t = (np.asarray(x) for x in (si.p, d, si.t))
            deposits.extend((p[:, i] - t[i] * v[:, i], v[:, i], float(t[i]))
                            for i in np.flatnonzero(kept))
        return done

    monkeypatch.setattr(photons.PhotonTracer, "_deposit", recording)
    totals = {}
    for test in (False, True):
        monkeypatch.setattr(photons, "LEAK_TEST", test)
        deposits.clear()
        estimate = estimate_receivers(scene, photons=1 << 20, seeds=4, seed=0,
                                      time_cap=1e-3, caustic_only=True)
        totals[test] = float(sum(m.total_flux() for m in estimate.caustic).sum())
        leaked = [_crosses_cap(o, d, t) for o, d, t in deposits]
        if not test:
            assert len(deposits) > 0 and all(leaked), leaked
    assert totals[False] > 0
    assert totals[True] == 0 and not deposits
