"""`caustics validate` (harness/commands/scene.py) on scenes whose problems only the
geometry shows: the report is always printed, errors and warnings one line each.
Regression locks; kept beside the scene tests because they exercise the scene checks
end to end."""

from __future__ import annotations

import json

from harness.cli import main

SPHERE = 'type = "sphere"\ncenter = [0.0, 0.0, 2.0]\nradius = 1.0'


def test_validate_json_with_a_bad_mesh_still_prints_json(tmp_path, minimal_scene_text, capsys):
    """Regression lock: a UTF-16 mesh once ended validate --json in a traceback and
    no output; now the JSON names the error, next to the good scene's entry."""
    (tmp_path / "wide.obj").write_bytes("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".encode("utf-16"))
    bad = tmp_path / "bad.toml"
    bad.write_text(minimal_scene_text.replace(SPHERE, 'type = "mesh"\nfile = "wide.obj"'))
    good = tmp_path / "good.toml"
    good.write_text(minimal_scene_text)
    assert main(["validate", "--json", str(good), str(bad)]) == 1
    captured = capsys.readouterr()
    report = json.loads(captured.out)
    assert [s["path"] for s in report["scenes"]] == [str(good)]
    assert report["warnings"] == []
    (error,) = report["errors"]
    assert (error["file"], error["path"]) == (str(bad), "objects[0].file")
    assert "UTF-16" in error["message"]
    assert "Traceback" not in captured.err


def test_warnings_in_json_and_on_stderr(tmp_path, minimal_scene_text, capsys):
    """Regression lock: a legal but suspect scene (camera inside the sphere) exits 0
    with the warning in the JSON and as one `warning:` line on stderr."""
    path = tmp_path / "inside.toml"
    path.write_text(minimal_scene_text.replace("position = [0.0, -9.0, 7.0]",
                                               "position = [0.0, -0.5, 2.0]"))
    assert main(["validate", "--json", str(path)]) == 0
    captured = capsys.readouterr()
    report = json.loads(captured.out)
    assert report["errors"] == []
    (warning,) = report["warnings"]
    assert (warning["file"], warning["path"]) == (str(path), "camera.position")
    lines = captured.err.strip().splitlines()
    assert lines == [f"warning: {path}: camera.position: {warning['message']}"]


def test_validate_text_reports_light_inside_object(tmp_path, minimal_scene_text, capsys):
    """Regression lock: a light inside the glass sphere is an error line naming the field."""
    path = tmp_path / "lamp.toml"
    path.write_text(minimal_scene_text.replace("position = [0.0, 0.0, 6.0]",
                                               "position = [0.0, 0.0, 2.0]"))
    assert main(["validate", str(path)]) == 1
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith(f"error: {path}: light.position: the light is inside objects[0]")
