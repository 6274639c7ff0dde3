"""``caustics reference`` writes the EXRs and the result.json keys the README's CLI table names."""

from __future__ import annotations

import json

from harness.cli import main
from renderers.exr import read_exr
from tests.renderers.mitsuba.test_cache import TINY


def test_reference_command_writes_files_and_keys(tmp_path):
    scene = tmp_path / "tiny.toml"
    scene.write_text(TINY)
    out = tmp_path / "out"
    status = main(["reference", str(scene), "-o", str(out), "--photons", "8192", "--spp", "2",
                   "--seed", "3", "--target-noise", "0.5", "--cache-dir", str(tmp_path / "c"),
                   "-q"])
    assert status == 0
    document = json.loads((out / "result.json").read_text())
    for key in ("receiver_extent", "event_chains", "photons", "spp", "seed", "relative_noise",
                "timings", "variant", "cut_flux_fraction", "camera_cut_fraction"):
        assert key in document, key
    assert document["receiver_extent"] == [[-2.0, 2.0, -2.0, 2.0]]
    assert document["seed"] == 3 and document["spp"] == 2
    assert document["photons"] <= 8192 and document["target_noise"] == 0.5
    assert read_exr(out / "camera.exr")["RGB"].shape == (16, 16, 3)
    layers = read_exr(out / "receiver_irradiance.exr")
    assert layers["RGB"].shape == (16, 16, 3) and layers["variance"].shape == (16, 16, 3)


def test_bad_scene_is_a_one_line_error(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(TINY.replace("ior = 1.5", "ior = 0.5"))
    assert main(["reference", str(bad), "-o", str(tmp_path / "o"), "-q"]) == 1
    assert "objects[0].material.ior" in capsys.readouterr().err
