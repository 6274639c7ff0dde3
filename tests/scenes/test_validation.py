"""Each kind of bad scene gives a SceneError whose message names the file and the
exact field path; nothing else escapes."""

from __future__ import annotations

import re

import pytest

from scenes import SceneError, load_scene, parse_scene


def _errors(text: str, tmp_path, name: str = "bad.toml") -> list[str]:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SceneError) as info:
        load_scene(path)
    lines = str(info.value).splitlines()
    assert lines, "a SceneError must carry at least one problem"
    for line in lines:
        assert line.startswith(str(path)), f"problem does not name the file: {line}"
    return lines


def _replace(text: str, old: str, new: str) -> str:
    assert old in text, f"fixture text lacks {old!r}"
    return text.replace(old, new, 1)


def test_toml_syntax_error_names_file_and_line(minimal_scene_text, tmp_path):
    """A TOML syntax error is reported with the file and the parser's line/column."""
    lines = _errors(_replace(minimal_scene_text, "radius = 1.0", "radius = = 1.0"), tmp_path)
    assert len(lines) == 1
    assert "TOML syntax error" in lines[0] and re.search(r"line \d+", lines[0])


def test_missing_required_field(minimal_scene_text, tmp_path):
    lines = _errors(_replace(minimal_scene_text, "radius = 1.0\n", ""), tmp_path)
    assert lines == [f"{tmp_path / 'bad.toml'}: objects[0].radius: missing required field"]


def test_missing_table(minimal_scene_text, tmp_path):
    text = minimal_scene_text.split("[camera]")[0]
    lines = _errors(text, tmp_path)
    assert any(line.endswith("camera: missing required field") for line in lines)


def test_wrong_type(minimal_scene_text, tmp_path):
    lines = _errors(_replace(minimal_scene_text, "radius = 1.0", 'radius = "big"'), tmp_path)
    assert lines == [
        f"{tmp_path / 'bad.toml'}: objects[0].radius: expected a number, got string"
    ]


def test_boolean_is_not_a_number(minimal_scene_text, tmp_path):
    """TOML booleans must not slip through as 0/1 (bool is an int in Python)."""
    lines = _errors(_replace(minimal_scene_text, "radius = 1.0", "radius = true"), tmp_path)
    assert "objects[0].radius: expected a number, got boolean" in lines[0]


def test_vector_of_wrong_length(minimal_scene_text, tmp_path):
    lines = _errors(
        _replace(minimal_scene_text, "position = [0.0, 0.0, 6.0]", "position = [0.0, 6.0]"),
        tmp_path,
    )
    assert lines == [
        f"{tmp_path / 'bad.toml'}: light.position: expected an array of 3 numbers, got 2"
    ]


def test_vector_component_of_wrong_type(minimal_scene_text, tmp_path):
    lines = _errors(
        _replace(minimal_scene_text, "albedo = [0.5, 0.5, 0.5]", 'albedo = [0.5, "x", 0.5]'),
        tmp_path,
    )
    assert "receivers[0].albedo[1]: expected a number, got string" in lines[0]


def test_negative_radius(minimal_scene_text, tmp_path):
    lines = _errors(_replace(minimal_scene_text, "radius = 1.0", "radius = -1.0"), tmp_path)
    assert lines == [f"{tmp_path / 'bad.toml'}: objects[0].radius: must be > 0, got -1"]


def test_ior_below_one(minimal_scene_text, tmp_path):
    lines = _errors(_replace(minimal_scene_text, "ior = 1.5", "ior = 0.9"), tmp_path)
    assert lines == [
        f"{tmp_path / 'bad.toml'}: objects[0].material.ior: must be >= 1, got 0.9"
    ]


def test_per_channel_ior_below_one(minimal_scene_text, tmp_path):
    lines = _errors(_replace(minimal_scene_text, "ior = 1.5", "ior = [1.5, 0.5, 1.6]"), tmp_path)
    assert "objects[0].material.ior: must be >= 1, got [1.5, 0.5, 1.6]" in lines[0]


