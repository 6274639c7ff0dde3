"""Region masks: caustic threshold and the camera's object mask."""

from __future__ import annotations

import dataclasses

import numpy as np

from harness.compare.regions import caustic_region, object_mask, object_region
from harness.compare.scoring import References, camera_is_blind, views_of
from scenes import load_scene
from scenes.geometry import build_geometry
from tests.conftest import SCENES


def test_caustic_region_threshold():
    ref = np.full((10, 10, 3), 0.01)
    ref[4:6, 4:6] = 1.0
    mask = caustic_region(ref)
    assert mask.sum() == 4 and mask[4:6, 4:6].all()
    assert not caustic_region(np.zeros((4, 4, 3))).any()


def test_object_mask_covers_the_sphere():
    """glass_sphere seen from (0, −9, 7): the unit sphere at distance √(81 + 25) m
    subtends a half-angle asin(1/√106) = 5.57°; with a 40° horizontal field of view
    over 64 px the disc's radius is ≈ 64 · tan(5.57°)/(2 tan 20°) ≈ 8.6 px, area
    ≈ 233 px. Undilated mask within 15 % of that (discretisation and perspective)."""
    scene = load_scene(SCENES / "glass_sphere.toml")
    camera = dataclasses.replace(scene.camera, resolution=(64, 64))
    mask = object_mask(camera, build_geometry(scene), dilate=0)
    radius = 64 * np.tan(np.arcsin(1 / np.sqrt(106))) / (2 * np.tan(np.radians(20)))
    assert abs(mask.sum() - np.pi * radius**2) < 0.15 * np.pi * radius**2
    _, cols = np.nonzero(mask)
    assert abs(cols.mean() - 31.5) < 1.0  # centred horizontally (sphere on the axis plane)
    assert object_mask(camera, build_geometry(scene), dilate=1).sum() > mask.sum()


def test_object_region_is_the_silhouette_interior():
    """The scored object region is the undilated object mask shrunk by one pixel: it
    lies inside the silhouette, shares no pixel with the region without the object
    (the dilated mask's complement), and of the ≈ 233 px disc (previous test) it
    keeps all but its rim, about 2π · 8.6 ≈ 54 px: between 130 and 200 px."""
    scene = load_scene(SCENES / "glass_sphere.toml")
    camera = dataclasses.replace(scene.camera, resolution=(64, 64))
    geometry = build_geometry(scene)
    inside = object_region(camera, geometry)
    hits = object_mask(camera, geometry, dilate=0)
    assert np.all(hits[inside])
    assert not np.any(inside & ~object_mask(camera, geometry))
    assert 130 < inside.sum() < 200, inside.sum()
    # Every pixel of the region has its four neighbours on the object.
    rows, cols = np.nonzero(inside)
    for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        assert hits[rows + dr, cols + dc].all()


def test_blind_reference_camera_is_detected():
    """A reference camera holding almost none of the real-time image's energy where
    that is lit is 'blind' (ptracer under water), even with a few stray particles; a
    sparse but unbiased one (most pixels black, as at 2 spp) is not."""
    rng = np.random.default_rng(3)
    method = np.ones((32, 32, 3))
    stray = np.zeros((32, 32, 3))
    stray[0, :5] = 5.0                     # 25 of 1024 energy units: 2.4 %
    sparse = rng.poisson(0.4, (32, 32, 1)).repeat(3, axis=2) / 0.4   # 67 % black
    assert camera_is_blind(stray, method)
    assert not camera_is_blind(sparse, method)


def test_water_pool_camera_is_scored_against_the_camera_tracer():
    """Every scene gets a camera comparison. On water_pool the floor is seen
    only through the water, which a ptracer reference renders black, so with ptracer
    the camera is left out with a note; the camera tracer's reference is compared,
    with the object region (the water surface seen through) scored."""
    from renderers.results import ReceiverMap, RenderResult  # noqa: PLC0415

    scene = load_scene(SCENES / "water_pool.toml")
    scene = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                  resolution=(48, 36)))
    geometry = build_geometry(scene)
    maps = tuple(ReceiverMap(np.ones((8, 8, 3), np.float32), r.extent)
                 for r in geometry.receivers)
    lit = np.ones((36, 48, 3), np.float32)

    def result(camera, integrator):
        return RenderResult("x", camera, maps, (), metadata={"camera_integrator": integrator})

    method = result(lit, None)
    views, notes = views_of(scene, geometry, method,
                            References(result(np.zeros_like(lit), "ptracer"),
                                       result(np.zeros_like(lit), "ptracer")))
    assert notes and "camera" not in [v.name for v in views]
    views, notes = views_of(scene, geometry, method,
                            References(result(lit, "camera_trace"), result(lit, "camera_trace")))
    (camera,) = [v for v in views if v.name == "camera"]
    assert notes == () and camera.regions["object"].sum() > 100
