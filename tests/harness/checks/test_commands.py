"""``caustics golden`` and ``caustics calibrate``: the bundled references verify, a
missing folder is a one-line error naming it, and calibration writes regression locks
that load, say how they were calibrated, and hold for the render they came from."""

from __future__ import annotations

import json
import shutil

from harness.checks import GOLDEN_DIR
from harness.checks.bounds import load_locks
from harness.checks.golden import golden_scene, load_golden
from harness.checks.locks import lock_checks, realtime_maps
from harness.cli import main
from scenes import with_settings
from tests.conftest import SCENES


def test_golden_command_verifies_the_bundled_references(capsys):
    assert main(["golden"]) == 0
    out = capsys.readouterr().out
    assert out.count("ok  ") == 7 and "128x128" in out and "16 seeds" in out


def test_golden_command_names_a_missing_folder(tmp_path, capsys):
    assert main(["golden", "--dir", str(tmp_path / "nowhere")]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"error: {tmp_path / 'nowhere' / 'manifest.json'}: unreadable")
    assert err.count("\n") == 1


def test_calibrate_writes_locks_that_hold(tmp_path, capsys, ctx):
    """One scene (glass_sphere), no extra reference (``--extra 0``): 5 locks per
    preset (the flux ratio from both sides), each with its calibration (the jitter
    included), and all of them hold for the render they were calibrated on."""
    golden = tmp_path / "golden"
    shutil.copytree(GOLDEN_DIR, golden)
    manifest = json.loads((golden / "manifest.json").read_text())
    manifest["scenes"] = {"glass_sphere": manifest["scenes"]["glass_sphere"]}
    (golden / "manifest.json").write_text(json.dumps(manifest))
    out = tmp_path / "locks.toml"
    assert main(["calibrate", "--golden", str(golden), "--extra", "0", "-o", str(out)]) == 0
    assert "wrote 10 regression locks for 1 scenes" in capsys.readouterr().out
    locks = load_locks(out)
    assert {b.scene for b in locks} == {"glass_sphere", "glass_sphere@strong"}
    assert all("jitter 1e-05 m" in b.provenance for b in locks)
    reference = load_golden(golden, "glass_sphere")
    for method in ("paper", "strong"):
        scene = with_settings(golden_scene(SCENES, "glass_sphere"), {"preset": method})
        checks = lock_checks(scene, method, realtime_maps(scene, ctx=ctx), reference, locks)
        assert len(checks) == 5 and all(c.passed for c in checks), checks
