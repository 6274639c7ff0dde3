"""Geometry built once per scene: shapes, normals, (u, v) domains, analytic checks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from scenes import SceneError, load_scene, parse_scene
from scenes.geometry import build_geometry
from tests.conftest import SCENES, all_scene_files


@pytest.mark.parametrize("path", all_scene_files(), ids=lambda p: p.stem)
def test_every_scene_builds_finite_unit_normal_meshes(path):
    """Every committed scene's meshes are finite, indexed in range, with unit normals."""
    geometry = build_geometry(load_scene(path))
    meshes = [r.mesh for r in geometry.receivers] + [o.mesh for o in geometry.objects]
    for mesh in meshes:
        assert np.isfinite(mesh.positions).all() and np.isfinite(mesh.normals).all()
        assert mesh.faces.max() < len(mesh.positions)
        np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-5)
    for rec in geometry.receivers:
        assert rec.mesh.uvs is not None and rec.mesh.uvs.shape == (len(rec.mesh.positions), 2)
        umin, umax, vmin, vmax = rec.extent
        assert umin < umax and vmin < vmax


def test_sphere_is_the_same_sphere(minimal_scene_text):
    """Icosphere vertices lie on the sphere, normals are radial, surface area ≈ 4πR²
    (a level-5 icosphere's area is within 0.1 % of the sphere's)."""
    geo = build_geometry(parse_scene(minimal_scene_text)).objects[0].mesh
    r = np.linalg.norm(geo.positions - [0, 0, 2], axis=1)
    np.testing.assert_allclose(r, 1.0, rtol=1e-6)
    np.testing.assert_allclose(geo.normals, (geo.positions - [0, 0, 2]) / r[:, None], atol=1e-6)
    assert geo.area() == pytest.approx(4 * np.pi, rel=1e-3)
    assert geo.closed


def test_plane_uv_is_metres_from_centre(minimal_scene_text):
    rec = build_geometry(parse_scene(minimal_scene_text)).receivers[0]
    np.testing.assert_allclose(rec.mesh.uvs, rec.mesh.positions[:, :2])
    assert rec.extent == (-4.0, 4.0, -4.0, 4.0)
    assert rec.mesh.area() == pytest.approx(64.0)


def test_tilted_plane_frame(minimal_scene_text):
    """A plane with normal +x: u along the projected u_axis, v = n × u."""
    text = minimal_scene_text.replace("albedo = [0.5, 0.5, 0.5]",
                                      "albedo = [0.5, 0.5, 0.5]\nnormal = [1.0, 0.0, 0.0]\n"
                                      "u_axis = [0.0, 1.0, 0.0]")
    rec = build_geometry(parse_scene(text)).receivers[0]
    p, uv = rec.mesh.positions, rec.mesh.uvs
    np.testing.assert_allclose(p[:, 1], uv[:, 0], atol=1e-6)   # u along +y
    np.testing.assert_allclose(p[:, 2], uv[:, 1], atol=1e-6)   # v = x × y = +z
    np.testing.assert_allclose(rec.mesh.normals, [[1, 0, 0]] * 4)


