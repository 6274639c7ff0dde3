"""Analytic checks of the photon tracer's receiver maps (expected values in the tests).

Noise model used by every threshold: the maps are means over K seeds; a texel's
standard error comes from the seeds' spread. Where the expected irradiance is the
same function everywhere, the per-texel variances are pooled (mean relative
variance x expected^2), so z-scores are close to normal rather than Student-t
with K - 1 degrees of freedom. "max |z| < 5": for 256 texels the chance that
Gaussian noise alone exceeds 5 sigma somewhere is 256 * 5.7e-7 = 1.5e-4.
"""

from __future__ import annotations

import numpy as np

from renderers.mitsuba.reference import estimate_receivers
from renderers.results import texel_centers
from tests.renderers.mitsuba.scenes import (
    FAR_SPHERE,
    glass_sphere,
    ideal_sphere_paths,
    inradius_deficit,
    make_scene,
)

K = 4
RES = (16, 16)


def _pooled_z(mean, var, expected):
    rel_var = np.mean(var / expected**2)  # pooled relative variance of the mean
    return (mean - expected) / (expected * np.sqrt(rel_var))


def test_directional_light_gives_e0_cos_theta_everywhere():
    """Empty scene (one tiny sphere far away), sun along d: E = E0 cos(theta),
    cos(theta) = |d_z| / |d| on the z-up plane, in every texel and channel."""
    d = np.array([0.3, 0.2, -1.0])
    e0 = np.array([4.0, 5.0, 6.0])
    scene = make_scene(light=f'type = "directional"\ndirection = {d.tolist()}\n'
                             f'irradiance = {e0.tolist()}', objects=FAR_SPHERE)
    est = estimate_receivers(scene, photons=1 << 18, seeds=K, resolution=RES,
                             target_noise=1e-9)
    expected = e0 * abs(d[2]) / np.linalg.norm(d)
    m = est.maps[0]
    z = _pooled_z(m.irradiance, m.variance, expected)
    ratio = m.irradiance.reshape(-1, 3).mean(axis=0) / expected
    print(f"directional: mean E / (E0 cos) = {ratio}, max |z| = {np.abs(z).max():.2f}")
    assert np.abs(z).max() < 5
    # Whole-map mean: its standard error is the per-texel one / sqrt(texels).
    se = np.sqrt(np.mean(m.variance / expected**2, axis=(0, 1)) / (RES[0] * RES[1]))
    assert np.all(np.abs(ratio - 1) < 4 * se)


def test_point_light_gives_i_cos_over_r2():
    """Point light of intensity I at p: E(x) = I cos(theta) / r^2 = I h / r^3, averaged
    over each texel (4 x 4 sub-samples; the curvature inside a texel is far below
    the noise)."""
    p = np.array([0.5, -0.3, 3.0])
    intensity = np.array([10.0, 20.0, 30.0])
    scene = make_scene(light=f'type = "point"\nposition = {p.tolist()}\n'
                             f'intensity = {intensity.tolist()}', objects=FAR_SPHERE)
    est = estimate_receivers(scene, photons=1 << 18, seeds=K, resolution=RES,
                             target_noise=1e-9)
    m = est.maps[0]
    sub = 4
    u, v = texel_centers(m.extent, (RES[1] * sub, RES[0] * sub))
    uu, vv = np.meshgrid(u, v)
    r = np.sqrt((uu - p[0]) ** 2 + (vv - p[1]) ** 2 + p[2] ** 2)
    g = (p[2] / r**3).reshape(RES[1], sub, RES[0], sub).mean(axis=(1, 3))
    expected = g[..., None] * intensity
    z = _pooled_z(m.irradiance, m.variance, expected)
    ratio = m.irradiance.sum(axis=(0, 1)) / expected.sum(axis=(0, 1))
    print(f"point: total E / expected = {ratio}, max |z| = {np.abs(z).max():.2f}")
    assert np.abs(z).max() < 5


