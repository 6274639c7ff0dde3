"""The `caustics` command: validate / describe / schema, exit codes, no tracebacks."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from harness.cli import main
from scenes import SceneError, default_scene_path, resolve_scene
from tests.conftest import REPO, SCENES, all_scene_files


def test_validate_all_committed_scenes_json(capsys):
    """`caustics validate scenes/*.toml scenes/hard/*.toml --json` exits 0 and lists
    the effects the README's scene table names for the paper scenes."""
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


def test_default_scene_is_the_bundled_glass_sphere(capsys):
    """The default scene is the bundled glass_sphere file itself, not a copy of it."""
    assert default_scene_path().resolve() == (SCENES / "glass_sphere.toml").resolve()
    assert main(["validate"]) == 0
    assert "[glass_sphere]" in capsys.readouterr().out


def test_bundled_scenes_resolve_by_name_and_unknown_names_list_them(tmp_path, monkeypatch):
    """A bare name finds the bundled file from any directory; a path still wins; an
    unknown name is one SceneError that lists the bundled names."""
    monkeypatch.chdir(tmp_path)
    assert resolve_scene("bunny") == SCENES / "bunny.toml"
    assert resolve_scene("hard/tiny_scale") == SCENES / "hard" / "tiny_scale.toml"
    assert resolve_scene("tiny_scale") == SCENES / "hard" / "tiny_scale.toml"
    local = tmp_path / "bunny"
    local.write_text("")
    assert resolve_scene("bunny").resolve() == local
    with pytest.raises(SceneError) as info:
        resolve_scene("../scenes/bunny")
    assert "no bundled scene" in str(info.value) and "glass_sphere" in str(info.value)


# Blocks the heavy libraries in a fresh interpreter: importing any of them raises.
_BLOCKED = """
import sys
BLOCKED = ("mitsuba", "drjit", "moderngl", "matplotlib", "playwright")
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ImportError(f"{name} is blocked in this test")
sys.meta_path.insert(0, Block())
from harness.cli import main
code = main(sys.argv[1:])
loaded = sorted(m for m in sys.modules if m.split(".")[0] in BLOCKED)
print("loaded:", loaded)
sys.exit(code)
"""


@pytest.mark.parametrize("argv", [["validate", "--no-trace", "glass_sphere", "hard/grazing_light"],
                                  ["describe", "water_pool"], ["schema"]])
def test_scene_commands_run_from_tmp_without_heavy_libraries(tmp_path, argv):
    """From an unrelated directory, with mitsuba, drjit, moderngl, matplotlib and
    playwright unimportable, the scene commands still work and load none of them
    (``validate`` without its caustic probe, which traces with Mitsuba)."""
    proc = subprocess.run([sys.executable, "-c", _BLOCKED, *argv], capture_output=True,
                          text=True, cwd=tmp_path, check=False)
    assert proc.returncode == 0, proc.stderr
    assert "loaded: []" in proc.stdout


def test_help_loads_no_handler_module(tmp_path):
    """`caustics --help` builds the parser only: no command module, no heavy library."""
    script = ("import sys\nfrom harness.cli import build_parser\nbuild_parser()\n"
              "print(sorted(m for m in sys.modules if m.startswith(('harness.commands', "
              "'renderers', 'reports', 'mitsuba', 'drjit', 'moderngl', 'matplotlib'))))")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          cwd=tmp_path, check=True)
    assert proc.stdout.strip() == "[]"


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
