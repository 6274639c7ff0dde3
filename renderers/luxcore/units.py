"""Units check: LuxCore's map of a bare receiver against the analytic point-light answer.

With the objects removed, a plane receiver under a point light of intensity I
[W/sr] gets E = I cos(theta) / r^2. Integrated over a texel that is I times the
texel's solid angle seen from the light, exact for a rectangle whose plane lies at
distance h from the light (corner function, inclusion-exclusion over the corners):

    Omega([x0, x1] x [y0, y1]) = sum over corners of +-atan(x y / (h sqrt(h^2 + x^2 + y^2)))

with (x, y) measured from the light's foot on the plane. So the analytic map is
I Omega_texel / A_texel [W/m^2], with no quadrature error.

Two statistics are compared, each against its own noise from K seeds (standard
error = sample standard deviation / sqrt(K)):

* the flux ratio  sum(E_lux) / sum(E_analytic) over the map: radiometric units
  (the 4 pi of the light's gain, the pi / albedo of the Lambertian read-out);
* the flux centroid (u, v) minus the analytic one, metres: orientation and the
  one-row offset of LuxCore's orthographic light-traced film (a row shift moves it by
  a whole texel, many standard errors).

Both must lie within ``t`` standard errors, t the two-sided Student-t quantile with
K - 1 degrees of freedom at ``alpha``; and the flux ratio's standard error must be
below ``max_noise`` so that a check too noisy to see a unit error cannot pass.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy import stats

from renderers.luxcore.render import render_film, seed_list
from renderers.luxcore.translate import UnsupportedScene, check_supported, receiver_view
from scenes.errors import HarnessError
from scenes.geometry import SceneGeometry, build_geometry
from scenes.model import PlaneReceiver, PointLight, Scene

__all__ = [
    "UnitsCheck",
    "UnitsCheckFailed",
    "analytic_point_irradiance",
    "check_units",
    "require_units",
]


class UnitsCheckFailed(HarnessError, RuntimeError):
    """LuxCore's bare-receiver map disagrees with the analytic irradiance."""


@dataclass(frozen=True)
class UnitsCheck:
    """Outcome of :func:`check_units` for one receiver.

    Attributes
    ----------
    ratio : float
        Flux ratio LuxCore / analytic over the map (dimensionless; 1 is right).
    ratio_noise : float
        Standard error of ``ratio`` from the K seeds.
    centroid_offset : tuple of float
        LuxCore's flux centroid minus the analytic one, (du, dv) in metres.
    centroid_noise : tuple of float
        Standard errors of ``centroid_offset``, metres.
    tolerance : float
        t: the number of standard errors allowed.
    max_noise : float
        Largest ``ratio_noise`` accepted.
    photons, seeds : int
        Light paths per seed, and K.
    passed : bool
        All three conditions hold.
    """

    ratio: float
    ratio_noise: float
    centroid_offset: tuple[float, float]
    centroid_noise: tuple[float, float]
    tolerance: float
    max_noise: float
    photons: int
    seeds: int
    passed: bool

    def describe(self) -> str:
        """One line for logs and error messages."""
        du, dv = self.centroid_offset
        su, sv = self.centroid_noise
        return (f"flux ratio {self.ratio:.5f} ± {self.ratio_noise:.5f} (allowed "
                f"{self.tolerance:.1f} σ, σ ≤ {self.max_noise}); centroid offset "
                f"({du:+.2e} ± {su:.1e}, {dv:+.2e} ± {sv:.1e}) m; K = {self.seeds}, "
                f"{self.photons} photons each")


def analytic_point_irradiance(light: PointLight, receiver: PlaneReceiver, extent,
                              resolution: tuple[int, int]) -> np.ndarray:
    """Texel-averaged irradiance of a bare plane under a point light.

    Returns
    -------
    ndarray, (H, W, 3), float64
        I Omega_texel / A_texel in W/m², row 0 at vmin; zero if the light is behind
        the plane's front side.
    """
    n = np.asarray(receiver.normal, float) / np.linalg.norm(receiver.normal)
    u = np.asarray(receiver.u_axis, float)
    u = u - n * (u @ n)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    rel = np.asarray(light.position, float) - np.asarray(receiver.center, float)
    h = float(rel @ n)
    w, hh = resolution
    if h <= 0:
        return np.zeros((hh, w, 3))
    umin, umax, vmin, vmax = extent
    x = np.linspace(umin, umax, w + 1) - rel @ u
    y = np.linspace(vmin, vmax, hh + 1) - rel @ v
    xx, yy = np.meshgrid(x, y)
    corner = np.arctan(xx * yy / (h * np.sqrt(h * h + xx * xx + yy * yy)))
    omega = corner[1:, 1:] - corner[1:, :-1] - corner[:-1, 1:] + corner[:-1, :-1]
    area = (umax - umin) * (vmax - vmin) / (w * hh)
    return omega[..., None] / area * np.asarray(light.intensity, float)