def test_water_surface_normals_match_height_gradient():
    """Water normals are (-∂h/∂x, -∂h/∂y, 1) normalised. Check them against central
    differences of the heights of the same surface built 6x finer (595² vertices,
    spacing 0.0101 m, sharing every 6th vertex with the 100² grid). For the plop's
    0.35 m wavelength that difference has relative error (kh)²/6 ≈ 0.55 % of a slope
    of at most A·k ≈ 0.4, so 0.01 in the normal's components is a safe bound."""
    scene = load_scene(SCENES / "water_pool.toml")
    water = scene.objects[0]
    mesh = build_geometry(scene).objects[0].mesh
    fine_water = dataclasses.replace(water, resolution=(595, 595))
    fine = build_geometry(dataclasses.replace(scene, objects=(fine_water,))).objects[0].mesh
    z = fine.positions[:, 2].reshape(595, 595).astype(np.float64)
    dzdy, dzdx = np.gradient(z, 6.0 / 594)
    normal = np.stack([-dzdx, -dzdy, np.ones_like(z)], -1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    coarse = mesh.normals.reshape(100, 100, 3)
    inner = (slice(1, -1), slice(1, -1))
    np.testing.assert_allclose(coarse[inner], normal[::6, ::6][inner], atol=0.01)
    assert np.ptp(mesh.positions[:, 2]) > 0.02  # the waves and the plop are really there


def test_plop_changes_with_time():
    """A plop is absent before its start time and spreads outward afterwards."""
    scene = load_scene(SCENES / "water_pool.toml")
    water = scene.objects[0]
    still = dataclasses.replace(water, waves=(), time=water.plops[0].start - 0.1)
    later = dataclasses.replace(water, waves=(), time=water.plops[0].start + 1.0)
    z_before = build_geometry(dataclasses.replace(scene, objects=(still,))).objects[0].mesh
    z_after = build_geometry(dataclasses.replace(scene, objects=(later,))).objects[0].mesh
    assert np.ptp(z_before.positions[:, 2]) == 0.0
    assert np.ptp(z_after.positions[:, 2]) > 0.005


def test_ring_normals_point_to_axis():
    ring = build_geometry(load_scene(SCENES / "metal_ring.toml")).objects[0].mesh
    radial = ring.positions[:, :2] / np.linalg.norm(ring.positions[:, :2], axis=1, keepdims=True)
    np.testing.assert_allclose(ring.normals[:, :2], -radial, atol=1e-6)
    assert not ring.closed


def test_bunny_fit_and_transform():
    """The bunny is fitted to 2 m and placed above the floor, closed, smooth normals."""
    mesh = build_geometry(load_scene(SCENES / "bunny.toml")).objects[0].mesh
    lo, hi = mesh.bounds
    assert max(hi - lo) == pytest.approx(2.0, rel=1e-5)
    assert lo[2] > 0.0
    assert mesh.closed and len(mesh.faces) > 50_000


def test_high_ior_cube_keeps_flat_normals():
    """The TIR cube has one normal per face (24 vertices), not rounded corners."""
    mesh = build_geometry(load_scene(SCENES / "hard" / "high_ior_tir.toml")).objects[0].mesh
    assert len(mesh.positions) == 24
    assert len(np.unique(mesh.normals.round(5), axis=0)) == 6


def test_step_terrain_has_discontinuities():
    rec = build_geometry(load_scene(SCENES / "hard" / "step_terrain.toml")).receivers[0]
    z = np.unique(rec.mesh.positions[:, 2].round(6))
    assert len(z) == 17  # x in [-4, 4] m, floor(x / 0.5) in -8..8: 17 terrace levels


def test_corrupt_mesh_names_the_field(tmp_path, minimal_scene_text):
    """A mesh file that exists but is not a mesh: error names the object's file field."""
    (tmp_path / "broken.obj").write_text("this is not an obj\n")
    text = minimal_scene_text.replace(
        'type = "sphere"\ncenter = [0.0, 0.0, 2.0]\nradius = 1.0',
        'type = "mesh"\nfile = "broken.obj"')
    path = tmp_path / "s.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as info:
        build_geometry(load_scene(path))
    assert f"{path}: objects[0].file:" in str(info.value)


def test_bad_height_array_names_the_field(tmp_path, minimal_scene_text):
    np.save(tmp_path / "h.npy", np.array([1.0, 2.0, 3.0]))
    text = minimal_scene_text.replace(
        'type = "plane"\ncenter = [0.0, 0.0, 0.0]\nsize = [8.0, 8.0]',
        'type = "heightfield"\ncenter = [0.0, 0.0, 0.0]\nsize = [8.0, 8.0]\n'
        'height = { type = "file", file = "h.npy" }')
    path = tmp_path / "s.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as info:
        build_geometry(load_scene(path))
    assert f"{path}: receivers[0].height.file: must be a 2-D array" in str(info.value)


def test_height_array_file_is_interpolated(tmp_path, minimal_scene_text):
    """A 2x2 height array spanning the receiver: corners exact, centre the mean."""
    np.save(tmp_path / "h.npy", np.array([[0.0, 1.0], [2.0, 3.0]]))
    text = minimal_scene_text.replace(
        'type = "plane"\ncenter = [0.0, 0.0, 0.0]\nsize = [8.0, 8.0]',
        'type = "heightfield"\ncenter = [0.0, 0.0, 0.0]\nsize = [8.0, 8.0]\n'
        'resolution = [3, 3]\nheight = { type = "file", file = "h.npy" }')
    path = tmp_path / "s.toml"
    path.write_text(text)
    z = build_geometry(load_scene(path)).receivers[0].mesh.positions[:, 2].reshape(3, 3)
    np.testing.assert_allclose(z[[0, 0, 2, 2], [0, 2, 0, 2]], [0, 1, 2, 3])
    assert z[1, 1] == pytest.approx(1.5)
