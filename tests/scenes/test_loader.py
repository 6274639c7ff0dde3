"""File paths in a scene stay inside the scene file's folder unless explicitly
allowed (regression locks of the containment rule)."""

from __future__ import annotations

import os

import pytest

from scenes import SceneError, load_scene
from scenes.loader import containment_root
from scenes.schema import OUTSIDE_PATHS_VARIABLE
from tests.conftest import SCENES

SPHERE = 'type = "sphere"\ncenter = [0.0, 0.0, 2.0]\nradius = 1.0'
TETRAHEDRON = (
    "v -0.5 -0.5 1.6\nv 0.5 -0.5 1.6\nv 0.0 0.5 1.6\nv 0.0 0.0 2.4\n"
    "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n"
)


@pytest.fixture(autouse=True)
def _no_opt_in(monkeypatch):
    monkeypatch.delenv(OUTSIDE_PATHS_VARIABLE, raising=False)


def _scene(folder, minimal_scene_text, file: str):
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "scene.toml"
    path.write_text(minimal_scene_text.replace(SPHERE, f'type = "mesh"\nfile = "{file}"'))
    return path


def _error(path, **options) -> str:
    with pytest.raises(SceneError) as info:
        load_scene(path, **options)
    (line,) = str(info.value).splitlines()
    return line


@pytest.mark.parametrize("file", ["../../../etc/passwd", "/etc/passwd", "../outside.obj"])
def test_paths_leaving_the_folder_are_refused(tmp_path, minimal_scene_text, file):
    """Regression lock: `..` and absolute paths out of the scene's folder are one
    error naming the field and the opt-in, whether or not the file exists."""
    (tmp_path / "outside.obj").write_text(TETRAHEDRON)
    line = _error(_scene(tmp_path / "scenes", minimal_scene_text, file))
    assert f"objects[0].file: {file} resolves to " in line
    assert f"set {OUTSIDE_PATHS_VARIABLE}=1" in line


def test_symlink_out_of_the_folder_is_refused(tmp_path, minimal_scene_text):
    """Regression lock: a symlink inside the folder that points out of it is
    resolved and refused."""
    (tmp_path / "outside.obj").write_text(TETRAHEDRON)
    folder = tmp_path / "scenes"
    folder.mkdir()
    os.symlink(tmp_path / "outside.obj", folder / "link.obj")
    assert "outside the scene's folder" in _error(_scene(folder, minimal_scene_text, "link.obj"))


def test_opt_in_by_keyword_and_by_environment(tmp_path, minimal_scene_text, monkeypatch):
    """Regression lock: the keyword and the environment variable each allow an outside path."""
    (tmp_path / "outside.obj").write_text(TETRAHEDRON)
    path = _scene(tmp_path / "scenes", minimal_scene_text, "../outside.obj")
    expected = str((tmp_path / "outside.obj").resolve())
    assert load_scene(path, allow_outside_paths=True).objects[0].file == expected
    monkeypatch.setenv(OUTSIDE_PATHS_VARIABLE, "1")
    assert load_scene(path).objects[0].file == expected
    assert "resolves to" in _error(path, allow_outside_paths=False)


def test_paths_inside_the_folder_are_fine(tmp_path, minimal_scene_text):
    """Regression lock: a sub-folder, and `..` that comes back inside, are inside."""
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "t.obj").write_text(TETRAHEDRON)
    path = _scene(tmp_path, minimal_scene_text, "meshes/../meshes/t.obj")
    assert load_scene(path).objects[0].file == str((tmp_path / "meshes" / "t.obj").resolve())


def test_bundled_hard_scenes_reach_the_shared_meshes():
    """Regression lock: bundled scenes may use the whole bundled folder (hard/ names
    ../meshes/)."""
    assert containment_root(SCENES / "hard" / "high_ior_tir.toml") == SCENES.resolve()
    scene = load_scene(SCENES / "hard" / "high_ior_tir.toml")
    assert scene.objects[0].file.endswith("meshes/cube.obj")


def test_a_copied_hard_scene_is_contained_to_its_own_folder(tmp_path):
    """Regression lock: outside the bundled folder the rule is the scene's own
    folder, whatever the folder is called."""
    folder = tmp_path / "hard"
    folder.mkdir()
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "cube.obj").write_bytes((SCENES / "meshes" / "cube.obj").read_bytes())
    copy = folder / "high_ior_tir.toml"
    copy.write_bytes((SCENES / "hard" / "high_ior_tir.toml").read_bytes())
    assert containment_root(copy) == folder.resolve()
    assert "objects[0].file: ../meshes/cube.obj resolves to" in _error(copy)