def _centroid(e: np.ndarray, extent) -> np.ndarray:
    umin, umax, vmin, vmax = extent
    hh, w = e.shape[:2]
    u = umin + (np.arange(w) + 0.5) * (umax - umin) / w
    v = vmin + (np.arange(hh) + 0.5) * (vmax - vmin) / hh
    flux = e.sum(axis=-1)
    total = flux.sum()
    return np.array([(flux.sum(axis=0) @ u) / total, (flux.sum(axis=1) @ v) / total])


def check_units(scene: Scene, *, photons: int = 250_000, seeds: int = 8, receiver: int = 0,
                resolution: tuple[int, int] = (32, 32), alpha: float = 1e-3,
                max_noise: float = 0.005,
                geometry: SceneGeometry | None = None) -> UnitsCheck:
    """Render ``scene.receivers[receiver]`` without objects and compare to the analytic map.

    Parameters
    ----------
    photons
        Light paths per seed.
    seeds
        K >= 2 independent seeds.
    alpha
        Two-sided false-alarm probability of each test.
    max_noise
        Largest standard error of the flux ratio accepted (dimensionless).
    """
    if seeds < 2:
        raise ValueError("the units check needs at least 2 seeds for its noise")
    if not isinstance(scene.light, PointLight):
        raise UnsupportedScene(f"{scene.source}: light.type: the units check needs a point light")
    bare = dataclasses.replace(scene, objects=())
    check_supported(bare)
    geometry = geometry or build_geometry(scene)
    view = receiver_view(bare, receiver, resolution=resolution, geometry=geometry)
    expected = analytic_point_irradiance(scene.light, scene.receivers[receiver], view.extent,
                                         view.resolution)
    lit = np.asarray(scene.light.intensity) > 0
    ratios, offsets = [], []
    for seed in seed_list(seeds):
        got = render_film(bare, view, variant="bare", photons=photons, seed=seed,
                          geometry=geometry).irradiance
        ratios.append(np.mean(got.sum(axis=(0, 1))[lit] / expected.sum(axis=(0, 1))[lit]))
        offsets.append(_centroid(got, view.extent) - _centroid(expected, view.extent))
    ratios, offsets = np.array(ratios), np.array(offsets)
    ratio, ratio_noise = float(ratios.mean()), float(ratios.std(ddof=1) / np.sqrt(seeds))
    offset = offsets.mean(axis=0)
    offset_noise = offsets.std(axis=0, ddof=1) / np.sqrt(seeds)
    t = float(stats.t.ppf(1 - alpha / 2, seeds - 1))
    passed = bool(abs(ratio - 1) <= t * ratio_noise and ratio_noise <= max_noise
                  and np.all(np.abs(offset) <= t * offset_noise))
    return UnitsCheck(ratio, ratio_noise, tuple(offset.tolist()), tuple(offset_noise.tolist()),
                      t, max_noise, photons, seeds, passed)


_PASSED: dict = {}


def require_units(scene: Scene, *, geometry: SceneGeometry | None = None) -> list[UnitsCheck]:
    """Run :func:`check_units` on every receiver (once per light and receivers).

    Raises
    ------
    UnitsCheckFailed
        Any receiver fails; LuxCore's maps are then not to be trusted.
    """
    key = (scene.light, scene.receivers)
    if key not in _PASSED:
        checks = [check_units(scene, receiver=i, geometry=geometry)
                  for i in range(len(scene.receivers))]
        for i, check in enumerate(checks):
            if not check.passed:
                raise UnitsCheckFailed(f"{scene.source}: receivers[{i}]: LuxCore units check "
                                       f"failed: {check.describe()}")
        _PASSED[key] = checks
    return _PASSED[key]
