"""`caustics compare` end to end on a small glass sphere: files, numbers, cache.

The references are SMALL's budget, in the run's reference cache (``tests/conftest.py``):
the committed scene's are traced once for the two tests that compare it, the 48 x 48
copy's once for the tests that compare the copy."""

from __future__ import annotations

import csv
import json

import pytest

from harness.cli import main
from harness.studies.pareto import equal_error_speedup
from tests.conftest import REPO, SCENES

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


def test_compare_writes_everything_and_reuses_the_cache(tmp_path, capsys):
    """A quick compare writes the report, metrics.json (each metric beside its noise
    floor), convergence.csv (every estimator, plain and safeguarded, iterations
    0..4), cost_accuracy.csv (real-time and reference series, Pareto flags), records
    the equal-error speedups (warm and cold, regression lock: each is what the CSV's
    times of the same kind give) and the paper's claims; a second run takes both
    references from the cache."""
    scene, out = _small_scene(tmp_path), tmp_path / "out"
    argv = ["compare", str(scene), "-o", str(out), "--quick", "-q", *SMALL]
    assert main(argv) == 0
    summary = capsys.readouterr().out
    assert "glass_sphere" in summary and "equal-error speedup" in summary
    assert "paper" in summary and "strong" in summary
    strong = json.loads((out / "glass_sphere-strong" / "metrics.json").read_text())
    assert strong["method"]["name"] == "strong"
    assert strong["provenance"]["method"]["preset"] == "strong"
    assert strong["settings"]["splat"] == "triangles"
    assert strong["provenance"]["reference"]["cache"] == "hit"    # shared with paper
    index = (out / "index.html").read_text()
    assert index.index("glass_sphere-paper/") < index.index("glass_sphere-strong/")
    folder = out / "glass_sphere-paper"
    assert (out / "index.html").is_file() and (folder / "index.html").is_file()
    data = json.loads((folder / "metrics.json").read_text())
    relmse = [m for m in data["metrics"] if (m["view"], m["region"], m["metric"])
              == ("receiver0", "caustic", "relmse")]
    assert len(relmse) == 1 and relmse[0]["value"] > 0 and relmse[0]["noise_floor"] > 0
    assert {m["view"] for m in data["metrics"]} == {"camera", "receiver0"}
    # The object seen through is a camera region of its own, scored.
    assert {m["region"] for m in data["metrics"] if m["view"] == "camera"} == {
        "full", "object", "object_masked"}
    assert len(data["claims"]) == 2
    assert all(text.startswith(("holds", "does not hold", "undecided at this noise",
                                "not measured"))
               for text in data["claims"].values())
    assert "caustic_map" in data["provenance"]["method"]["passes"]
    assert data["provenance"]["reference"]["event_chains"]
    for name in data["files"].values():
        assert (folder / name).is_file(), name
    for name in ("convergence.pdf", "cost_accuracy.pdf"):
        assert (folder / name).read_bytes().startswith(b"%PDF"), name
    with (folder / "convergence.csv").open() as f:
        rows = list(csv.DictReader(f))
    keys = {(r["estimator"], r["safeguarded"], int(r["iteration"])) for r in rows}
    assert keys == {(e, s, k) for e in ("modified", "newton", "secant")
                    for s in ("False", "True") for k in range(5)}
    with (folder / "cost_accuracy.csv").open() as f:
        cost = list(csv.DictReader(f))
    assert {r["series"] for r in cost} == {"caustics_mapping", "reference"}
    assert any(r["pareto"] == "True" for r in cost)
    # Both speedups are the ones the CSV's own times and excess errors give (the
    # reference's curve fitted on warm times; cold adds its build and compile seconds,
    # against the method's cold time; the scene-settings row is the method's point).
    speedups = data["equal_error_speedup"]
    base = next(r for r in cost if r["label"] == "scene settings")
    reference = [r for r in cost if r["series"] == "reference"]
    one_off = speedups["reference"]["build_s"] + speedups["reference"]["compile_s"]
    for kind in ("warm", "cold"):
        expected = equal_error_speedup(
            float(base[f"time_{kind}_s"]), float(base["excess"]),
            [float(r["time_warm_s"]) for r in reference],
            [float(r["excess"]) for r in reference],
            reference_stderrs=[float(r["excess_stderr"]) for r in reference],
            method_stderr=float(base["excess_stderr"]),
            overhead_s=one_off if kind == "cold" else 0.0)
        got = speedups[kind]
        assert got["kind"] == expected.kind, kind
        assert (got["speedup"], got["reference_time"]) == pytest.approx(
            (expected.speedup, expected.reference_time), rel=1e-9), kind
    assert set(speedups["method"]) == set(speedups["reference"]) == {"build_s", "compile_s"}
    assert main(argv[:-len(SMALL)] + SMALL + ["--studies", "metrics", "--preset", "paper"]) == 0
    again = json.loads((folder / "metrics.json").read_text())
    assert again["provenance"]["reference"]["cache"] == "hit"
    assert again["provenance"]["independent_reference"]["cache"] == "hit"


