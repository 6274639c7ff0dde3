"""The `caustics` command: validate / describe / schema, exit codes, no tracebacks."""

from __future__ import annotations

import json
import subprocess
import sys

from harness.cli import default_scene_path, main
from tests.conftest import REPO, SCENES, all_scene_files


def test_validate_all_committed_scenes_json(capsys):
    """`caustics validate scenes/*.toml scenes/hard/*.toml --json` exits 0 and lists
    the effects the issue names for the paper scenes."""
    paths = [str(p) for p in all_scene_files()]
    assert main(["validate", *paths, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    effects = {s["name"]: s["effects"] for s in report["scenes"]}
    assert len(report["scenes"]) == len(paths) and report["errors"] == []
    assert "refraction.double" in effects["glass_sphere"]
    assert "refraction.single" in effects["water_pool"]
    assert "reflection" in effects["metal_ring"]
    assert "dispersion" in effects["dispersion_sphere"]
    assert "absorption" in effects["colored_bunny"]
    assert {s["path"] for s in report["scenes"]} == set(paths)


def test_validate_bad_scene_exits_1_one_line_per_problem(tmp_path, minimal_scene_text, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(minimal_scene_text.replace("radius = 1.0", "radius = -1.0")
                   .replace("ior = 1.5", "ior = 0.5"))
    good = SCENES / "glass_sphere.toml"
    assert main(["validate", str(good), str(bad)]) == 1
    captured = capsys.readouterr()
    assert "glass_sphere" in captured.out
    errors = captured.err.strip().splitlines()
    assert errors == [
        f"error: {bad}: objects[0].radius: must be > 0, got -1",
        f"error: {bad}: objects[0].material.ior: must be >= 1, got 0.5",
    ]


def test_validate_json_reports_errors(tmp_path, minimal_scene_text, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(minimal_scene_text.replace('type = "point"', 'type = "laser"'))
    assert main(["validate", "--json", str(bad)]) == 1
    report = json.loads(capsys.readouterr().out)
    assert report["scenes"] == []
    assert report["errors"][0]["path"] == "light.type"
    assert report["errors"][0]["file"] == str(bad)


def test_no_traceback_in_a_real_process(tmp_path):
    """Run the installed entry point as a user would: exit 1, message, no traceback."""
    bad = tmp_path / "bad.toml"
    bad.write_text("[scene\nname=")
    proc = subprocess.run([sys.executable, "-m", "harness", "validate", str(bad)],
                          capture_output=True, text=True, cwd=REPO, check=False)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith(f"error: {bad}: TOML syntax error")


def test_default_scene_is_glass_sphere_verbatim():
    """The embedded default scene is the committed glass_sphere scene, byte for byte."""
    assert default_scene_path().read_bytes() == (SCENES / "glass_sphere.toml").read_bytes()


def test_describe_default_scene(capsys):
    assert main(["describe"]) == 0
    out = capsys.readouterr().out
    assert "scene glass_sphere" in out
    assert "refraction.double" in out and "10242 vertices" in out


def test_readme_field_reference_is_current(capsys):
    """The README's scene-format reference equals `caustics schema` output."""
    assert main(["schema"]) == 0
    generated = capsys.readouterr().out.strip()
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    section = readme.split("<!-- schema:begin -->")[1].split("<!-- schema:end -->")[0]
    assert section.strip() == generated, "README is stale: regenerate with `caustics schema`"
    for field in ("intensity", "irradiance", "absorption", "splat_sigma", "direct_lighting"):
        assert f"`{field}`" in section
