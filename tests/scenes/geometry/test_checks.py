"""Checks on the built meshes: degenerate and open meshes, the light and the camera
inside closed objects, objects the light cannot reach."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from scenes import SceneError, effects_of, load_scene
from scenes.geometry import build_geometry, scene_warnings
from scenes.geometry.checks import winding_number
from scenes.geometry.mesh import make_mesh
from tests.conftest import SCENES, all_scene_files

SPHERE = ('type = "sphere"\ncenter = [0.0, 0.0, 2.0]\nradius = 1.0\n'
          'material = { type = "dielectric", ior = 1.5 }')
CONDUCTOR = '{ type = "conductor", reflectance = [0.9, 0.9, 0.9] }'
GLASS = '{ type = "dielectric", ior = 1.5 }'


def _box_obj(*, open_top: bool) -> str:
    """A unit box at z in [1.5, 2.5] (outward faces); ``open_top`` drops its lid."""
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    box.apply_translation((0.0, 0.0, 2.0))
    faces = [f for f, n in zip(box.faces, box.face_normals, strict=True)
             if not (open_top and n[2] > 0.5)]
    return trimesh.exchange.obj.export_obj(trimesh.Trimesh(box.vertices, faces,
                                                           process=False))


def _write_scene(tmp_path, text: str, name: str = "scene"):
    # One file name per scene: build_geometry caches by the Scene, file path included.
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


def _mesh_scene(tmp_path, minimal_scene_text, obj_text: str, material: str,
                name: str = "box"):
    (tmp_path / f"{name}.obj").write_text(obj_text)
    assert SPHERE in minimal_scene_text
    return _write_scene(tmp_path, minimal_scene_text.replace(
        SPHERE, f'type = "mesh"\nfile = "{name}.obj"\nmaterial = {material}'), name)


def _problems(path) -> list[str]:
    with pytest.raises(SceneError) as info:
        build_geometry(load_scene(path))
    return str(info.value).splitlines()


def test_open_dielectric_is_refused(tmp_path, minimal_scene_text):
    """Physical requirement: refraction into and out of an object needs a closed
    boundary; an open dielectric mesh is one error naming the field."""
    path = _mesh_scene(tmp_path, minimal_scene_text, _box_obj(open_top=True), GLASS)
    assert _problems(path) == [f"{path}: objects[0].file: mesh is open (not watertight); "
                               "a refractive object must be closed"]


def test_open_conductor_is_flagged_open(tmp_path, minimal_scene_text):
    """Regression lock: an open mirror is legal and reaches the renderers as open
    (``closed`` false: drawn two-sided, never back-face culled in the shadow map),
    and its effects say so; the same box closed stays closed with no flag."""
    path = _mesh_scene(tmp_path, minimal_scene_text, _box_obj(open_top=True), CONDUCTOR)
    scene = load_scene(path)
    assert not build_geometry(scene).objects[0].mesh.closed
    assert "open_mesh" in effects_of(scene) and "reflection" in effects_of(scene)
    closed = load_scene(_mesh_scene(tmp_path, minimal_scene_text,
                                    _box_obj(open_top=False), CONDUCTOR, "closed"))
    assert build_geometry(closed).objects[0].mesh.closed
    assert "open_mesh" not in effects_of(closed)


def test_flat_shaded_closed_mesh_counts_as_closed():
    """Regression lock: the TIR cube repeats each corner per face (flat normals) yet
    is watertight once corners are merged by position, so it stays a dielectric."""
    mesh = build_geometry(load_scene(SCENES / "hard" / "high_ior_tir.toml")).objects[0].mesh
    assert mesh.closed and len(mesh.positions) == 24


@pytest.mark.parametrize(("obj_text", "message"), [
    ("v 0 0 2\nv 1 0 2\nv 2 0 2\nv 3 0 2\nf 1 2 3\nf 2 3 4\n",
     "is degenerate: every face has zero area"),
    ("v 0 0 2\nv 1 0 2\nv 0 1 2\nf 1 2 3\n",
     "has 3 vertices; a closed object needs at least 4"),
    ("v 0 0 2\nv 1 0 2\nv 0 1 2\nv 0.25 0.25 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\nf 1 3 2\n",
     "is degenerate: the closed mesh encloses no volume"),
], ids=["zero-area", "three-vertices", "zero-volume"])
def test_degenerate_meshes_are_refused(tmp_path, minimal_scene_text, obj_text, message):
    """Physical requirement: a mesh with no area (or, closed, no volume) bounds
    nothing light can refract through."""
    path = _mesh_scene(tmp_path, minimal_scene_text, obj_text, GLASS)
    assert _problems(path) == [f"{path}: objects[0].file: {message}"]


def test_mesh_placed_out_of_range_names_the_transform(tmp_path, minimal_scene_text):
    """Physical requirement: a scale that puts vertices beyond the float32 distance
    limit is an error at the transform, not at the file."""
    path = _mesh_scene(tmp_path, minimal_scene_text, _box_obj(open_top=False), GLASS)
    path.write_text(path.read_text().replace(
        'file = "box.obj"', 'file = "box.obj"\ntransform = { scale = 1e18 }'))
    (line,) = _problems(path)
    assert line.startswith(f"{path}: objects[0].transform: places vertices")


@pytest.mark.parametrize("position", ["[0.0, 0.0, 2.2]", "[0.3, -0.3, 1.9]"])
def test_light_inside_sphere_is_an_error(tmp_path, minimal_scene_text, position):
    """Physical requirement: a point light inside a closed glass sphere emits only
    paths that leave through one refraction (L T D), which neither renderer counts."""
    path = _write_scene(tmp_path, minimal_scene_text.replace(
        "position = [0.0, 0.0, 6.0]", f"position = {position}"))
    (line,) = _problems(path)
    assert line.startswith(f"{path}: light.position: the light is inside objects[0] "
                           "(a closed sphere)")


def test_light_inside_closed_mesh_is_an_error(tmp_path, minimal_scene_text):
    """Physical requirement: the same for a closed mesh (winding-number test)."""
    path = _mesh_scene(tmp_path, minimal_scene_text, _box_obj(open_top=False), GLASS)
    path.write_text(path.read_text().replace("position = [0.0, 0.0, 6.0]",
                                             "position = [0.1, 0.2, 2.3]"))
    (line,) = _problems(path)
    assert "light.position: the light is inside objects[0] (a closed mesh)" in line


def test_light_inside_open_conductor_is_legal(tmp_path, minimal_scene_text):
    """Regression lock: an open mesh has no inside; a light in the open box is fine."""
    path = _mesh_scene(tmp_path, minimal_scene_text, _box_obj(open_top=True), CONDUCTOR)
    path.write_text(path.read_text().replace("position = [0.0, 0.0, 6.0]",
                                             "position = [0.0, 0.0, 2.0]"))
    assert not build_geometry(load_scene(path)).objects[0].mesh.closed


def test_camera_inside_object_is_a_warning(tmp_path, minimal_scene_text):
    """Regression lock: the camera inside the sphere is legal, with one warning."""
    path = _write_scene(tmp_path, minimal_scene_text.replace(
        "position = [0.0, -9.0, 7.0]", "position = [0.0, -0.5, 2.0]"))
    warnings = [str(w) for w in scene_warnings(load_scene(path))]
    assert len(warnings) == 1
    assert warnings[0].startswith(f"{path}: camera.position: the camera is inside objects[0]")


def test_object_outside_spot_cone_is_a_warning(tmp_path, minimal_scene_text):
    """Physical requirement: a sphere wholly outside a 10 deg spot cone is unlit and
    forms no caustic; one aimed at it is lit (no warning)."""
    spot = ('type = "spot"\nposition = [0.0, 0.0, 6.0]\ndirection = [DIRECTION]\n'
            "cutoff_angle = 10.0\nintensity = [30.0, 30.0, 30.0]")
    base = minimal_scene_text.replace(
        'type = "point"\nposition = [0.0, 0.0, 6.0]\nintensity = [30.0, 30.0, 30.0]', spot)
    assert base != minimal_scene_text
    away = load_scene(_write_scene(tmp_path, base.replace("DIRECTION", "1.0, 0.0, -1.0"),
                                   "away"))
    assert [w.path for w in scene_warnings(away)] == ["objects[0]"]
    assert "outside the spot light's cone" in scene_warnings(away)[0].message
    toward = load_scene(_write_scene(tmp_path, base.replace("DIRECTION", "0.0, 0.0, -1.0"),
                                     "toward"))
    assert scene_warnings(toward) == []


def test_no_specular_object_is_a_warning(tmp_path, minimal_scene_text):
    """Regression lock: a diffuse-only scene is legal but forms no caustic."""
    path = _write_scene(tmp_path, minimal_scene_text.replace(
        '{ type = "dielectric", ior = 1.5 }', '{ type = "diffuse", albedo = [0.5, 0.5, 0.5] }'))
    (warning,) = scene_warnings(load_scene(path))
    assert warning.path == "objects" and "forms no caustic" in warning.message


@pytest.mark.parametrize("path", all_scene_files(), ids=lambda p: p.stem)
def test_bundled_scenes_have_no_warnings(path):
    """Regression lock: every bundled scene passes the geometry checks silently."""
    assert scene_warnings(load_scene(path)) == []


def test_winding_number_known_values():
    """Physical requirement: the solid angle of a closed surface is 4 pi from inside
    and 0 from outside, however close to the surface (here 1e-3 of its size)."""
    box = trimesh.creation.box(extents=(2.0, 2.0, 2.0))
    mesh = make_mesh(box.vertices, box.vertex_normals, box.faces, closed=True)
    assert winding_number(mesh, (0.1, 0.2, -0.3)) == pytest.approx(1.0)
    assert winding_number(mesh, (3.0, 0.0, 0.0)) == pytest.approx(0.0, abs=1e-12)
    assert winding_number(mesh, (0.999, 0.1, 0.2)) == pytest.approx(1.0)
    assert winding_number(mesh, (1.001, 0.1, 0.2)) == pytest.approx(0.0, abs=1e-9)
    assert np.isfinite(winding_number(mesh, box.vertices[0]))
