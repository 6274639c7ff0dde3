"""The reference camera tracer (renderers/mitsuba/camera_trace.py) against ptracer,
exact ray geometry and radiometry.

Noise model used by the z-tests: a camera image is the mean of K seeds, and its
variance is the variance of the mean (s^2 / K, K - 1 degrees of freedom). The
Welch statistic z = (a - b) / sqrt(var_a + var_b) of two independent estimates of
the same expectation is then close to Student's t with the Welch-Satterthwaite
degrees of freedom nu = (var_a + var_b)^2 / (var_a^2 / (K_a - 1) + var_b^2 /
(K_b - 1)), so E[z^2] = nu / (nu - 2) and Var[z^2] = 2 nu^2 (nu - 1) / ((nu - 2)^2
(nu - 4)) (for nu > 4). Over N pixels with independent noise, the mean z^2 has that
expectation averaged over the pixels and a standard deviation sqrt(mean Var / N);
the tests allow 4 of those standard deviations (a false alarm rate of about 6e-5
for a normal mean). Where a comparison fails, its images are written as EXRs to
``$CAUSTICS_FAILURE_DIR`` (else pytest's temporary folder) and named in the message.

Scenes are the bundled ones with a smaller camera (and fewer photons, samples and
seeds than their settings), so each test runs in well under a minute.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from scipy.ndimage import binary_dilation

from harness.checks.sphere_camera import (
    BLACK_LEVEL,
    analytic_sphere_camera,
    black_fraction,
    luminance,
)
from renderers.exr import write_exr
from renderers.mitsuba.camera import render_camera
from renderers.mitsuba.camera_trace import CameraTracer, render_traced_camera
from renderers.mitsuba.noise import seed_statistics
from renderers.mitsuba.reference import estimate_receivers
from scenes import load_scene
from scenes.camera import pinhole_directions
from scenes.model import DielectricMaterial

SCENES = Path(__file__).resolve().parents[3] / "scenes"
ALPHA = 0.01  # family-wise false-alarm rate of the per-pixel Welch tests


def _scene(name: str, resolution: int, **material):
    """Bundled scene ``name`` with a ``resolution``^2 camera (and, if given, its first
    object's dielectric material fields replaced)."""
    scene = load_scene(SCENES / f"{name}.toml")
    scene = dataclasses.replace(scene, camera=dataclasses.replace(
        scene.camera, resolution=(resolution, resolution)))
    if material:
        obj = scene.objects[0]
        new = dataclasses.replace(obj, material=dataclasses.replace(obj.material, **material))
        scene = dataclasses.replace(scene, objects=(new, *scene.objects[1:]))
    return scene


def _require(ok: bool, message: str, tmp_path: Path, name: str, **images) -> None:
    """Fail with ``message`` unless ``ok``, after writing ``images`` ((H, W) or
    (H, W, 3) arrays) as EXRs a developer can inspect; the message names the folder."""
    if ok:
        return
    folder = Path(os.environ.get("CAUSTICS_FAILURE_DIR") or tmp_path) / name
    folder.mkdir(parents=True, exist_ok=True)
    for label, image in images.items():
        rgb = np.asarray(image, dtype=np.float32)
        if rgb.ndim == 2:
            rgb = np.repeat(rgb[..., None], 3, axis=-1)
        write_exr(folder / f"{label}.exr", {"RGB": rgb})
    pytest.fail(f"{message}; images: {folder}")


def _welch(a, va, b, vb, *, seeds: tuple[int, int]):
    """Welch z of estimates ``a`` and ``b`` (variances of the mean ``va``, ``vb``, from
    ``seeds`` = (K_a, K_b) seeds), its degrees of freedom, and the expectation and
    variance of z^2 per pixel (module docstring). Pixels without noise give NaN."""
    ka, kb = seeds
    var = va + vb
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (a - b) / np.sqrt(var)
        nu = var**2 / (va**2 / (ka - 1) + vb**2 / (kb - 1))
    mean_z2 = nu / (nu - 2)
    var_z2 = 2 * nu**2 * (nu - 1) / ((nu - 2) ** 2 * (nu - 4))
    return z, nu, mean_z2, var_z2


# ------------------------------------------------------------------- ptracer agreement

FLOOR_RES = 64          # camera pixels per side
PT_SEEDS, PT_SPP = 32, 256      # ptracer: 32 seeds (31 dof) of 256 particles per pixel
TRACE_SEEDS, TRACE_SPP = 8, 16
LOOKUP_PHOTONS = 1 << 20        # lookup-map photons per seed (the tracer's noise is far
                                # below ptracer's either way)
LOOKUP_BIAS = 0.05              # allowance on the mean z^2 (see the test's docstring)


@pytest.mark.physical_requirement
def test_floor_seen_directly_matches_ptracer(tmp_path, record_property):
    """Physical requirement, glass_sphere (64^2 camera): on the floor seen directly,
    where ptracer is right (light L D E and caustic L T T D E paths, connected to the
    pinhole), the camera tracer agrees with it per pixel within the two renders'
    noise. Pixels: every subpixel ray of the exact sphere camera
    (harness/checks/sphere_camera.py) sees the floor, at least 2 pixels from the
    sphere's silhouette (the icosphere's outline differs from the ideal sphere's by
    under a pixel) and from the shadow's edge.

    Statistic: per-pixel Welch z on one channel (the scene is grey: the channels are
    the same samples). (1) Bonferroni: every two-sided p-value above 0.01 / N. (2)
    The mean z^2 within 4 standard deviations of its expectation (module docstring;
    ptracer's 31 dof dominate: E[z^2] ~ 1.07), plus LOOKUP_BIAS for the lookup
    map's blur: its texels are 3.1 cm and the pixels cover 10 to 24 cm of floor
    here, so the blur is mostly below the pixels' own averaging; measured with 6
    seeds of 4 M photons (256^2) and 16 M (1024^2) against one ptracer render, a
    1024^2 lookup instead of the 256^2 one lowers the mean z^2 from 1.16 to 1.11,
    noise of the lookups included: 0.05 is allowed for it."""
    scene = _scene("glass_sphere", FLOOR_RES)
    traced = render_traced_camera(scene, photons=LOOKUP_PHOTONS, spp=TRACE_SPP,
                                  seeds=TRACE_SEEDS, seed=100)
    frames = [render_camera(scene, spp=PT_SPP, seed=1000 + i) for i in range(PT_SEEDS)]
    pt_mean, pt_var = seed_statistics(np.stack(frames))
    exact = analytic_sphere_camera(scene, supersample=4)
    # Shadow fraction of each pixel (direct light only, with and without shadows).
    unshadowed = analytic_sphere_camera(dataclasses.replace(
        scene, info=dataclasses.replace(scene.info, shadows=False)), supersample=4)
    lit = np.divide(luminance(exact.image), luminance(unshadowed.image),
                    out=np.zeros(exact.floor.shape), where=luminance(unshadowed.image) > 0)
    edge = (lit > 1e-6) & (lit < 1 - 1e-6)
    pixels = exact.floor & ~binary_dilation(exact.sphere | edge, iterations=2)
    a, va = traced.image[..., 1][pixels], traced.variance[..., 1][pixels]
    b, vb = pt_mean[..., 1][pixels], pt_var[..., 1][pixels]
    z, nu, mean_z2, var_z2 = _welch(a, va, b, vb, seeds=(TRACE_SEEDS, PT_SEEDS))
    n = z.size
    p = 2 * stats.t.sf(np.abs(z), nu)
    expected, sd = mean_z2.mean(), np.sqrt(var_z2.mean() / n)
    caustic_only = int(np.sum((lit[pixels] < 1e-6) & (a > 0)))
    print(f"floor vs ptracer: {n} pixels ({caustic_only} lit by the caustic alone), "
          f"mean z^2 = {np.mean(z**2):.3f} (expected {expected:.3f} +- {sd:.3f}), "
          f"max |z| = {np.abs(z).max():.2f}, min p = {p.min():.1e} (threshold "
          f"{ALPHA / n:.1e}), mean radiance {a.mean():.4f} vs {b.mean():.4f}")
    record_property("checks", 2)
    assert n > 1500 and caustic_only > 20, "the compared floor must hold the caustic"
    zmap = np.zeros(pixels.shape)
    zmap[pixels] = z
    images = {"trace": traced.image, "ptracer": pt_mean, "z": zmap}
    _require(p.min() > ALPHA / n, "a floor pixel differs from ptracer beyond noise",
             tmp_path, "camera-trace-floor", **images)
    _require(abs(np.mean(z**2) - expected) < 4 * sd + LOOKUP_BIAS,
             "mean z^2 against ptracer is off", tmp_path, "camera-trace-floor", **images)


# ------------------------------------------------------------ seen through the sphere

SPHERE_RES = 96


def _caustic_map(scene, photons=1 << 20, seeds=4):
    """The reference's caustic receiver map of ``scene`` (receiver 0)."""
    return estimate_receivers(scene, photons=photons, seeds=seeds, caustic_only=True,
                              target_noise=1e-9).caustic[0]


@pytest.mark.physical_requirement
@pytest.mark.parametrize("fresnel", [False, True], ids=["no_fresnel", "fresnel"])
def test_sphere_shows_the_refracted_floor_and_caustic(fresnel, tmp_path, record_property):
    """Physical requirement, glass_sphere (96^2 camera), as given and with the
    ``fresnel`` effect: seen through the sphere, the camera shows the floor by two
    refractions, with the caustic, as the exact ray geometry of
    harness/checks/sphere_camera.py does (ideal sphere, the same caustic map looked
    up bilinearly, 4 x 4 stratum centres per pixel; with Fresnel each interface
    transmits 1 - F, the chain the photon tracer counts).

    (1) Black fraction of the sphere's interior pixels (rays that leave for the sky
    after the second refraction; ``sphere_camera.black_fraction``): within 0.05 of
    the exact one (harness/checks/camera.py's bound; about 41 % of the pixels are black, which the
    method's single refraction to a plane does not reproduce). (2) Mean radiance over
    the interior within 2 % of the exact one (measured 0.3 %: the icosphere's
    facets and interpolated normals against the ideal sphere, and the lookup maps'
    own noise; with Fresnel, 0.3 % as well, against a Fresnel loss of 12 %).
    (3) Not vacuous: the caustic is seen through the sphere -- some
    interior pixels that the exact image without the caustic (direct light only)
    shows black, seeing the floor in the sphere's shadow, are lit."""
    scene = _scene("glass_sphere", SPHERE_RES, **({"fresnel": True} if fresnel else {}))
    traced = render_traced_camera(scene, photons=LOOKUP_PHOTONS, spp=16, seeds=4, seed=7)
    exact = analytic_sphere_camera(scene, _caustic_map(scene), supersample=4)
    direct_only = analytic_sphere_camera(scene, supersample=4)
    interior = exact.interior
    black = black_fraction(traced.image, interior)
    lum, lum_exact = luminance(traced.image)[interior], luminance(exact.image)[interior]
    ratio = lum.mean() / lum_exact.mean()
    level = BLACK_LEVEL * np.percentile(luminance(traced.image), 99)
    shadowed = luminance(direct_only.image)[interior] <= level
    caustic_seen = int(np.sum(shadowed & (lum > level)))
    print(f"sphere ({interior.sum()} interior pixels): black fraction {black:.4f} vs exact "
          f"{exact.black_fraction:.4f}; mean radiance ratio {ratio:.4f}; {caustic_seen} "
          f"pixels (exact {int(np.sum(shadowed & (lum_exact > level)))}) show the caustic "
          "in the sphere's shadow")
    record_property("checks", 3)
    images = {"trace": traced.image, "exact": exact.image}
    _require(abs(black - exact.black_fraction) < 0.05, "black fraction off", tmp_path,
             "camera-trace-sphere", **images)
    _require(abs(ratio - 1) < 0.02, "radiance through the sphere off", tmp_path,
             "camera-trace-sphere", **images)
    assert caustic_seen > 5, "the caustic is not seen through the sphere"


# ------------------------------------------------------------------ through the water


def _plane_hits(o, d, z, half):
    """Points where rays (o, d) cross the plane at height ``z``, and whether they do so
    forward within |x|, |y| <= ``half``."""
    t = (z - o[..., 2]) / d[..., 2]
    x = o + t[..., None] * d
    inside = (t > 0) & (np.abs(x[..., 0]) <= half[0]) & (np.abs(x[..., 1]) <= half[1])
    return x, inside


POOL_RES = 64


@pytest.mark.physical_requirement
def test_pool_floor_is_seen_through_the_water(tmp_path, record_property):
    """Physical requirement, water_pool (64^2 camera, sun E0 = 800 W/m^2, no direct
    lighting: all light reaches the floor through the water): the camera sees the
    floor through the water surface, ptracer does not.

    Pixels: those whose centre ray, refracted at the still water plane (z = 1 m,
    IOR 1.33), lands on the 4 x 4 m floor, at least 2 pixels inside that region's
    edge (the waves, at most 4 cm high, tilt rays by a few degrees).

    (1) The tracer lights every one of them (luminance above
    ``sphere_camera.BLACK_LEVEL`` of the image's 99th percentile). (2) ptracer renders
    them all black. (3) Energy and the n^2 law: without Fresnel the surface transmits
    all the sun's flux, so the floor's mean irradiance is E0 cos(theta) (theta the
    sun's angle from the vertical: flux per horizontal area is unchanged by
    refraction; waves only redistribute it), its radiance in the water
    albedo / pi E0 cos(theta), and seen from the air 1 / 1.33^2 of that (radiance /
    n^2 is invariant along a ray): 113.4 W m^-2 sr^-1. The pixels' mean radiance is
    within 5 % of it: the wave caustics' bright bands and the perspective weight the
    pixels unevenly (measured -2 %); without the n^2 law it would be 77 % higher."""
    scene = _scene("water_pool", POOL_RES)
    traced = render_traced_camera(scene, photons=LOOKUP_PHOTONS, spp=4, seeds=2, seed=3)
    ptracer = render_camera(scene, spp=16, seed=3)
    water = scene.objects[0]
    ior = water.material.iors[1]
    floor_half = np.asarray(scene.receivers[0].size) / 2
    centres = np.arange(POOL_RES) + 0.5
    fx, fy = np.meshgrid(centres, centres)
    d = pinhole_directions(scene.camera, fx, fy)
    eye = np.broadcast_to(np.asarray(scene.camera.position, float), d.shape)
    at, on_water = _plane_hits(eye, d, water.center[2], np.asarray(water.size) / 2)
    cos_i = -d[..., 2]
    eta = 1 / ior
    k = 1 - eta**2 * (1 - cos_i**2)
    refracted = eta * d + (eta * cos_i - np.sqrt(np.maximum(k, 0)))[..., None] * [0, 0, 1]
    _, on_floor = _plane_hits(at, refracted, 0.0, floor_half)
    region = on_water & on_floor
    pixels = region & ~binary_dilation(~region, iterations=2)
    lum = luminance(traced.image)
    lit = np.mean(lum[pixels] > BLACK_LEVEL * np.percentile(lum, 99))
    sun = np.asarray(scene.light.direction, float)
    cos_sun = -sun[2] / np.linalg.norm(sun)
    albedo = scene.receivers[0].albedo[1]
    expected = albedo / np.pi * scene.light.irradiance[1] * cos_sun / ior**2
    mean = traced.image[..., 1][pixels].mean()
    print(f"pool: {pixels.sum()} pixels through the water; tracer lit fraction {lit:.4f}, "
          f"mean radiance {mean:.2f} vs {expected:.2f} W m^-2 sr^-1 "
          f"({mean / expected - 1:+.2%}); ptracer max {ptracer[pixels].max():.3g}")
    record_property("checks", 3)
    images = {"trace": traced.image, "ptracer": ptracer, "pixels": pixels.astype(float)}
    assert pixels.sum() > 0.3 * POOL_RES**2
    _require(lit > 0.99, "the floor is not seen through the water", tmp_path,
             "camera-trace-pool", **images)
    _require(np.all(ptracer[pixels] == 0), "ptracer sees through the water", tmp_path,
             "camera-trace-pool", **images)
    _require(abs(mean / expected - 1) < 0.05, "mean radiance through the water off",
             tmp_path, "camera-trace-pool", **images)


# ----------------------------------------------------------------------------- noise

NOISE_RES, NOISE_SEEDS, NOISE_SPP, NOISE_PHOTONS = 64, 8, 16, 1 << 16


@pytest.mark.physical_requirement
def test_pixel_variance_is_the_variance_of_the_mean(tmp_path, record_property):
    """Physical requirement (the reference's error bars are honest), glass_sphere
    (64^2 camera, 16 samples per pixel, 2^16 lookup photons per seed: noisy on
    purpose): two renders on disjoint seeds (8 each) differ per pixel by Welch z with
    mean z^2 within 4 standard deviations of its expectation (module docstring;
    E[z^2] ~ 1.17 for 14 dof), over all pixels with noise and over the caustic
    alone (pixels whose radiance the lookup maps carry: in the sphere's shadow).

    Not vacuous: the same two renders with each one's lookup maps shared by its 8
    seeds (the maps traced once) miss the maps' noise in their variance, and their
    mean z^2 over the caustic pixels is far above its expectation (measured 7.1; more
    than twice the expectation is required)."""
    scene = _scene("glass_sphere", NOISE_RES)
    first, second = (render_traced_camera(scene, photons=NOISE_PHOTONS, spp=NOISE_SPP,
                                          seeds=NOISE_SEEDS, seed=seed) for seed in (0, 100))
    exact = analytic_sphere_camera(scene, supersample=4)
    noisy = (first.variance[..., 1] + second.variance[..., 1]) > 0
    level = BLACK_LEVEL * np.percentile(luminance(first.image), 99)
    caustic = noisy & exact.floor & (luminance(exact.image) <= level)
    z, _, mean_z2, var_z2 = _welch(first.image[..., 1], first.variance[..., 1],
                                   second.image[..., 1], second.variance[..., 1],
                                   seeds=(NOISE_SEEDS, NOISE_SEEDS))
    results = {}
    for name, mask in (("all", noisy), ("caustic", caustic)):
        n = int(mask.sum())
        results[name] = (np.mean(z[mask] ** 2), mean_z2[mask].mean(),
                         np.sqrt(var_z2[mask].mean() / n), n)
    shared = [_shared_lookup_render(scene, seed) for seed in (0, 100)]
    zs, _, ez_s, _ = _welch(shared[0][0][..., 1], shared[0][1][..., 1],
                            shared[1][0][..., 1], shared[1][1][..., 1],
                            seeds=(NOISE_SEEDS, NOISE_SEEDS))
    for name, (m, e, sd, n) in results.items():
        print(f"noise, {name}: {n} pixels, mean z^2 = {m:.3f} (expected {e:.3f} +- {sd:.3f})")
    print(f"noise, caustic, lookup maps shared by the seeds: mean z^2 = "
          f"{np.mean(zs[caustic] ** 2):.2f} (expected {ez_s[caustic].mean():.2f})")
    record_property("checks", 3)
    assert results["caustic"][3] > 50
    for name, (m, e, sd, _) in results.items():
        _require(abs(m - e) < 4 * sd, f"mean z^2 between seeds off ({name})", tmp_path,
                 "camera-trace-noise", first=first.image, second=second.image, z=z)
    assert np.mean(zs[caustic] ** 2) > 2 * ez_s[caustic].mean()


def _shared_lookup_render(scene, seed):
    """K = NOISE_SEEDS camera seeds sharing one set of lookup maps (traced once, with
    ``seed``): mean and variance of the mean, the maps' noise left out."""
    from renderers.mitsuba.camera_lookup import LookupMaps  # noqa: PLC0415
    from renderers.mitsuba.photons import PhotonTracer  # noqa: PLC0415

    tracer = CameraTracer(scene)
    photons = PhotonTracer(scene, caustic_only=True)
    sums = photons.trace(NOISE_PHOTONS, seed=seed, stream=1 << 20)
    lookup = LookupMaps.from_arrays([m / sums.photons for m in sums.caustic], photons.extents)
    frames = [tracer.render(spp=NOISE_SPP, seed=seed + i, lookup=lookup)[0]
              for i in range(NOISE_SEEDS)]
    return seed_statistics(np.stack(frames))


# ---------------------------------------------------------- dispersion and absorption


def _interior_means(image, mask):
    """Mean radiance per channel (3,) over the ``mask`` pixels."""
    return np.asarray(image, np.float64)[mask].mean(axis=0)


@pytest.mark.physical_requirement
def test_dispersion_refracts_each_channel_with_its_own_ior(tmp_path, record_property):
    """Physical requirement, dispersion_sphere (IOR 1.45 / 1.52 / 1.62, 96^2 camera):
    through the sphere each channel shows the floor refracted with its own IOR.
    Against the exact camera (harness/checks/sphere_camera.py, per-channel
    refraction, the same caustic map): (1) each channel's mean radiance over the
    sphere's interior within 1 % of the exact one (measured 0.2 %; glass_sphere's
    grey check agrees to 0.3 %, see test_sphere_shows_the_refracted_floor_and_caustic);
    (2) per pixel, each channel is closer to the exact image's same channel than to
    the other channels (mean absolute difference less than half): the per-channel
    images differ by more than the error. Not vacuous: the exact red and blue
    interior means differ by more than 3 % (measured 6 %)."""
    scene = _scene("dispersion_sphere", SPHERE_RES)
    traced = render_traced_camera(scene, photons=LOOKUP_PHOTONS, spp=16, seeds=2, seed=7)
    exact = analytic_sphere_camera(scene, _caustic_map(scene, seeds=2), supersample=4)
    mask = exact.interior
    ours, theirs = _interior_means(traced.image, mask), _interior_means(exact.image, mask)
    same = np.abs(traced.image[mask] - exact.image[mask]).mean(axis=0)
    other = np.array([min(np.abs(traced.image[mask][:, c] - exact.image[mask][:, o]).mean()
                          for o in range(3) if o != c) for c in range(3)])
    print(f"dispersion: interior means {ours} vs exact {theirs}; per-pixel |difference| "
          f"same channel {same}, nearest other channel {other}")
    record_property("checks", 2)
    assert abs(theirs[0] - theirs[2]) > 0.03 * theirs[1]
    images = {"trace": traced.image, "exact": exact.image}
    _require(bool(np.all(np.abs(ours / theirs - 1) < 0.01)), "a channel's radiance is off",
             tmp_path, "camera-trace-dispersion", **images)
    _require(bool(np.all(same < 0.5 * other)), "channels not refracted by their own IOR",
             tmp_path, "camera-trace-dispersion", **images)


SIGMA = (0.2, 0.5, 1.0)  # 1/m: red, green, blue absorption


@pytest.mark.physical_requirement
def test_absorption_darkens_by_beer_lambert(tmp_path, record_property):
    """Physical requirement, glass_sphere with absorption sigma = (0.2, 0.5, 1.0) 1/m
    (96^2 camera): a camera ray through the sphere is attenuated by
    exp(-sigma L), L its chord inside, per channel, on top of the (also absorbed)
    caustic it sees. Against the exact camera (its chords through the ideal sphere
    and the absorbing scene's own caustic map): each channel's mean radiance over the
    interior within 1 % (measured 0.2 %; 0.3 % without absorption). Not vacuous:
    against the clear sphere the exact interior loses 31 %, 60 % and 84 % of its
    light (red, green, blue), far more than the tolerance; required: blue above 30 %
    and the losses ordered like sigma."""
    tinted = _scene("glass_sphere", SPHERE_RES, absorption=SIGMA)
    assert isinstance(tinted.objects[0].material, DielectricMaterial)
    traced = render_traced_camera(tinted, photons=LOOKUP_PHOTONS, spp=16, seeds=2, seed=7)
    exact = analytic_sphere_camera(tinted, _caustic_map(tinted, seeds=2), supersample=4)
    clear_scene = _scene("glass_sphere", SPHERE_RES)
    clear = analytic_sphere_camera(clear_scene, _caustic_map(clear_scene, seeds=2),
                                   supersample=4)
    mask = exact.interior
    ours, theirs = _interior_means(traced.image, mask), _interior_means(exact.image, mask)
    loss = 1 - theirs / _interior_means(clear.image, mask)
    print(f"absorption: interior means {ours} vs exact {theirs} "
          f"(ratio {ours / theirs}); exact loss against the clear sphere {loss}")
    record_property("checks", 1)
    assert loss[2] > 0.3 and loss[0] < loss[1] < loss[2]
    _require(bool(np.all(np.abs(ours / theirs - 1) < 0.01)), "Beer-Lambert attenuation off",
             tmp_path, "camera-trace-absorption", trace=traced.image, exact=exact.image)


# ----------------------------------------------------------------- direct irradiance

LIGHTS = {
    "point": 'type = "point"\nposition = [0.5, -0.3, 3.0]\nintensity = [10.0, 20.0, 30.0]',
    "spot": 'type = "spot"\nposition = [0.2, -0.1, 2.0]\ndirection = [0.15, 0.1, -1.0]\n'
            'intensity = [10.0, 20.0, 30.0]\ncutoff_angle = 40.0\nbeam_width = 20.0',
    "directional": 'type = "directional"\ndirection = [0.3, 0.2, -1.0]\n'
                   'irradiance = [4.0, 5.0, 6.0]',
    "area": 'type = "area"\ncenter = [0.3, -0.2, 2.5]\nnormal = [0.0, 0.2, -1.0]\n'
            'size = [1.0, 0.6]\nintensity = [10.0, 20.0, 30.0]',
}
SUB = 8  # subpixel strata per axis: the tracer's 64 samples, the exact midpoints


def _exact_direct(scene, light) -> tuple[np.ndarray, np.ndarray]:
    """Radiance albedo / pi E(x) of the bare 4 x 4 m floor, averaged over SUB x SUB
    subpixel midpoints, and the mask of pixels whose every midpoint sees the floor.
    E: point I cos / r^2; spot the same times Mitsuba's linear falloff
    (tests/renderers/spot_profile.py); directional E0 cos; area the rectangle's
    radiance I / A integrated by a 32 x 32 midpoint rule, L cos_l cos / r^2 dA."""
    from renderers.mitsuba.exporter import area_light_frame  # noqa: PLC0415
    from tests.renderers import spot_profile  # noqa: PLC0415

    width, height = scene.camera.resolution
    fx, fy = np.meshgrid((np.arange(width * SUB) + 0.5) / SUB,
                         (np.arange(height * SUB) + 0.5) / SUB)
    d = pinhole_directions(scene.camera, fx, fy)
    eye = np.broadcast_to(np.asarray(scene.camera.position, float), d.shape)
    x, floor = _plane_hits(eye, d, 0.0, np.asarray(scene.receivers[0].size) / 2)
    kind = type(light).kind
    if kind == "directional":
        travel = np.asarray(light.direction, float)
        e = np.asarray(light.irradiance) * (-travel[2] / np.linalg.norm(travel))
        e = np.broadcast_to(e, x.shape)
    elif kind in ("point", "spot"):
        to_light = np.asarray(light.position) - x
        r = np.linalg.norm(to_light, axis=-1)
        e = (to_light[..., 2] / r**3)[..., None] * np.asarray(light.intensity)
        if kind == "spot":
            axis = np.asarray(light.direction) / np.linalg.norm(light.direction)
            theta = np.degrees(np.arccos(np.clip(-(to_light / r[..., None]) @ axis, -1, 1)))
            e = e * spot_profile.falloff(theta, cutoff=light.cutoff_angle,
                                         beam=light.beam_width)[..., None]
    else:
        frame = area_light_frame(light)
        q = (np.arange(32) + 0.5) / 32 * 2 - 1
        qa, qb = np.meshgrid(q, q)
        points = (frame[:3, 0] * qa.ravel()[:, None] + frame[:3, 1] * qb.ravel()[:, None]
                  + frame[:3, 3])
        normal = frame[:3, 2]
        da = light.size[0] * light.size[1] / points.shape[0]
        e = np.zeros(x.shape)
        for p in points:
            v = p - x
            r2 = np.sum(v * v, axis=-1)
            cos_l = np.clip(-(v @ normal) / np.sqrt(r2), 0, None)
            cos_x = np.clip(v[..., 2] / np.sqrt(r2), 0, None)
            e += (cos_l * cos_x / r2)[..., None] * da
        e = e * np.asarray(light.intensity) / (light.size[0] * light.size[1])
    radiance = np.where(floor[..., None], scene.receivers[0].albedo[0] / np.pi * e, 0.0)
    image = radiance.reshape(height, SUB, width, SUB, 3).mean(axis=(1, 3))
    return image, floor.reshape(height, SUB, width, SUB).all(axis=(1, 3))


DIRECT_RES, DIRECT_SEEDS = 48, 8


@pytest.mark.physical_requirement
@pytest.mark.parametrize("kind", list(LIGHTS))
def test_direct_light_is_the_lights_analytic_irradiance(kind, tmp_path, record_property):
    """Physical requirement, a bare floor (4 x 4 m, albedo 0.5; 48^2 camera, pixels of
    5 to 12 cm of floor; a tiny sphere far away): each light type's direct
    irradiance, in the radiometric contract's units, against its closed form
    (``_exact_direct``, 8 x 8 subpixel midpoints) per pixel, on the pixels at least
    one pixel inside the floor's edge, one channel (the three are the same samples).
    (1) The sum over the pixels within 0.1 % of the exact one: a units, cosine or
    normalisation error shows here (measured below 2e-4). (2) Per pixel: the
    tracer's own noise (the subpixel jitter; for the area light also its one random
    point of the rectangle per sample) is its variance of the mean over K = 8
    seeds, so the mean z^2 against the exact image is within 4 standard deviations
    of its expectation (module docstring; 7 dof), the midpoint rules' error
    ignored (below the jitter noise: measured mean z^2 1.42 for 1.40 expected with a
    point light); pixels without noise (relative standard error below float32 rounding: a
    directional light's uniform radiance, a spot's dark outside) are within 1e-4 of
    the brightest pixel instead."""
    from tests.renderers.mitsuba.scenes import FAR_SPHERE, make_scene  # noqa: PLC0415

    scene = make_scene(light=LIGHTS[kind], objects=FAR_SPHERE)
    scene = dataclasses.replace(scene, camera=dataclasses.replace(
        scene.camera, resolution=(DIRECT_RES, DIRECT_RES)))
    traced = render_traced_camera(scene, photons=1 << 14, spp=SUB * SUB, seeds=DIRECT_SEEDS,
                                  seed=11)
    exact, floor = _exact_direct(scene, scene.light)
    pixels = floor & ~binary_dilation(~floor, iterations=1)
    a, va, b = traced.image[..., 1][pixels], traced.variance[..., 1][pixels], \
        exact[..., 1][pixels]
    total = a.sum() / b.sum() - 1
    noisy = va > (1e-6 * b) ** 2  # relative noise above float32 rounding
    # The exact image has no noise: infinitely many "seeds" of variance 0.
    z, _, mean_z2, var_z2 = _welch(a[noisy], va[noisy], b[noisy], 0.0,
                                   seeds=(DIRECT_SEEDS, 1 << 30))
    expected, sd = mean_z2.mean(), np.sqrt(var_z2.mean() / max(z.size, 1))
    quiet = np.abs(a[~noisy] - b[~noisy]) / b.max()
    print(f"{kind}: {pixels.sum()} pixels ({np.sum(b > 0)} lit, {noisy.sum()} with noise), "
          f"total {total:+.2e}; mean z^2 {np.mean(z**2) if z.size else np.nan:.3f} "
          f"(expected {expected:.3f} +- {sd:.3f}); noiseless max error "
          f"{quiet.max() if quiet.size else 0:.1e}")
    record_property("checks", 2)
    assert pixels.sum() > 500 and np.sum(b > 0) > 300
    ok = abs(total) < 1e-3 and (not quiet.size or quiet.max() < 1e-4)
    ok &= not z.size or abs(np.mean(z**2) - expected) < 4 * sd
    _require(bool(ok), f"{kind} light's direct irradiance off", tmp_path,
             f"camera-trace-direct-{kind}", trace=traced.image, exact=exact)


# ---------------------------------------------------------------- lookup resolution


@pytest.mark.physical_requirement
def test_footprints_are_the_pinholes_on_the_floor():
    """Physical requirement, glass_sphere (128^2 camera): the footprint the lookup
    rule measures on the floor seen directly is the pinhole's. For each pixel whose
    centre ray and its right and lower neighbours' all see the floor directly, the
    ideal footprint sqrt|du_x dv_y - dv_x du_y| from the three rays' floor hits,
    computed here with exact ray-plane geometry (and the perspective model of
    harness/checks/sphere_camera.py), matches ``CameraTracer.footprints`` within
    1e-3 relative (float32 hit points about 10 m away, differences of 3 to 9 cm)."""
    scene = _scene("glass_sphere", 128)
    (measured,) = CameraTracer(scene).footprints()
    centres = np.arange(128) + 0.5
    fx, fy = np.meshgrid(centres, centres)
    d = pinhole_directions(scene.camera, fx, fy)
    eye = np.broadcast_to(np.asarray(scene.camera.position, float), d.shape)
    x, on_floor = _plane_hits(eye, d, 0.0, np.asarray(scene.receivers[0].size) / 2)
    exact_sphere = analytic_sphere_camera(scene, supersample=1)
    direct = on_floor & ~binary_dilation(exact_sphere.sphere, iterations=2)
    here, right, below = (slice(None, -1),) * 2, (slice(None, -1), slice(1, None)), \
        (slice(1, None), slice(None, -1))
    du_x, dv_x = (x[right] - x[here])[..., 0], (x[right] - x[here])[..., 1]
    du_y, dv_y = (x[below] - x[here])[..., 0], (x[below] - x[here])[..., 1]
    ideal = np.sqrt(np.abs(du_x * dv_y - dv_x * du_y))
    both = direct[here] & direct[right] & direct[below]
    rel = np.abs(measured[both] / ideal[both] - 1)
    print(f"footprints: {both.sum()} floor pixels, {np.nanmin(ideal[both]):.4f} to "
          f"{np.nanmax(ideal[both]):.4f} m, max relative difference {rel.max():.1e}")
    assert both.sum() > 5000 and np.isfinite(measured[both]).all()
    assert rel.max() < 1e-3


@pytest.mark.regression_lock
def test_glass_sphere_lookup_plan():
    """Regression lock (today's output, guards change): glass_sphere at its own 512^2
    camera. The 10th percentile of the floor footprints is 1.336 cm (1 % allowed), so
    the lookup is 1024^2 (texels of 0.78 cm below it; 512^2's 1.56 cm are not), and
    the photons per seed are the receiver maps' 2 M times (3.125 / 1.336)^2 = 5.47."""
    scene = load_scene(SCENES / "glass_sphere.toml")
    plan = CameraTracer(scene).lookup_plan(2_000_000)
    print(plan)
    assert plan.resolution == (1024, 1024) and not plan.capped
    assert plan.footprints[0] == pytest.approx(0.01336, rel=0.01)
    assert plan.photons == pytest.approx(2_000_000 * (0.03125 / plan.footprints[0]) ** 2,
                                         rel=1e-6)


# ------------------------------------------------------------- cache and command line


@pytest.mark.regression_lock
def test_cache_keeps_the_two_camera_integrators_apart(tmp_path):
    """Regression lock of the cache's contract (tiny scene of test_cache.py): the key
    names the camera integrator, so a ``ptracer`` reference and a camera-tracer one
    are two entries; an entry recording the other integrator under a key is a miss
    (re-rendered), never returned; the metadata says which integrator made the
    image and, for the tracer, its lookup maps."""
    from renderers.mitsuba import mitsuba_versions  # noqa: PLC0415
    from renderers.mitsuba.cache import cache_key, load_entry, write_result_dir  # noqa: PLC0415
    from renderers.mitsuba.reference import render_reference  # noqa: PLC0415
    from scenes import parse_scene  # noqa: PLC0415
    from tests.renderers.mitsuba.test_cache import TINY  # noqa: PLC0415

    scene = parse_scene(TINY, file="<tiny>")
    versions = mitsuba_versions()
    assert cache_key(scene, versions) == cache_key(scene, versions, camera="trace")
    assert cache_key(scene, versions, camera="ptracer") != cache_key(scene, versions)
    root = tmp_path / "cache"
    ptracer = render_reference(scene, cache=root, progress=False, camera="ptracer")
    traced = render_reference(scene, cache=root, progress=False)
    assert traced.metadata["cache"].startswith("miss")
    assert ptracer.metadata["camera_integrator"] == "ptracer"
    assert traced.metadata["camera_integrator"] == "camera_trace"
    assert traced.metadata["camera_lookup"]["resolution"] == [16, 16]
    assert render_reference(scene, cache=root, progress=False,
                            camera="ptracer").metadata["cache"] == "hit"
    # A ptracer image stored under the tracer's key (as an older writer could) is a miss.
    key = cache_key(scene, versions)
    write_result_dir(root / key, dataclasses.replace(
        ptracer, metadata={**ptracer.metadata, "hash": key}))
    with pytest.warns(UserWarning, match="camera image by ptracer"):
        result, why = load_entry(root, key, camera="trace")
    assert result is None and why.startswith("invalid")


@pytest.mark.regression_lock
def test_reference_command_chooses_the_camera(tmp_path):
    """Regression lock: ``caustics reference --camera`` picks the integrator written
    to result.json (default the camera tracer). glass_sphere with a 24^2 camera and
    tiny budgets: in camera.exr the tracer lights some of the sphere's interior
    pixels (the floor seen through it), ptracer none."""
    import json  # noqa: PLC0415

    from harness.cli import main  # noqa: PLC0415
    from renderers.exr import read_exr  # noqa: PLC0415

    text = (SCENES / "glass_sphere.toml").read_text()
    path = tmp_path / "small.toml"
    path.write_text(text.replace("resolution = [512, 512]", "resolution = [24, 24]")
                    + "\n[settings]\nreceiver_map = [32, 32]\nphotons = 65536\nspp = 4\n"
                    "seeds = 2\n")
    images = {}
    for camera in (None, "ptracer"):
        out = tmp_path / f"out-{camera}"
        extra = ["--camera", camera] if camera else []
        assert main(["reference", str(path), "-o", str(out), "--cache-dir",
                     str(tmp_path / "c"), "-q", *extra]) == 0
        document = json.loads((out / "result.json").read_text())
        images[document["camera_integrator"]] = read_exr(out / "camera.exr")["RGB"]
    assert set(images) == {"camera_trace", "ptracer"}
    interior = analytic_sphere_camera(load_scene(path)).interior  # 1 px inside the outline
    assert interior.sum() >= 8
    assert np.sum(images["camera_trace"][interior].max(axis=-1) > 0) >= 2
    assert images["ptracer"][interior].max() == 0