def test_compare_rejects_unknown_study(tmp_path, capsys):
    assert main(["compare", str(_small_scene(tmp_path)), "-o", str(tmp_path / "o"),
                 "--studies", "metrics,bogus", "-q"]) == 2
    assert "unknown study bogus" in capsys.readouterr().err


def test_compare_checks_every_kind_like_the_test_suite(tmp_path, capsys, monkeypatch):
    """On the committed glass_sphere, `compare` runs the three kinds of accuracy check
    and says how many of each it checked: physical requirements on this run (the
    paper preset's spurious TIR in a sphere is a known gap, not a failure), the
    regression locks at the golden settings (all five hold); the method targets only
    at the scene's own settings, so not with a reduced photon budget (and the report
    says why). With 0 iterations a lock fails and --fail-on-checks exits 3. A
    modified copy of the scene gets the physical requirements only."""
    monkeypatch.chdir(REPO)
    out = tmp_path / "out"
    # REFERENCE's references, in the run's cache: the same as the bundled-name test's.
    # The method renders at the scene's own settings (the locks' calibration).
    fast = ["--studies", "metrics", "-q", "--preset", "paper", *REFERENCE]
    scene = str(SCENES / "glass_sphere.toml")
    assert main(["compare", scene, "-o", str(out), *fast, "--fail-on-checks"]) == 0
    summary = capsys.readouterr().out
    data = json.loads((out / "glass_sphere-paper" / "metrics.json").read_text())
    by_kind = {}
    for t in data["checks"]:
        by_kind.setdefault(t["kind"], []).append(t)
    assert len(by_kind["regression lock"]) == 5
    assert all(t["passed"] for t in by_kind["regression lock"])
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


def test_compare_by_bundled_name_from_any_directory(tmp_path, monkeypatch, capsys):
    """Run from an unrelated directory, `compare glass_sphere` finds the bundled scene,
    the bundled golden references and locks (each lock is checked and reported),
    and names the method's images `<view>_method.exr`."""
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    argv = ["compare", "glass_sphere", "-o", str(out), "--studies", "metrics", "-q",
            "--preset", "paper", *REFERENCE]
    assert main(argv) == 0
    data = json.loads((out / "glass_sphere-paper" / "metrics.json").read_text())
    assert data["scene"]["source"].endswith("scenes/glass_sphere.toml")
    locks = [t for t in data["checks"] if t["kind"] == "regression lock"]
    assert locks, "the bundled locks were not checked"
    assert {t["view"] for t in locks} == {"receiver0"}
    assert data["files"]["receiver0/method"] == "receiver0_method.exr"
    assert (out / "glass_sphere-paper" / "receiver0_method.exr").is_file()


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