def test_unknown_light_type(minimal_scene_text, tmp_path):
    lines = _errors(_replace(minimal_scene_text, 'type = "point"', 'type = "laser"'), tmp_path)
    assert len(lines) == 1
    assert "light.type: unknown type 'laser'" in lines[0]
    assert "'point'" in lines[0] and "'directional'" in lines[0]


def test_missing_mesh_file(minimal_scene_text, tmp_path):
    text = _replace(
        minimal_scene_text,
        'type = "sphere"\ncenter = [0.0, 0.0, 2.0]\nradius = 1.0',
        'type = "mesh"\nfile = "no_such_mesh.obj"',
    )
    lines = _errors(text, tmp_path)
    assert len(lines) == 1
    assert "objects[0].file: file not found: no_such_mesh.obj" in lines[0]


def test_unknown_key(minimal_scene_text, tmp_path):
    lines = _errors(_replace(minimal_scene_text, "radius = 1.0", "radius = 1.0\nradus = 2.0"),
                    tmp_path)
    assert len(lines) == 1
    assert "objects[0].radus: unknown key" in lines[0]


def test_unknown_top_level_table(minimal_scene_text, tmp_path):
    lines = _errors(minimal_scene_text + "\n[lights]\ntype = 'point'\n", tmp_path)
    assert any("lights: unknown key" in line for line in lines)


def test_all_problems_reported_at_once(minimal_scene_text, tmp_path):
    """Several independent mistakes give one line each, not just the first."""
    text = _replace(minimal_scene_text, "radius = 1.0", "radius = -2.0")
    text = _replace(text, "ior = 1.5", "ior = 0.5")
    text = _replace(text, "fov = 40.0", "fov = 400.0")
    lines = _errors(text, tmp_path)
    paths = sorted(line.split(": ")[1] for line in lines)
    assert paths == ["camera.fov", "objects[0].material.ior", "objects[0].radius"]


def test_non_finite_number(minimal_scene_text, tmp_path):
    lines = _errors(_replace(minimal_scene_text, "radius = 1.0", "radius = nan"), tmp_path)
    assert "objects[0].radius: must be finite" in lines[0]


def test_integer_field_rejects_float(minimal_scene_text, tmp_path):
    text = _replace(minimal_scene_text, "resolution = [64, 64]", "resolution = [64.5, 64]")
    lines = _errors(text, tmp_path)
    assert "camera.resolution[0]: expected an integer" in lines[0]


def test_choice_field(minimal_scene_text, tmp_path):
    lines = _errors(minimal_scene_text + '\n[settings]\nestimator = "bisection"\n', tmp_path)
    assert "settings.estimator: must be one of 'modified', 'newton', 'secant'" in lines[0]


def test_cross_field_check(minimal_scene_text, tmp_path):
    """A camera looking at its own position has no viewing direction."""
    text = _replace(minimal_scene_text, "look_at = [0.0, 0.0, 0.5]", "look_at = [0.0, -9.0, 7.0]")
    lines = _errors(text, tmp_path)
    assert "camera.look_at: must differ from position" in lines[0]


def test_no_objects(minimal_scene_text, tmp_path):
    # A top-level key must come before the first table header.
    text = "objects = []\n" + minimal_scene_text.split("[[objects]]")[0] + (
        "[camera]" + minimal_scene_text.split("[camera]")[1]
    )
    lines = _errors(text, tmp_path)
    assert any("objects: needs at least one caustic object" in line for line in lines)


def test_unreadable_file(tmp_path):
    with pytest.raises(SceneError, match="cannot read file"):
        load_scene(tmp_path / "absent.toml")


def test_not_utf8(tmp_path):
    path = tmp_path / "binary.toml"
    path.write_bytes(b"\xff\xfe\x00name")
    with pytest.raises(SceneError, match="not UTF-8"):
        load_scene(path)


def test_valid_scene_parses_to_frozen_dataclasses(minimal_scene_text):
    scene = parse_scene(minimal_scene_text, file="mem.toml")
    assert scene.name == "minimal" and scene.source == "mem.toml"
    assert scene.objects[0].material.iors == (1.5, 1.5, 1.5)
    with pytest.raises(AttributeError):
        scene.objects[0].radius = 2.0  # type: ignore[misc]
    assert hash(scene) == hash(parse_scene(minimal_scene_text, file="mem.toml"))
