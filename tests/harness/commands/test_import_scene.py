"""`caustics import`: a file the harness never wrote becomes a scene file that validates
(and, slow, that `caustics compare` runs on with both presets); a refusal is one line per
problem and exit 1; the output must be a .toml (exit 2)."""

from __future__ import annotations

import pytest

from harness.cli import main
from tests.scenes.importers.files import AREA_XML, plain_gltf, plain_xml

#: Settings small enough for a comparison on a 2-core machine in minutes.
_TINY = ["--set", "photons=100000", "--set", "seeds=2", "--set", "spp=2",
         "--set", "reference_time_cap=0.001", "--set", "grid=48", "--set", "caustic_map=128",
         "--set", "positions_map=128", "--set", "shadow_map=128",
         "--set", "receiver_map=[48,48]", "--quick"]


def _unseen(kind: str, folder):
    return plain_gltf(folder / "plain.glb") if kind == "gltf" else plain_xml(folder)


@pytest.mark.parametrize("kind", ["gltf", "mitsuba"])
def test_import_then_validate(kind, tmp_path, capsys):
    source = _unseen(kind, tmp_path)
    assert main(["import", str(source), "-o", str(tmp_path / "out" / "s.toml")]) == 0
    assert "wrote" in capsys.readouterr().err
    assert main(["validate", str(tmp_path / "out" / "s.toml")]) == 0


def test_area_light_is_one_line_then_approximated(tmp_path, capsys):
    source = plain_xml(tmp_path, AREA_XML)
    assert main(["import", str(source), "-o", str(tmp_path / "s.toml")]) == 1
    lines = capsys.readouterr().err.strip().splitlines()
    area = [line for line in lines if "area light" in line]
    assert len(area) == 1 and "'lamp'" in area[0] and "--approximate" in area[0]
    assert not (tmp_path / "s.toml").exists()
    assert main(["import", str(source), "-o", str(tmp_path / "s.toml"), "--approximate"]) == 0
    err = capsys.readouterr().err
    assert "approximated: Mitsuba shape 'lamp'" in err
    text = (tmp_path / "s.toml").read_text()
    assert "Approximated: Mitsuba shape 'lamp'" in text
    # The file's own point light is kept; the area light's stand-in is second in line.
    assert "# from Mitsuba emitter 'bulb'" in text


def test_bad_file_and_usage(tmp_path, capsys):
    broken = tmp_path / "broken.glb"
    broken.write_bytes(b"glTF\x02\x00\x00\x00")
    assert main(["import", str(broken), "-o", str(tmp_path / "s.toml")]) == 1
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith("error:") and "broken.glb" in line
    assert main(["import", str(broken), "-o", str(tmp_path / "s.json")]) == 2


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["gltf", "mitsuba"])
def test_compare_runs_on_an_imported_scene(kind, tmp_path, monkeypatch):
    """Both presets compare on the imported scene (about 3 min per file on 2 cores)."""
    monkeypatch.setenv("CAUSTICS_CACHE_DIR", str(tmp_path / "cache"))
    scene = tmp_path / "s.toml"
    assert main(["import", str(_unseen(kind, tmp_path)), "-o", str(scene)]) == 0
    out = tmp_path / "report"
    assert main(["compare", str(scene), "-o", str(out), "--preset", "paper",
                 "--preset", "strong", *_TINY]) == 0
    assert any(out.rglob("*.html"))
