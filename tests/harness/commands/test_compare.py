"""`caustics compare` end to end on a small glass sphere: files, numbers, cache.

The references are SMALL's budget, in the run's reference cache (``tests/conftest.py``):
the committed scene's once, the 48 x 48 copy's once for this file and
``tests/harness/compare/test_consistency.py`` (which holds the test of everything a
quick compare of both presets writes, on its one run)."""

from __future__ import annotations

import json

from harness.cli import main
from tests.conftest import SCENES

#: Small references: the starting photon budget only (``reference_time_cap`` of 1 ms
#: stops the launches past it). Uncapped, glass_sphere's reference traced on toward
#: ``target_noise`` (1.15 M photons a seed instead of 0.1 M), and the camera tracer's
#: lookup maps, whose photons scale with it, took 67 s a reference instead of 6.
SMALL = ["--set", "photons=100000", "--set", "seeds=2", "--set", "spp=2",
         "--set", "reference_time_cap=0.001",
         "--set", "grid=48", "--set", "caustic_map=128", "--set", "positions_map=128",
         "--set", "shadow_map=128", "--set", "receiver_map=[48, 48]"]
#: SMALL's reference budget alone (the method at the scene's own settings).
REFERENCE = SMALL[:8]


def _small_scene(tmp_path):
    text = (SCENES / "glass_sphere.toml").read_text().replace("resolution = [512, 512]",
                                                                "resolution = [48, 48]")
    path = tmp_path / "glass_sphere.toml"
    path.write_text(text)
    return path


def test_compare_rejects_unknown_study(tmp_path, capsys):
    assert main(["compare", str(_small_scene(tmp_path)), "-o", str(tmp_path / "o"),
                 "--studies", "metrics,bogus", "-q"]) == 2
    assert "unknown study bogus" in capsys.readouterr().err


def test_compare_checks_every_kind_like_the_test_suite(tmp_path, capsys, monkeypatch):
    """Run from an unrelated directory, `compare glass_sphere` finds the bundled scene,
    its golden references and locks, names the method's images `<view>_method.exr`,
    runs the three kinds of accuracy check and says how many of each it checked:
    physical requirements on this run (the paper preset's spurious TIR in a sphere is
    a known gap, not a failure), the regression locks at the golden settings (all
    five hold, each on receiver 0); the method targets only at the scene's own
    settings, so not with a reduced photon budget (and the report says why). With 0
    iterations a lock fails and --fail-on-checks exits 3. A modified copy of the scene
    gets the physical requirements only."""
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    # REFERENCE's references, in the run's cache; the method renders at the scene's
    # own settings (the locks' calibration).
    fast = ["--studies", "metrics", "-q", "--preset", "paper", *REFERENCE]
    scene = "glass_sphere"
    assert main(["compare", scene, "-o", str(out), *fast, "--fail-on-checks"]) == 0
    summary = capsys.readouterr().out
    data = json.loads((out / "glass_sphere-paper" / "metrics.json").read_text())
    assert data["scene"]["source"].endswith("scenes/glass_sphere.toml")
    assert data["files"]["receiver0/method"] == "receiver0_method.exr"
    assert (out / "glass_sphere-paper" / "receiver0_method.exr").is_file()
    by_kind = {}
    for t in data["checks"]:
        by_kind.setdefault(t["kind"], []).append(t)
    assert len(by_kind["regression lock"]) == 5
    assert all(t["passed"] for t in by_kind["regression lock"])
    assert {t["view"] for t in by_kind["regression lock"]} == {"receiver0"}
    physical = {t["metric"]: t for t in by_kind["physical requirement"]}
    assert {"finite", "energy", "flux agreement", "no TIR in a sphere", "reference flux",
            "reference focus"} <= set(physical)
    assert physical["no TIR in a sphere"]["gap"] and not physical["no TIR in a sphere"]["passed"]
    assert "method target" not in by_kind
    assert "settings differ" in data["provenance"]["checks_not_applied"]["method target"]
    assert f"physical requirements checked: {len(physical)} (" in summary
    assert "1 known gap)" in summary
    assert "regression locks checked: 5 (5 passed)" in summary
    assert "method targets checked: 0 (0 passed)" in summary
    assert main(["compare", scene, "-o", str(out), *fast, "--iterations", "0",
                 "--fail-on-checks"]) == 3
    data = json.loads((out / "glass_sphere-paper" / "metrics.json").read_text())
    locks = [t for t in data["checks"] if t["kind"] == "regression lock"]
    assert not all(t["passed"] for t in locks)
    copy = _small_scene(tmp_path)
    assert main(["compare", str(copy), "-o", str(tmp_path / "copy"), *fast, *SMALL[8:]]) == 0
    data = json.loads((tmp_path / "copy" / "glass_sphere-paper" / "metrics.json").read_text())
    assert {t["kind"] for t in data["checks"]} == {"physical requirement"}


def test_missing_locks_file_is_an_error(tmp_path, capsys):
    """A named locks file that does not exist stops the run before anything renders,
    with one line naming it, and exit 1 even with --fail-on-thresholds; it never
    means "no checks"."""
    missing = tmp_path / "missing.toml"
    argv = ["compare", "glass_sphere", "-o", str(tmp_path / "out"), "--thresholds",
            str(missing), "--fail-on-thresholds", "-q"]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err == f"error: {missing}: no such file\n"
    assert not (tmp_path / "out").exists()
