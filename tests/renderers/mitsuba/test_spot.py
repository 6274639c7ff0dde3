"""The spot light on the reference side, against its analytic falloff.

Definition (Mitsuba 3's ``spot`` emitter, ``falloff_curve`` in
``src/emitters/spot.cpp``; the scene model's ``[light] type = "spot"``): with
theta the angle from the axis, theta_b the beam width and theta_c the cutoff,

    f(theta) = 1                                         theta <= theta_b
             = (theta_c - theta) / (theta_c - theta_b)   theta_b < theta < theta_c
             = 0                                         theta >= theta_c,

linear in the angle; without ``beam_width`` the beam is the whole cone. A spot of
axis intensity I at p lights a point x of a plane with normal n by
E(x) = I f(theta) cos(theta_n) / r^2, r = |x - p|, cos(theta_n) = n . (p - x) / r.

Noise model of the map test: the map is a mean over K independent seeds. A photon
that reaches texel i carries the weight I f / pdf, with the emission pdf constant
over the spot's cone (the light sits inside the receiver's bounding sphere, so the
receiver share is drawn uniformly over the sphere), so the variance of texel i's
estimate is proportional to S_i = the texel's integral of f^2 cos(theta_n) / r^2
(photon counting: var = (1/N) E[w^2] for independent photons; the stratified lanes
lower it, by about a quarter here, without changing its shape much). The constant
is pooled over the lit texels from the K seeds' spread (about 180 texels of 7
degrees of freedom: known to a few per cent), so each texel's z-score is close to
normal. "max |z| < 5": for about 180 texels, Gaussian noise alone exceeds 5 sigma
somewhere with probability 180 x 5.7e-7 = 1e-4.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from renderers.mitsuba import load_mitsuba
from renderers.mitsuba.emission import spot_falloff
from renderers.mitsuba.exporter import emitter_dicts
from renderers.mitsuba.reference import estimate_receivers
from scenes.model import SpotLight
from tests.renderers import spot_profile
from tests.renderers.mitsuba.scenes import FAR_SPHERE, make_scene

K = 8
RES = (24, 24)            # texels over a 6 m plane: 0.25 m each
SIZE = 6.0
SUB = 16                  # sub-samples per texel side for the texel means
POSITION = np.array([0.2, -0.1, 2.0])
AXIS = np.array([0.15, 0.1, -1.0])    # tilted ~10 degrees: falloff angle != incidence
INTENSITY = np.array([10.0, 20.0, 30.0])
CUTOFF, BEAM = 40.0, 20.0


#: The profile of this module's spot (tests/renderers/spot_profile.py).
falloff = functools.partial(spot_profile.falloff, cutoff=CUTOFF, beam=BEAM)
smoothstep_falloff = functools.partial(spot_profile.smoothstep_falloff, cutoff=CUTOFF,
                                       beam=BEAM)


def _spot(**extra) -> SpotLight:
    return SpotLight(position=(0.0, 0.0, 0.0), direction=(0.0, 0.3, -1.0),
                     intensity=(1.0, 2.0, 3.0), **{"cutoff_angle": CUTOFF, **extra})


@pytest.mark.parametrize("beam", [BEAM, None])
def test_falloff_is_mitsubas_spot_emitter(beam):
    """Physical requirement (one light on both Mitsuba paths): the photon tracer's
    falloff (``emission.spot_falloff``) equals Mitsuba's own ``spot`` emitter as the
    exporter configures it for the camera's ptracer, and the analytic f(theta),
    from the axis through the beam edge and the ramp to past the cutoff; with and
    without ``beam_width`` (a hard edge)."""
    mi, dr, _ = load_mitsuba()
    light = _spot(beam_width=beam)
    emitter = mi.load_dict(emitter_dicts(light)["light"])
    axis = np.asarray(light.direction) / np.linalg.norm(light.direction)
    # Directions at angle theta from the axis, in the plane of the axis and x.
    side = np.cross(axis, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    theta = np.concatenate([np.linspace(0.0, 50.0, 101), [BEAM - 1e-3, BEAM + 1e-3]])
    rad = np.radians(theta)
    dirs = np.cos(rad)[:, None] * axis + np.sin(rad)[:, None] * side
    distance = 2.5
    it = dr.zeros(mi.Interaction3f, len(theta))
    it.p = mi.Point3f(*(distance * dirs).T.astype(np.float32))
    _, spectrum = emitter.sample_direction(it, mi.Point2f(0.5, 0.5))
    mitsuba = np.asarray(spectrum).reshape(3, -1).T * distance**2 / np.asarray(light.intensity)
    ours = np.asarray(spot_falloff(dr, mi, light, mi.Float(np.cos(rad).astype(np.float32))))
    expected = falloff(theta, cutoff=CUTOFF, beam=beam if beam is not None else CUTOFF)
    away = np.abs(theta - CUTOFF) > 1e-2  # float32 cannot place the cutoff exactly
    np.testing.assert_allclose(mitsuba[away], np.repeat(expected[away, None], 3, 1), atol=2e-5)
    np.testing.assert_allclose(ours[away], expected[away], atol=2e-5)
    assert ours.dtype == np.float32  # stays in the maps' precision (was promoted to Float64)


def _integrands(x, y):
    """At plane points (x, y) (m): theta (deg) and cos(theta_n) / r^2 (1/m^2)."""
    rel = np.stack([x - POSITION[0], y - POSITION[1], np.full_like(x, -POSITION[2])], -1)
    r = np.linalg.norm(rel, axis=-1)
    axis = AXIS / np.linalg.norm(AXIS)
    theta = np.degrees(np.arccos(np.clip(rel @ axis / r, -1.0, 1.0)))
    return theta, POSITION[2] / r**3          # cos(theta_n) / r^2 on the z = 0 plane


def _texel_means(sub: int, rows=None, cols=None) -> dict[str, np.ndarray]:
    """Means over each texel (midpoint rule, sub x sub points) of E / I, of S, of
    the hard-edge and smoothstep alternatives, and of the beam / ring / beyond
    indicators; all texels, or only those at (rows, cols)."""
    width = SIZE / RES[0]
    if rows is None:
        rows, cols = (a.ravel() for a in np.indices((RES[1], RES[0])))
    offsets = (np.arange(sub) + 0.5) / sub * width
    x = (-SIZE / 2 + cols * width)[:, None, None] + offsets[None, None, :]
    y = (-SIZE / 2 + rows * width)[:, None, None] + offsets[None, :, None]
    x, y = np.broadcast_arrays(x, y)
    theta, geometric = _integrands(x, y)
    f = falloff(theta)
    terms = {"E": f * geometric, "S": f**2 * geometric,
             "hard": np.where(theta < CUTOFF, 1.0, 0.0) * geometric,
             "smooth": smoothstep_falloff(theta) * geometric,
             "beam": theta <= BEAM, "ring": (theta > BEAM) & (theta < CUTOFF),
             "beyond": theta >= CUTOFF}
    return {k: v.mean(axis=(1, 2)) for k, v in terms.items()}


def _expected_map() -> dict[str, np.ndarray]:
    """Texel means, (H, W) (row 0 at vmin, like the maps): E, hard, smooth in W/m^2
    as (H, W, 3); S (the variance shape); the share of each texel's area inside the
    beam, in the ring, beyond the cutoff. Texels the cutoff crosses (f is smooth
    elsewhere) get 256 x 256 points, so a sliver of the cone inside a texel is
    integrated well below the noise."""
    coarse = {k: v.reshape(RES[1], RES[0]) for k, v in _texel_means(SUB).items()}
    rows, cols = np.nonzero((coarse["beyond"] > 0) & (coarse["beyond"] < 1)
                            | (coarse["beam"] > 0) & (coarse["beam"] < 1))
    fine = _texel_means(256, rows, cols)
    for k, v in fine.items():
        coarse[k][rows, cols] = v
    for k in ("E", "hard", "smooth"):
        coarse[k] = coarse[k][..., None] * INTENSITY
    return coarse


def test_irradiance_under_a_spot_is_i_falloff_cos_over_r2():
    """Physical requirement: a tilted spot (beam 20 deg, cutoff 40 deg) over a bare
    6 m plane (one tiny sphere far outside the cone): the photon tracer's map equals
    the texel means of I f(theta) cos(theta_n) / r^2 within noise (module
    docstring: max |z| < 5 over the lit texels, pooled variance), in the beam and in
    the falloff ring alike, with each region's total flux within 4 standard errors
    of the seeds' spread; every texel wholly beyond the cutoff is exactly zero (no
    photon there carries weight). The test can fail: the same map rejects a hard
    edge at the cutoff and pbrt's smoothstep profile by far more than 5 sigma."""
    light = (f'type = "spot"\nposition = {POSITION.tolist()}\ndirection = {AXIS.tolist()}\n'
             f'intensity = {INTENSITY.tolist()}\ncutoff_angle = {CUTOFF}\nbeam_width = {BEAM}')
    scene = make_scene(light=light, objects=FAR_SPHERE, receiver_size=SIZE)
    est = estimate_receivers(scene, photons=1 << 20, seeds=K, resolution=RES,
                             target_noise=1e-9)
    m = est.maps[0]
    assert m.extent == (-SIZE / 2, SIZE / 2, -SIZE / 2, SIZE / 2)
    ref = _expected_map()
    expected = ref["E"]

    dark = ref["beyond"] == 1.0
    assert dark.sum() > 100
    assert np.all(m.irradiance[dark] == 0.0)

    lit = ref["S"] > 0
    # Pooled variance: var_i = c * S_i per channel, c from the seeds (docstring).
    c = np.mean(m.variance[lit] / ref["S"][lit][:, None], axis=0)
    sigma = np.sqrt(c * ref["S"][..., None])

    def max_z(model):
        return float(np.abs((m.irradiance[lit] - model[lit]) / sigma[lit]).max())

    z = max_z(expected)
    beam, ring = ref["beam"] == 1.0, ref["ring"] == 1.0
    ratios = {}
    for name, region in (("beam", beam), ("ring", ring)):
        flux = m.irradiance[region].sum(axis=0)
        se = np.sqrt(m.variance[region].sum(axis=0))
        ratios[name] = (flux / expected[region].sum(axis=0), se / expected[region].sum(axis=0))
    alternatives = {name: max_z(ref[name]) for name in ("hard", "smooth")}
    print(f"spot map: max |z| = {z:.2f} over {lit.sum()} lit texels "
          f"({beam.sum()} in the beam, {ring.sum()} in the ring, {dark.sum()} dark); "
          + "; ".join(f"{n} flux / expected = {r[0].round(5)} (se {r[1].round(5)})"
                      for n, r in ratios.items())
          + f"; alternatives max |z|: {alternatives}")
    assert beam.sum() >= 8 and ring.sum() >= 50  # both regions are tested
    assert z < 5
    for ratio, se in ratios.values():
        assert np.all(np.abs(ratio - 1) < 4 * se)
    assert min(alternatives.values()) > 10
