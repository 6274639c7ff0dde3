"""The camera pass's view of the caustic objects (docs/method.md): double
refraction through the camera-view back faces (Wyman 2005), the receiver hit from
the light's positions atlas, TIR, Fresnel, absorption, dispersion and reflection.

Every accuracy check here is a **method target**: what a preset should reach against
an exact answer, the analytic sphere camera of ``harness/checks/sphere_camera.py``
or an exact trace of the same triangles on Mitsuba's ray tracer
(:mod:`harness.raycast`); a miss of the paper preset is a known gap (strict xfail
with the measured numbers). The exact answers are shaded with the method's
own receiver irradiance map where they need a caustic, so both sides see the same
caustic and the comparison is of the camera pass, not of the caustic map. The
images a failure needs (exact, method, |difference|) are written to the test's
temporary folder, and the failure message names the file.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.checks import sphere_camera
from harness.checks.sphere_camera import analytic_sphere_camera, black_fraction, luminance
from renderers.caustics_mapping import render
from scenes import load_scene, with_settings
from scenes.model import DielectricMaterial
from tests.conftest import SCENES

#: Camera resolution of these checks: the sphere covers 848 interior pixels.
CAMERA = (128, 128)
#: Target tolerances (method_targets.toml): black fraction of the sphere's pixels within 0.08
#: of the exact lens image's, mean radiance over them within 20 %.
BLACK_TOLERANCE = 0.08
MEAN_TOLERANCE = 0.20


def _scene(name: str, *, camera=CAMERA, **settings):
    scene = with_settings(load_scene(SCENES / f"{name}.toml"), settings)
    return dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                 resolution=camera))


def _with_material(scene, **changes):
    (obj,) = scene.objects
    material = dataclasses.replace(obj.material, **changes)
    return dataclasses.replace(scene, objects=(dataclasses.replace(obj, material=material),))


def _write_images(folder, name, exact, method, mask):
    """exact, method and |difference| side by side in one PNG (tone-mapped at the
    exact's 99th percentile; the difference dimmed outside the compared pixels
    ``mask``); returns its path."""
    from PIL import Image  # noqa: PLC0415 (Pillow only where images are written)

    top = max(float(np.percentile(exact, 99)), 1e-30)
    diff = np.abs(method - exact)
    diff[~mask] *= 0.25

    def tone(x):
        return (np.clip(x / top, 0, 1) ** (1 / 2.2) * 255).astype(np.uint8)

    path = folder / f"{name}.png"
    Image.fromarray(np.concatenate([tone(exact), tone(method), tone(diff)], axis=1)).save(path)
    return path


def _sphere_numbers(ctx, scene):
    """(method image, analytic SphereCamera) with the analytic shaded by the method's
    own receiver map."""
    result = render(scene, ctx=ctx)
    exact = analytic_sphere_camera(scene, result.receivers[0], supersample=2)
    return result.camera, exact


def _compare_sphere(ctx, scene, tmp_path, label):
    image, exact = _sphere_numbers(ctx, scene)
    mask = exact.interior
    black = black_fraction(image, mask)
    mean = luminance(image[mask]).mean() / luminance(exact.image[mask]).mean()
    print(f"{label}: black {black:.3f} (exact {exact.black_fraction:.3f}), "
          f"mean radiance ratio {mean:.3f}")
    where = _write_images(tmp_path, label, exact.image, image, mask)
    return black, exact.black_fraction, mean, where


# ------------------------------------------------------------------- lens images

_PAPER_DIRECTIONAL = pytest.mark.xfail(strict=True, reason=(
    "known gap of the paper preset: unverified estimates shade every exit ray, and under a "
    "directional light the orthographic positions atlas projects a ray leaving upwards "
    "onto the floor, so no lookup is ever empty and the sky is never seen (measured: "
    "black 0.117 vs exact 0.409, mean radiance 1.47x)"))


@pytest.mark.method_target
@pytest.mark.parametrize(("name", "preset"), [
    ("glass_sphere", "strong"), ("glass_sphere", "paper"),
    ("dispersion_sphere", "strong"),
    pytest.param("dispersion_sphere", "paper", marks=_PAPER_DIRECTIONAL),
])
def test_sphere_is_the_exact_lens_image(ctx, tmp_path, name, preset):
    """Method target: the sphere's pixels (``interior`` of the analytic
    camera, 848 at 128²) are as often black, and on average as bright, as in the
    exact double refraction: black fraction within 0.08, mean luminance within 20 %
    (harness/checks/data/method_targets.toml). Measured: glass_sphere strong 0.434 vs
    0.430, ratio 0.998; paper 0.383 vs 0.430, ratio 1.097 (its unverified hits shade some sky rays);
    dispersion_sphere strong 0.426 vs 0.409, ratio 0.998. The single refraction to a
    plane that this pass replaced drew the glass sphere 1.5 % black."""
    black, exact_black, mean, where = _compare_sphere(
        ctx, _scene(name, preset=preset), tmp_path, f"{name}-{preset}")
    assert abs(black - exact_black) <= BLACK_TOLERANCE, (black, exact_black, str(where))
    assert abs(mean - 1) <= MEAN_TOLERANCE, (mean, str(where))


# ------------------------------------------------- exact paths on the same triangles

#: Per-pixel outcome of the exact chain: the primary ray meets no object; the chain
#: reaches a receiver; total internal reflection at the exit (or, rarely, the ray
#: inside meets no exit); the ray leaving the object meets no receiver first (the
#: sky, or the object again).
NO_OBJECT, RECEIVER, TIR, SKY = -1, 0, 1, 2


@dataclasses.dataclass(frozen=True)
class ExactPaths:
    """An exact camera trace of the chain through a scene's one object (H, W arrays):
    ``outcome`` (one of the codes above), ``radiance`` (H, W, 3) W m^-2 sr^-1 where
    the chain reaches the receiver (else 0), ``lit`` where that receiver point sees
    the light (direct light unshadowed)."""

    outcome: np.ndarray
    radiance: np.ndarray
    lit: np.ndarray


def _refract(d, n, eta):
    """Snell at unit normal n facing against d, eta = n_from / n_to; (t, tir)."""
    cos_i = -np.sum(d * n, axis=1)
    k = 1 - eta**2 * (1 - cos_i**2)
    t = eta * d + (eta * cos_i - np.sqrt(np.maximum(k, 0)))[:, None] * n
    return t / np.linalg.norm(t, axis=1, keepdims=True), k < 0


def _facing(n, d):
    """n flipped to face against d."""
    return np.where((np.sum(n * d, axis=1) > 0)[:, None], -n, n)


def _exact_paths(scene, caustic) -> ExactPaths:
    """The chain of the scene's one object (``scenes.event_chain``: L R D, L T D or
    L T T D), traced from the eye through the pixel centres on the scene's own
    triangles and shading normals (Mitsuba's ray tracer, :mod:`harness.raycast`), no
    Fresnel or absorption; receiver 0 must be a plane. A receiver point is shaded
    albedo / pi * (E_direct V + E_caustic), E_caustic read bilinearly in ``caustic``
    (the method's receiver map), times the reflectance (conductor) or 1 / n^2 (one
    refraction into water: radiance / n^2 is invariant along a ray)."""
    from harness.raycast import SurfaceTracer, camera_rays  # noqa: PLC0415 (Mitsuba)

    tracer = SurfaceTracer(scene)
    (obj,) = scene.objects
    receiver = scene.receivers[0]
    material = obj.material
    origin, d = camera_rays(scene.camera)
    first = tracer(origin, d)
    outcome = np.full(len(d), NO_OBJECT)
    on = np.flatnonzero(first.kind == tracer.OBJECT)
    p, n = first.position[on], _facing(first.shading_normal[on], d[on])
    leave, ray, weight = first.geometric_normal[on], d[on], np.ones((len(on), 3))
    code = np.full(len(on), RECEIVER)
    if isinstance(material, DielectricMaterial):
        ior = material.iors[0]
        ray, _ = _refract(ray, n, 1 / ior)
        if obj.kind == "water_surface":
            weight /= ior**2
        else:
            inside = tracer(p, ray, leaving=leave)
            p, leave = inside.position, inside.geometric_normal
            ray, tir = _refract(ray, _facing(inside.shading_normal, ray), ior)
            code[tir | (inside.kind != tracer.OBJECT)] = TIR
    else:
        ray = ray - 2 * np.sum(ray * n, axis=1)[:, None] * n
        weight *= np.asarray(material.reflectance, float)
    go = code == RECEIVER
    last = tracer(p[go], ray[go], leaving=leave[go])
    x, u, v, plane_n = sphere_camera._plane_hit(p[go], ray[go], receiver)
    reached = (last.kind == tracer.RECEIVER) & np.isfinite(u)
    code[np.flatnonzero(go)[~reached]] = SKY
    outcome[on] = code
    # Shade the receiver points the chains reach.
    idx = np.flatnonzero(go)[reached]
    x, u, v = x[reached], u[reached], v[reached]
    light = scene.light
    if light.kind == "directional":
        to_light = -np.asarray(light.direction, float) / np.linalg.norm(light.direction)
        to_light, dist, power = np.broadcast_to(to_light, x.shape), np.inf, light.irradiance
        falloff = 1.0
    else:
        to_light = np.asarray(light.position, float) - x
        dist = np.linalg.norm(to_light, axis=1)
        to_light, power, falloff = to_light / dist[:, None], light.intensity, 1 / dist**2
    e = np.outer(np.clip(to_light @ plane_n, 0, None) * falloff, np.asarray(power, float))
    lit = np.ones(len(x), bool)
    if scene.info.shadows:
        shadow = tracer(x, to_light, leaving=np.broadcast_to(plane_n, x.shape))
        lit = ~(shadow.distance < dist)
    e = e * lit[:, None] * scene.info.direct_lighting
    e += sphere_camera._bilinear(caustic, u, v)
    radiance = np.zeros((len(d), 3))
    lit_pixels = np.zeros(len(d), bool)
    radiance[on[idx]] = weight[idx] * np.asarray(receiver.albedo, float) / np.pi * e
    lit_pixels[on[idx]] = lit
    w, h = scene.camera.resolution
    return ExactPaths(outcome.reshape(h, w), radiance.reshape(h, w, 3),
                      lit_pixels.reshape(h, w))


def _black(image):
    """Black pixels of ``image`` (sphere_camera's level: 1e-4 of the 99th percentile)."""
    lum = luminance(np.asarray(image, np.float64))
    return lum <= sphere_camera.BLACK_LEVEL * np.percentile(lum, 99)


def _shares(ctx, scene, tmp_path, label):
    """Render ``scene``; (black share of each exact outcome's pixels, their counts,
    method / exact mean luminance where the chain reaches the receiver, image path)."""
    result = render(scene, ctx=ctx)
    exact = _exact_paths(scene, result.receivers[0])
    black = _black(result.camera)
    groups = {"tir": exact.outcome == TIR, "sky": exact.outcome == SKY,
              "reached": exact.outcome == RECEIVER,
              "lit": (exact.outcome == RECEIVER) & exact.lit}
    shares = {k: float(black[g].mean()) if g.any() else float("nan") for k, g in groups.items()}
    counts = {k: int(g.sum()) for k, g in groups.items()}
    reached = groups["reached"]
    ratio = luminance(result.camera[reached]).mean() / luminance(exact.radiance[reached]).mean()
    where = _write_images(tmp_path, label, exact.radiance, result.camera, reached)
    print(f"{label}: black shares {shares}, pixels {counts}, mean ratio {ratio:.3f}")
    return shares, counts, ratio, where


# ------------------------------------------------------- total internal reflection

@pytest.mark.method_target
@pytest.mark.parametrize("preset", ["strong", "paper"])
def test_total_internal_reflection_ends_the_chain(ctx, tmp_path, preset):
    """Method target: the hard case high_ior_tir (a glass cube of IOR 2.8, critical
    angle 20.9 degrees) against the exact trace of its L T T D chain at 128²: of the
    cube's pixels whose exact exit ray is totally reflected (379), at least 95 % are
    black (measured 100 % both presets): the chain counts nothing there, as the photon
    tracer drops such a photon. Not everything is black: of the pixels whose chain
    reaches a directly lit floor point (447), at most 15 % are (measured strong 6.9 %,
    paper 8.9 %: exits misplaced at the cube's edges). With all specular paths, TIR
    reflects inside and the next exit is searched: some TIR pixels light up, at most
    90 % stay black (measured strong 70 %, paper 64 %)."""
    scene = _scene("hard/high_ior_tir", preset=preset)
    shares, counts, _, where = _shares(ctx, scene, tmp_path, f"tir-{preset}")
    assert counts["tir"] > 300 and counts["lit"] > 300, counts
    assert shares["tir"] >= 0.95, (shares, str(where))
    assert shares["lit"] <= 0.15, (shares, str(where))
    all_paths = with_settings(scene, {"all_specular_paths": True})
    reflected, _, _, where = _shares(ctx, all_paths, tmp_path, f"tir-all-{preset}")
    assert reflected["tir"] <= 0.90, (reflected, str(where))


# ------------------------------------------------------ reflection, one refraction

_PAPER_RING = pytest.mark.xfail(strict=True, reason=(
    "known gap of the paper preset: camera rays reflected off the ring run at large angles "
    "to the light's projection rays, where the modified estimator's fixed point is not "
    "the hit (measured: 14 % of the ring's floor reflections black, mean 1.39x)"))
_PAPER_WATER = pytest.mark.xfail(strict=True, reason=(
    "known gap of the paper preset: where the light sees no floor through the ray's start "
    "on the water (the floor's rim, seen magnified through the surface) the first lookup "
    "is empty and the estimate is lost (measured: 19 % of the floor seen through the "
    "water black, mean 0.81x)"))


@pytest.mark.method_target
@pytest.mark.parametrize(("name", "preset"), [
    ("metal_ring", "strong"), pytest.param("metal_ring", "paper", marks=_PAPER_RING),
    ("water_pool", "strong"), pytest.param("water_pool", "paper", marks=_PAPER_WATER),
])
def test_one_bounce_shows_the_floor(ctx, tmp_path, name, preset):
    """Method target: a conductor (metal_ring, L R D, reflectance (0.95, 0.85, 0.6))
    and a water surface (water_pool, L T D, IOR 1.33, radiance / n^2 into the air)
    against the exact trace of their chain at 128², shaded with the method's receiver
    map: of the pixels whose chain reaches the floor (ring 329 lit, pool 6832) at most
    5 % are black, and their mean radiance is within 20 % of the exact (the
    targets' bounds). Measured strong: ring 0.6 % black, ratio 1.016; pool 0.6 %, 0.997 (without
    the 1 / n^2 factor the pool would be 1.77x). Rays that leave to the sky are black
    (at least 90 % of them; measured 100 %)."""
    shares, counts, ratio, where = _shares(ctx, _scene(name, preset=preset), tmp_path,
                                           f"{name}-{preset}")
    assert counts["lit"] > 300, counts
    assert shares["lit"] <= 0.05, (shares, str(where))
    assert abs(ratio - 1) <= MEAN_TOLERANCE, (ratio, str(where))
    if counts["sky"] > 100:
        assert shares["sky"] >= 0.90, (shares, str(where))


# ------------------------------------------------- Fresnel, absorption, dispersion

def _ratio_to_clear(ctx, scene, **material):
    """Mean radiance over the sphere's interior with ``material`` changes over that
    of clear glass, (method, exact), each exact shaded with its method render's map."""
    means = {}
    for label, variant in (("clear", scene), ("changed", _with_material(scene, **material))):
        image, exact = _sphere_numbers(ctx, variant)
        mask = exact.interior
        means[label] = (image[mask].astype(np.float64).mean(axis=0), exact.image[mask].mean(axis=0))
    method = means["changed"][0] / means["clear"][0]
    exact = means["changed"][1] / means["clear"][1]
    print(f"{material}: method ratio {method}, exact ratio {exact}")
    return method, exact


@pytest.mark.method_target
@pytest.mark.parametrize("preset", ["strong", "paper"])
def test_fresnel_dims_the_sphere_as_the_exact_does(ctx, preset):
    """Method target: with Fresnel the sphere's mean radiance drops by the exact camera's
    factor (each interface transmits 1 - F; the caustic changes alike on both sides,
    being the method's own), within 0.02. Measured: exact 0.872; method strong 0.873,
    paper 0.864. Non-vacuous: Fresnel costs the sphere more than 5 %."""
    method, exact = _ratio_to_clear(ctx, _scene("glass_sphere", preset=preset), fresnel=True)
    assert exact[1] < 0.95, exact
    np.testing.assert_allclose(method, exact, atol=0.02)


@pytest.mark.method_target
@pytest.mark.parametrize("preset", ["strong", "paper"])
def test_absorption_tints_the_sphere_as_the_exact_does(ctx, preset):
    """Method target: Beer-Lambert inside the sphere, K_a = (0.1, 0.6, 1.5) /m (the
    colored_bunny's), scales the sphere's mean radiance per channel by the exact
    camera's factor within 5 % (relative). Measured: exact (0.831, 0.332, 0.066);
    method strong (0.831, 0.332, 0.066), paper (0.831, 0.333, 0.066). Without the
    camera pass's absorption only the caustic's change would remain."""
    method, exact = _ratio_to_clear(ctx, _scene("glass_sphere", preset=preset),
                                    absorption=(0.1, 0.6, 1.5))
    assert exact[2] < 0.5 * exact[0], exact          # the channels differ
    np.testing.assert_allclose(method, exact, rtol=0.05)


def _channel_black(image, mask):
    """Black fraction of each channel of ``image`` over ``mask`` (each channel's own
    99th percentile, sphere_camera's level)."""
    top = np.percentile(image, 99, axis=(0, 1))
    return (image <= sphere_camera.BLACK_LEVEL * top)[mask].mean(axis=0)


_PAPER_DISPERSION = pytest.mark.xfail(strict=True, reason=(
    "known gap of the paper preset, as in the lens image under the directional light: the "
    "sky is never seen (measured per-channel black (0.126, 0.179, 0.219) vs exact "
    "(0.409, 0.432, 0.436))"))


@pytest.mark.method_target
@pytest.mark.parametrize("preset", ["strong", pytest.param("paper", marks=_PAPER_DISPERSION)])
def test_dispersion_refracts_each_channel_with_its_index(ctx, preset):
    """Method target: dispersion_sphere (IOR 1.45, 1.52, 1.62) refracts each channel
    with its own index: each channel's black fraction over the sphere within 0.03 of
    the exact's, and, as in the exact (0.409, 0.432, 0.436: the larger index sends
    more rays past the floor), blue at least 0.01 blacker than red (one IOR for all
    channels would give equal fractions). Measured strong (0.426, 0.438, 0.448)."""
    image, exact = _sphere_numbers(ctx, _scene("dispersion_sphere", preset=preset))
    method = _channel_black(image, exact.interior)
    expected = _channel_black(exact.image, exact.interior)
    print(f"per-channel black: method {method}, exact {expected}")
    assert expected[2] - expected[0] > 0.02, expected
    np.testing.assert_allclose(method, expected, atol=0.03)
    assert method[2] - method[0] >= 0.01, method


# ------------------------------------------------------------------------ passes

def test_back_faces_run_once_for_closed_dielectrics_only(ctx):
    """The wiring: pass 5a (``camera_backfaces``) runs, and is timed on its own, where a
    closed dielectric is seen (glass_sphere), and not for a water surface or a
    conductor; the camera pass is the last."""
    for name, expected in (("glass_sphere", True), ("water_pool", False),
                           ("metal_ring", False)):
        result = render(_scene(name, camera=(32, 32), grid=32, caustic_map=64,
                               positions_map=64, shadow_map=64), ctx=ctx)
        assert ("camera_backfaces" in result.metadata["passes"]) is expected, name
        assert ("camera_backfaces" in result.timings) is expected, name
        assert result.metadata["passes"][-1] == "camera"
