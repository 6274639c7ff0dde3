"""The exact sphere camera (``harness/checks/sphere_camera.py``) that both renderers'
camera tests and the camera checks of ``compare`` trust: its geometry checked against
closed forms before anything is compared with it."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.checks import sphere_camera
from harness.checks.sphere_camera import analytic_sphere_camera
from scenes.loader import load_scene
from scenes.model import DielectricMaterial

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")


@pytest.fixture(scope="module")
def glass_sphere():
    scene = load_scene("scenes/glass_sphere.toml")
    camera = dataclasses.replace(scene.camera, resolution=(128, 128))
    return dataclasses.replace(scene, camera=camera)


def _with_ior(scene, ior):
    (obj,) = scene.objects
    material = dataclasses.replace(obj.material, ior=ior)
    return dataclasses.replace(scene, objects=(dataclasses.replace(obj, material=material),))


def test_index_one_sphere_is_invisible(glass_sphere):
    """Physical requirement: a sphere of index 1 bends no ray, so without shadows the
    image is the bare floor's. Compared with the same scene without the sphere's
    refraction path (each pixel shaded where its straight ray meets the floor);
    equal to float64 rounding (1e-9 relative)."""
    info = dataclasses.replace(glass_sphere.info, shadows=False)
    scene = dataclasses.replace(_with_ior(glass_sphere, 1.0), info=info)
    through = analytic_sphere_camera(scene, supersample=1)
    assert through.interior.sum() > 500  # the sphere covers the pixels compared
    # The same pixels' straight rays: move the sphere out of view (behind the eye).
    (obj,) = scene.objects
    away = dataclasses.replace(obj, center=(0.0, -50.0, 2.0))
    bare = analytic_sphere_camera(dataclasses.replace(scene, objects=(away,)), supersample=1)
    np.testing.assert_allclose(through.image, bare.image, rtol=1e-9, atol=1e-15)


def test_deviation_matches_the_closed_form():
    """Physical requirement: a ray with impact parameter b through a sphere of radius R
    and index n is deviated by 2 (asin(b/R) - asin(b/(n R))) (geometric optics of a
    ball lens, no reflection inside); checked for b/R in [0, 0.95] to 1e-12 rad."""
    n, radius = 1.5, 1.0
    center = np.zeros(3)
    b = np.linspace(0.0, 0.95, 20)
    o = np.stack([np.full_like(b, -5.0), b, np.zeros_like(b)], axis=1)
    d = np.tile([1.0, 0.0, 0.0], (len(b), 1))
    near, _ = sphere_camera._sphere_hits(o, d, center, radius)
    p1 = o + near[:, None] * d
    t1, _ = sphere_camera._refract(d, (p1 - center) / radius, 1 / n)
    p2 = p1 + (-2 * np.sum((p1 - center) * t1, axis=1))[:, None] * t1
    np.testing.assert_allclose(np.linalg.norm(p2 - center, axis=1), radius, rtol=1e-12)
    t2, _ = sphere_camera._refract(t1, -(p2 - center) / radius, n)
    deviation = np.arccos(np.clip(t2 @ [1.0, 0.0, 0.0], -1, 1))
    expected = 2 * (np.arcsin(b / radius) - np.arcsin(b / (n * radius)))
    np.testing.assert_allclose(deviation, expected, atol=1e-7)
    # The closed form is not trivially zero over this range (up to 48 degrees).
    assert math.degrees(expected.max()) > 40


def test_glass_sphere_shows_the_sky_through_its_lens(glass_sphere):
    """Physical requirement: the paper's glass sphere is an inverted lens image in
    which a large share of pixels see past the 8 x 8 m floor into the empty sky.
    Without shadows only the sky is black; an independent exact ray trace
    measured 44 % (tolerance 0.03 for its different sampling). Shadows add the floor
    under the ball, so the black fraction must grow."""
    no_shadow = dataclasses.replace(glass_sphere,
                                    info=dataclasses.replace(glass_sphere.info, shadows=False))
    sky = analytic_sphere_camera(no_shadow, supersample=2).black_fraction
    shadowed = analytic_sphere_camera(glass_sphere, supersample=2).black_fraction
    assert abs(sky - 0.44) < 0.03, sky
    assert shadowed > sky + 0.02, (shadowed, sky)


def _ratio_to_clear_glass(scene, material):
    """Per-pixel ratio over the sphere's interior of ``material``'s image to clear
    glass (same IOR, no Fresnel or absorption), shadows off."""
    (obj,) = scene.objects
    info = dataclasses.replace(scene.info, shadows=False)
    tinted = dataclasses.replace(scene, info=info,
                                 objects=(dataclasses.replace(obj, material=material),))
    clear = dataclasses.replace(_with_ior(scene, material.ior), info=info)
    seen = analytic_sphere_camera(tinted, supersample=1)
    reference = analytic_sphere_camera(clear, supersample=1).image
    lit = seen.interior & (sphere_camera.luminance(reference) > 0)
    assert lit.sum() > 300  # enough sphere pixels see the lit floor
    return seen.image[lit, 1] / reference[lit, 1]


def test_fresnel_transmits_at_most_the_normal_incidence_share(glass_sphere):
    """Physical requirement: two interfaces of n = 1.5 transmit (1 - 0.04)^2 = 0.9216
    at normal incidence (Fresnel, unpolarised), less at grazing angles. The pixel
    nearest normal incidence is within 0.5 % of it (its ray is a few degrees off)."""
    ratio = _ratio_to_clear_glass(glass_sphere, DielectricMaterial(ior=1.5, fresnel=True))
    expected = (1 - 0.04) ** 2
    assert np.all(ratio <= expected * (1 + 1e-9))
    assert abs(ratio.max() / expected - 1) < 0.005, ratio.max()
    assert ratio.min() < expected - 0.05  # grazing rays lose visibly more


def test_absorption_follows_the_inside_path_length(glass_sphere):
    """Physical requirement: Beer–Lambert with K_a = 0.1 /m over a chord of at most
    2 R = 2 m transmits at least exp(-0.2); the ray nearest the centre comes within
    0.5 % of it."""
    material = DielectricMaterial(ior=1.5, absorption=(0.1, 0.1, 0.1))
    ratio = _ratio_to_clear_glass(glass_sphere, material)
    expected = math.exp(-0.2)
    assert np.all(ratio >= expected * (1 - 1e-9))
    assert abs(ratio.min() / expected - 1) < 0.005, ratio.min()
