"""The mapping from drei's caustic texture to the receiver's (u, v) map, without a
browser: a synthetic texture under a light camera built as three.js builds it.

Kind: physical requirements. The map keeps the flux the texture holds over the
plane, computed here independently (a texel covers ((right - left) / res)² of the
plane perpendicular to the light, so 1 / cos(theta) times that of the floor); and the
caustic of a sphere lands where the light ray through its centre meets the floor, a
point a flipped axis moves.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from renderers.drei.mapping import light_affine, receiver_map
from scenes import load_scene
from scenes.export import receiver_frame, to_gltf
from scenes.geometry import build_geometry
from tests.renderers.drei.lightcam import light_camera
from tests.renderers.drei.scenes import AXIS_ON_FLOOR, SUN_SCENE

pytestmark = pytest.mark.physical_requirement

RES = 128
#: The sun scene's light, towards the light in glTF axes, and cos(theta) on the floor.
TOWARDS = to_gltf(-np.array([0.3, 0.2, -1.0]))
COS = 1.0 / math.sqrt(1.13)


def frame_of(scene, resolution=(64, 64)):
    return receiver_frame(scene.receivers[0], build_geometry(scene).receivers[0],
                          resolution)[0]


def disc_texture(*, value=3.0, radius=0.3, slope=2.0) -> np.ndarray:
    """A disc around the texture's centre with a gradient along s: T in W/m²."""
    s = (np.arange(RES) + 0.5) / RES - 0.5
    ss, tt = np.meshgrid(s, s)
    return np.where(ss**2 + tt**2 < radius**2, value + slope * ss, 0.0)


def centroid(irradiance: np.ndarray, extent) -> tuple[float, float]:
    """Flux-weighted (u, v) of a map (row 0 at vmin), m."""
    e = irradiance[..., 0]
    h, w = e.shape
    umin, umax, vmin, vmax = extent
    u = umin + (np.arange(w) + 0.5) * (umax - umin) / w
    v = vmin + (np.arange(h) + 0.5) * (vmax - vmin) / h
    return float((e.sum(0) * u).sum() / e.sum()), float((e.sum(1) * v).sum() / e.sum())


def assert_caustic_at(irradiance, extent, expected, *, tolerance):
    """The map's centroid is within ``tolerance`` m of ``expected`` (u, v)."""
    found = centroid(irradiance, extent)
    assert math.dist(found, expected) <= tolerance, (
        f"caustic centroid at {found}, expected {expected} (within {tolerance} m)")


@pytest.fixture(scope="module")
def sun():
    """The sun scene's frame and a light camera centred on its sphere, as the
    component places it (the sphere's centre (0, 0, 2) is (0, 2, 0) in glTF)."""
    scene = load_scene(SUN_SCENE)
    camera = light_camera(towards_light=TOWARDS, focus=(0.0, 2.0, 0.0), distance=1.4,
                          half=1.7)
    return frame_of(scene), camera


def test_the_map_keeps_the_texture_flux(sun):
    frame, camera = sun
    texture = disc_texture()
    mapped = receiver_map(np.stack([texture, 0.5 * texture, 0 * texture]),
                          light_affine(camera, frame, height=0.0), frame)
    texel = ((camera.right - camera.left) / RES) ** 2 / COS
    expected = texture.sum() * texel * np.array([1.0, 0.5, 0.0])
    np.testing.assert_allclose(mapped.texture_flux, expected, rtol=1e-12)
    held = mapped.irradiance.reshape(-1, 3).sum(0) * frame_area(frame)
    np.testing.assert_allclose(held, expected, rtol=1e-9)
    assert not mapped.outside.any()


def frame_area(frame) -> float:
    umin, umax, vmin, vmax = frame.extent
    return (umax - umin) * (vmax - vmin) / (frame.resolution[0] * frame.resolution[1])


def test_flux_off_the_receiver_is_counted_not_kept(sun):
    """A receiver that sees half the caustic: map + outside = the texture's flux."""
    frame, camera = sun
    half = dataclasses.replace(frame, extent=(0.6, 4.0, -4.0, 4.0))
    mapped = receiver_map(np.stack([disc_texture()] * 3),
                          light_affine(camera, half, height=0.0), half)
    held = mapped.irradiance.reshape(-1, 3).sum(0) * frame_area(half)
    assert 0.3 < held[0] / mapped.texture_flux[0] < 0.7
    np.testing.assert_allclose(held + mapped.outside, mapped.texture_flux, rtol=1e-9)


def test_the_caustic_lands_on_the_axis_and_a_flipped_axis_is_caught(sun):
    """A texture symmetric about its centre lands around the point where the light ray
    through the sphere's centre meets the floor; the same map with v or u flipped (a
    row order or sign error) is caught by the same assertion."""
    frame, camera = sun
    mapped = receiver_map(np.stack([disc_texture(slope=0.0)] * 3),
                          light_affine(camera, frame, height=0.0), frame)
    texel = (frame.extent[1] - frame.extent[0]) / frame.resolution[0]
    assert_caustic_at(mapped.irradiance, frame.extent, AXIS_ON_FLOOR, tolerance=texel / 2)
    for flipped in (mapped.irradiance[::-1], mapped.irradiance[:, ::-1]):
        with pytest.raises(AssertionError, match="caustic centroid"):
            assert_caustic_at(flipped, frame.extent, AXIS_ON_FLOOR, tolerance=texel / 2)


def test_a_raised_receiver_shifts_the_frame():
    """The drei frame puts the receiver at y = 0: with the floor raised by h, the same
    texture lands where the axis meets the raised floor."""
    scene = load_scene(SUN_SCENE)
    raised = dataclasses.replace(scene, receivers=(
        dataclasses.replace(scene.receivers[0], center=(0.0, 0.0, 0.5)),))
    frame = frame_of(raised)
    camera = light_camera(towards_light=TOWARDS, focus=(0.0, 1.5, 0.0), distance=1.4,
                          half=1.7)
    mapped = receiver_map(np.stack([disc_texture(slope=0.0)] * 3),
                          light_affine(camera, frame, height=0.5), frame)
    # (0, 0, 2) + 1.5 (0.3, 0.2, -1) meets z = 0.5 at (0.45, 0.3).
    assert_caustic_at(mapped.irradiance, frame.extent, (0.45, 0.3), tolerance=0.0625)
