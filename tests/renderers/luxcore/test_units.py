"""Physical requirement: LuxCore's bare-plane map is the analytic point-light irradiance.

Expected value: a point light of intensity I at height h over the plane gives
E = I cos(theta) / r^2; averaged over a texel that is I Omega_texel / A_texel
(exact, :func:`renderers.luxcore.units.analytic_point_irradiance`).

Noise model behind every tolerance (measured, not assumed): the map is the mean of
K seeds. A texel counts photons, so its variance is proportional to its mean,
var_t = c E_t; c is pooled from the seeds' per-texel sample variances over all
256 texels (255 (K - 1) degrees of freedom, so c is known to ~4 %) and
z_t = (E_lux - E_t) / sqrt(c E_t) is close to standard normal.
* max |z| < 5: for 256 texels the chance that noise alone exceeds 5 sigma
  somewhere is 256 x 5.7e-7 = 1.5e-4 (the three channels share their photons).
* mean z^2 < 1 + 5 sqrt(2 / 256) = 1.44: chi-square with 256 degrees of freedom
  (mean 1, standard deviation sqrt(2 / 256) = 0.088) at 5 sigma.
* the flux ratio's standard error is the per-texel one summed in quadrature; the
  ratio must lie within 5 of them of 1.
Non-vacuity: the same map shifted by one texel row (the known one-row offset of
LuxCore's orthographic light-traced film) must fail the chi-square bound, and the
noise must be small enough (flux standard error < 0.5 %) to see a 4 pi or pi error.
"""

from __future__ import annotations

import numpy as np
import pytest

from renderers.luxcore.render import render_film
from renderers.luxcore.translate import receiver_view
from renderers.luxcore.units import analytic_point_irradiance, check_units
from tests.renderers.luxcore.conftest import make_scene

K = 6
PHOTONS = 200_000
RES = (16, 16)
LIGHT = 'type = "point"\nposition = [0.7, -0.4, 3.0]\nintensity = [10.0, 20.0, 30.0]'


@pytest.fixture(scope="module")
def bare_maps(luxcore):
    scene = make_scene(light=LIGHT)  # variant "bare" leaves the sphere out
    view = receiver_view(scene, 0, resolution=RES)
    maps = np.stack([render_film(scene, view, variant="bare", photons=PHOTONS, seed=s).irradiance
                     for s in range(1, K + 1)])
    expected = analytic_point_irradiance(scene.light, scene.receivers[0], view.extent, RES)
    return maps, expected


def _z(mean, var_of_mean, expected):
    c = np.mean(var_of_mean / expected)
    return (mean - expected) / np.sqrt(c * expected)


def test_bare_plane_matches_analytic_point_irradiance(bare_maps):
    maps, expected = bare_maps
    mean, var = maps.mean(axis=0), maps.var(axis=0, ddof=1) / K
    z = _z(mean, var, expected)
    ratio = mean.sum(axis=(0, 1)) / expected.sum(axis=(0, 1))
    ratio_se = np.sqrt(var.sum(axis=(0, 1))) / expected.sum(axis=(0, 1))
    print(f"flux ratio {ratio} ± {ratio_se}, max |z| {np.abs(z).max():.2f}, "
          f"mean z² {np.mean(z**2):.3f}")
    assert np.all(ratio_se < 0.005), "too noisy to see a unit error"
    assert np.all(np.abs(ratio - 1) < 5 * ratio_se)
    assert np.abs(z).max() < 5
    assert np.mean(z**2) < 1 + 5 * np.sqrt(2 / z[..., 0].size)


def test_a_one_row_shift_would_be_caught(bare_maps):
    maps, expected = bare_maps
    mean, var = maps.mean(axis=0), maps.var(axis=0, ddof=1) / K
    shifted = _z(mean[1:], var[1:], expected[:-1])
    assert np.mean(shifted**2) > 1 + 5 * np.sqrt(2 / shifted[..., 0].size)


def test_units_check_passes_on_the_bare_plane(luxcore):
    check = check_units(make_scene(light=LIGHT), photons=PHOTONS, seeds=K, resolution=RES)
    print(check.describe())
    assert check.passed
    assert check.ratio_noise < 0.005


def test_units_check_fails_without_the_pi_of_the_lambertian_readout(luxcore, monkeypatch):
    """Non-vacuity: a read-out missing pi (E = L / albedo) must be refused."""
    from renderers.luxcore import units  # noqa: PLC0415

    def without_pi(*args, **kwargs):
        film = render_film(*args, **kwargs)
        return type(film)(film.irradiance / np.pi, film.photons, film.seconds)

    monkeypatch.setattr(units, "render_film", without_pi)
    check = units.check_units(make_scene(light=LIGHT), photons=PHOTONS, seeds=K,
                              resolution=RES)
    assert not check.passed
