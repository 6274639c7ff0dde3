"""Mesh files in any state end in a SceneError naming the scene file and the field,
never a library's exception: encodings, garbage, non-finite vertices (regression
locks for the tracebacks trimesh gave, unless a test says otherwise)."""

from __future__ import annotations

import numpy as np
import pytest

from scenes import SceneError, load_scene
from scenes.geometry import build_geometry
from scenes.geometry.meshfile import MeshFileError, decode_obj, load_mesh_file

SPHERE = 'type = "sphere"\ncenter = [0.0, 0.0, 2.0]\nradius = 1.0'

# A closed tetrahedron (outward faces) around (0, 0, 2), as OBJ text.
TETRAHEDRON = (
    "v -0.5 -0.5 1.6\nv 0.5 -0.5 1.6\nv 0.0 0.5 1.6\nv 0.0 0.0 2.4\n"
    "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n"
)


def _scene_with_mesh(tmp_path, minimal_scene_text, mesh_name: str, data: bytes):
    (tmp_path / mesh_name).write_bytes(data)
    assert SPHERE in minimal_scene_text
    path = tmp_path / "scene.toml"
    path.write_text(minimal_scene_text.replace(SPHERE, f'type = "mesh"\nfile = "{mesh_name}"'))
    return path


def _mesh_error(tmp_path, minimal_scene_text, data: bytes, name: str = "m.obj") -> str:
    path = _scene_with_mesh(tmp_path, minimal_scene_text, name, data)
    with pytest.raises(SceneError) as info:
        build_geometry(load_scene(path))
    (line,) = str(info.value).splitlines()
    assert line.startswith(f"{path}: objects[0].file: "), line
    return line


def test_latin1_comment_is_read(tmp_path, minimal_scene_text):
    """Regression lock: a valid OBJ whose comment is Latin-1 (not UTF-8) loads, the
    same mesh as without the comment (trimesh alone needed charset_normalizer)."""
    latin = ("# caf\xe9, na\xefve\n" + TETRAHEDRON).encode("latin-1")
    path = _scene_with_mesh(tmp_path, minimal_scene_text, "m.obj", latin)
    mesh = build_geometry(load_scene(path)).objects[0].mesh
    plain = load_mesh_file(_write(tmp_path / "plain.obj", TETRAHEDRON.encode()))
    np.testing.assert_array_equal(mesh.positions, plain.positions)
    assert mesh.closed and len(mesh.faces) == 4


def test_latin1_outside_a_comment_names_the_line(tmp_path, minimal_scene_text):
    """Regression lock: non-UTF-8 bytes in an object name are an error naming the
    line, not a guess at the encoding."""
    line = _mesh_error(tmp_path, minimal_scene_text,
                       b"o caf\xe9\n" + TETRAHEDRON.encode())
    assert "line 1: byte 0xe9 is not UTF-8" in line and "save the OBJ as UTF-8" in line


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-32"])
def test_wide_encodings_are_refused(tmp_path, minimal_scene_text, encoding):
    """Regression lock: UTF-16/32 OBJ text (with or without byte-order mark) is one
    error saying to re-save as UTF-8 (it was a ModuleNotFoundError traceback)."""
    line = _mesh_error(tmp_path, minimal_scene_text, TETRAHEDRON.encode(encoding))
    assert "save the OBJ as UTF-8" in line


def test_utf8_with_byte_order_mark_is_read(tmp_path):
    """Regression lock: a UTF-8 byte-order mark is not part of the first line."""
    text = decode_obj(b"\xef\xbb\xbf" + TETRAHEDRON.encode())
    assert text.startswith("v -0.5")


@pytest.mark.parametrize("data", [
    b"this is not an obj\n",
    bytes(range(1, 256)) * 8,
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n",
    b"f a b c\nv x y z\n",
    b"v 1 2\nv 0 0 0\nv 1 0 0\nf 1 2 3\n",
    b"",
], ids=["text", "binary", "bad-index", "words", "two-coordinates", "empty"])
def test_garbage_obj_is_one_line(tmp_path, minimal_scene_text, data):
    """Regression lock: garbage in an .obj file is one SceneError line naming the field."""
    _mesh_error(tmp_path, minimal_scene_text, data)


def test_garbage_ply_is_one_line(tmp_path, minimal_scene_text):
    """Regression lock: a PLY header declaring properties it lacks is one line."""
    data = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n"
    line = _mesh_error(tmp_path, minimal_scene_text, data, name="m.ply")
    assert "not a readable PLY mesh" in line


def test_unsupported_format_is_named(tmp_path, minimal_scene_text):
    """Regression lock: only OBJ and PLY are read (the documented formats)."""
    line = _mesh_error(tmp_path, minimal_scene_text, b"solid x\n", name="m.stl")
    assert "unsupported mesh format '.stl'" in line


@pytest.mark.parametrize("value", ["nan", "inf", "1e39"])
def test_non_finite_vertex_is_refused(tmp_path, minimal_scene_text, value):
    """Physical requirement: a vertex that is not finite in float32 is an error; trimesh
    would otherwise delete it and its faces silently, rendering another mesh."""
    data = TETRAHEDRON.replace("v 0.0 0.0 2.4", f"v 0.0 0.0 {value}").encode()
    line = _mesh_error(tmp_path, minimal_scene_text, data)
    assert "1 vertex has coordinates that are not finite in float32" in line


def test_mesh_file_error_is_a_value_error():
    """Regression lock: callers that caught ValueError for a bad mesh still do."""
    with pytest.raises(ValueError):
        decode_obj(b"\xff\xfe" + "v 0 0 0".encode("utf-16-le"))
    assert issubclass(MeshFileError, ValueError)


def _write(path, data: bytes):
    path.write_bytes(data)
    return path