def _chain_flux(scene, seeds=K, photons=1 << 18):
    est = estimate_receivers(scene, photons=photons, seeds=seeds, resolution=(64, 64),
                             target_noise=1e-9)
    return est


def test_glass_sphere_flux_is_e0_pi_r2_minus_what_leaves():
    """Sun straight down on a glass sphere (IOR 1.5, R = 1 m, no Fresnel, no
    absorption), 3 x 3 m receiver, no direct light: the L T T D flux on the receiver
    equals E0 pi R^2 times the fraction of ideal-sphere rays that land on it
    (rays deviated past the edge, or upward, leave). Tolerance: 4 standard errors
    of the K-seed total, plus the icosphere's flux deficit bound 1 - (r_in / R)^2
    (its faces lie inside the ideal sphere)."""
    e0 = 10.0
    scene = make_scene(light=f'type = "directional"\ndirection = [0.0, 0.0, -1.0]\n'
                             f'irradiance = [{e0}, {e0}, {e0}]', objects=glass_sphere(),
                       receiver_size=3.0, direct=False)
    est = _chain_flux(scene)
    m = est.maps[0]
    area = m.texel_area()
    flux = m.irradiance[..., 1].sum() * area
    se = np.sqrt(m.variance[..., 1].sum()) * area
    lands, _ = ideal_sphere_paths(1.0, 2.0, 1.5, 1.5)
    expected = e0 * np.pi * lands.mean()
    deficit = inradius_deficit(scene)
    print(f"sphere flux {flux:.4f} W vs expected {expected:.4f} W "
          f"(pi R^2 E0 = {e0 * np.pi:.4f}; leaves {1 - lands.mean():.4f}); "
          f"rel. error {flux / expected - 1:+.5f}, 4 se {4 * se / expected:.5f}, "
          f"tessellation {deficit:.5f}")
    assert 0.01 < 1 - lands.mean() < 0.9  # the check is not vacuous: some flux leaves
    assert abs(flux - expected) < 4 * se + deficit * expected


def test_absorption_scales_each_channel_by_exp_minus_sigma_d():
    """Same photons (same seeds, no random events without Fresnel) through the
    sphere with and without absorption sigma = (0.2, 0.5, 1.0) 1/m: the flux ratio
    per channel equals the landing-ray mean of exp(-sigma * chord), chord =
    2 R cos(theta_t), on the ideal sphere. Tolerance: 4 standard errors of the
    per-seed ratios plus 0.3 % (chord lengths on the icosphere differ from the
    ideal sphere's by O((edge / R)^2) ~ 1e-3)."""
    sigma = np.array([0.2, 0.5, 1.0])
    light = 'type = "directional"\ndirection = [0.0, 0.0, -1.0]\nirradiance = [10.0, 10.0, 10.0]'
    clear = make_scene(light=light, objects=glass_sphere(), receiver_size=3.0, direct=False)
    tinted = make_scene(light=light, objects=glass_sphere(absorption=sigma),
                        receiver_size=3.0, direct=False)
    ratios = []
    for seed in range(K):
        a = estimate_receivers(tinted, photons=1 << 17, seeds=1, seed=seed,
                               resolution=(32, 32), target_noise=1e-9)
        b = estimate_receivers(clear, photons=1 << 17, seeds=1, seed=seed,
                               resolution=(32, 32), target_noise=1e-9)
        ratios.append(a.maps[0].irradiance.sum(axis=(0, 1))
                      / b.maps[0].irradiance.sum(axis=(0, 1)))
    ratios = np.array(ratios)
    measured = ratios.mean(axis=0)
    se = ratios.std(axis=0, ddof=1) / np.sqrt(K)
    lands, chord = ideal_sphere_paths(1.0, 2.0, 1.5, 1.5)
    expected = np.array([np.exp(-s * chord[lands]).mean() for s in sigma])
    print(f"absorption ratio {measured} vs expected {expected}, 4 se {4 * se}")
    assert np.all(np.abs(measured - expected) < 4 * se + 0.003 * expected)
    assert np.all(np.diff(measured) < 0)  # redder light survives: ordering by sigma
