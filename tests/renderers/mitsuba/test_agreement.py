"""The photon tracer's receiver map and an independent ptracer render agree on
glass_sphere, pixel by pixel, within their combined noise.

The ptracer camera is a perspective pinhole 0.3 m above the floor, looking straight
down at the caustic, below the sphere (which it therefore does not see and which
does not occlude it). A pinhole parallel to a plane maps pixels to a regular grid
of equal floor rectangles, so pixel (row, col) covers exactly texel
(H - 1 - row, col) of a photon map over the same window (image row 0 is +v).
With a box filter the pixel value is the mean radiance L over that rectangle,
and a Lambertian receiver's irradiance is E = pi L / albedo.

Statistic (like Mitsuba's own render tests): a per-pixel Welch t-test between the
two K-seed means, p-values Bonferroni-corrected, the test fails if any p < 0.01 /
pixels. The mean squared z over all pixels is printed too (about 1 when the two
agree within noise).
"""

from __future__ import annotations

import numpy as np
from scipy import stats

from renderers.mitsuba import load_mitsuba
from renderers.mitsuba.camera import render_camera
from renderers.mitsuba.noise import seed_statistics
from renderers.mitsuba.reference import estimate_receivers
from scenes import load_scene

K = 8            # seeds per side: Welch dof ~ 2(K - 1) keeps the t tails moderate
WIDTH = 16       # pixels = texels per side
HEIGHT_M = 0.3   # camera height above the floor (sphere bottom is at 1.0 m)
SPP = 20_000     # ptracer particles per pixel per seed (5.1 M particles)
PHOTONS = 1 << 18
ALPHA = 0.01     # family-wise false-alarm rate


def test_photon_map_matches_ptracer_on_glass_sphere(request):
    mi, _, _ = load_mitsuba()
    scene = load_scene(request.config.rootpath / "scenes" / "glass_sphere.toml")
    # Centre near the focus, offset so the window is not symmetric (a flip fails).
    cx, cy = -0.38, 0.31
    half = HEIGHT_M * np.tan(np.radians(45.0))
    sensor = {
        "type": "perspective", "fov": 90.0, "fov_axis": "x",
        "to_world": mi.ScalarTransform4f().look_at(
            origin=[cx, cy, HEIGHT_M], target=[cx, cy, 0.0], up=[0.0, 1.0, 0.0]),
        "sampler": {"type": "independent"},
        "film": {"type": "hdrfilm", "width": WIDTH, "height": WIDTH,
                 "rfilter": {"type": "box"}, "pixel_format": "rgb", "sample_border": False},
    }
    albedo = scene.receivers[0].albedo[0]
    frames = [np.pi / albedo * np.flipud(render_camera(scene, spp=SPP, seed=s, sensor=sensor))
              for s in range(K)]
    cam_mean, cam_var = seed_statistics(np.stack(frames))
    est = estimate_receivers(scene, photons=PHOTONS, seeds=K, resolution=(WIDTH, WIDTH),
                             extents=[(cx - half, cx + half, cy - half, cy + half)],
                             target_noise=1e-9)
    map_mean, map_var = est.maps[0].irradiance, est.maps[0].variance
    # One channel suffices: the scene is grey (the three are the same photons).
    a, va, b, vb = cam_mean[..., 1], cam_var[..., 1], map_mean[..., 1], map_var[..., 1]
    valid = (va + vb) > 0
    z = (a - b)[valid] / np.sqrt((va + vb)[valid])
    dof = (va + vb) ** 2 / (va**2 / (K - 1) + vb**2 / (K - 1) + 1e-300)
    p = 2 * stats.t.sf(np.abs(z), dof[valid])
    n = valid.sum()
    print(f"photon map vs ptracer: {n} pixels, mean z^2 = {np.mean(z**2):.3f}, "
          f"max |z| = {np.abs(z).max():.2f}, min p = {p.min():.2e} "
          f"(threshold {ALPHA / n:.2e}), peak E {b.max():.1f} vs {a.max():.1f} W/m^2")
    assert n > 0.9 * WIDTH * WIDTH
    assert p.min() > ALPHA / n
    # Not vacuous: the window holds a real caustic (peak well above the mean).
    assert b.max() > 10 * np.median(b)
