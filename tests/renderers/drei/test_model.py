"""The NumPy model of drei's caustic pass (renderers/drei/model.py) against the
page: the same light camera, and the same texture up to how the page samples its
8-bit normal texture (bilinearly, where the model reads exact positions).

Measured at 256² on the sun scene: the light camera's matrices equal to 2e-16; the
texture's sum within 0.15 %, lit texels 11,768 against 11,763, each texel's relative
difference at the median 0.2 % and at the 95th percentile 4.3 %. The bounds leave
about twice that room at the tests' 128².

Also, without a browser: Snell's law and Fresnel's normal-incidence value, and the
landing photon map keeping the flux that enters the sphere.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from renderers.drei.model import (
    Spheres,
    fresnel_transmittance,
    land,
    refract,
    trace_texture,
)
from renderers.drei.params import drei_params
from scenes import load_scene
from scenes.export import receiver_frame, to_gltf
from scenes.geometry import build_geometry
from tests.renderers.drei.scenes import AXIS_ON_FLOOR, SUN_SCENE
from tests.renderers.drei.test_mapping import assert_caustic_at

#: The sun scene's sphere in the drei frame (the floor is at height 0).
SPHERE = Spheres(np.array([to_gltf((0.0, 0.0, 2.0))]), np.array([1.0]))


def test_the_model_computes_the_pages_texture(drei):
    texture, camera = trace_texture(SPHERE, drei.params, 1.5)
    page = drei.textures[0]
    np.testing.assert_allclose(camera.view, drei.light_cameras[0].view, atol=1e-9)
    np.testing.assert_allclose(camera.projection, drei.light_cameras[0].projection,
                               atol=1e-9)
    assert texture.sum() == pytest.approx(page.sum(), rel=5e-3)
    both = (texture > 0) & (page > 0)
    assert both.sum() >= 0.995 * max((texture > 0).sum(), (page > 0).sum())
    relative = np.abs(texture[both] - page[both]) / page[both]
    assert np.median(relative) < 5e-3 and np.percentile(relative, 95) < 0.1


def test_refraction_and_fresnel_known_values():
    # Snell: 30 degrees into glass of 1.5 leaves at asin(sin 30 / 1.5).
    incident = np.array([math.sin(math.radians(30)), -math.cos(math.radians(30)), 0.0])
    out = refract(incident, np.array([0.0, 1.0, 0.0]), 1 / 1.5)
    assert math.degrees(math.asin(out[0])) == pytest.approx(
        math.degrees(math.asin(0.5 / 1.5)))
    # Normal incidence: R = ((n - 1) / (n + 1))² = 0.04 each way.
    assert fresnel_transmittance(np.array(1.0), 1 / 1.5) == pytest.approx(0.96)
    assert fresnel_transmittance(np.array(1.0), 1.5) == pytest.approx(0.96)
    # Beyond the critical angle nothing is transmitted.
    assert fresnel_transmittance(np.array(0.5), 1.5) == 0.0


def test_the_landing_photon_map_keeps_the_flux_through_the_sphere():
    """A sphere has no total internal reflection: every photon through it either
    lands or leaves upwards (deviated by more than 90 degrees near the rim), and the
    two hold E0 pi R² (the texture's grid approximates the disc: 1 % at 256²)."""
    scene = load_scene(SUN_SCENE)
    geometry = build_geometry(scene)
    frame = receiver_frame(scene.receivers[0], geometry.receivers[0], (64, 64))[0]
    wide = dataclasses.replace(frame, extent=(-40.0, 40.0, -40.0, 40.0))
    params = drei_params(scene, objects_radius=1.0, resolution=256)
    irradiance, lost = land(SPHERE, params, 1.5, wide)
    held = irradiance.sum() * (80.0 / 64) ** 2
    assert held + lost == pytest.approx(5.0 * math.pi, rel=0.01)
    assert 0 < lost < 0.05 * held
    # ... and centred where the light ray through the sphere's centre meets the floor.
    irradiance, _ = land(SPHERE, params, 1.5, frame)
    texel = 8.0 / 64
    assert_caustic_at(np.repeat(irradiance[..., None], 3, axis=-1), frame.extent,
                      AXIS_ON_FLOOR, tolerance=texel / 2)


def test_a_second_refraction_changes_the_texture_not_its_footprint():
    """The exit refraction changes every lit texel's area ratio (by more than 10 %)
    but not which texels are lit (the same entry points; a few rim texels whose exit
    ray runs parallel to the far plane drop out)."""
    params = drei_params(load_scene(SUN_SCENE), objects_radius=1.0, resolution=64)
    once, _ = trace_texture(SPHERE, params, 1.5)
    twice, _ = trace_texture(SPHERE, params, 1.5, refractions=2)
    assert abs(int((once > 0).sum()) - int((twice > 0).sum())) <= 4
    both = (once > 0) & (twice > 0)
    assert (np.abs(twice[both] / once[both] - 1) > 0.1).mean() > 0.5
