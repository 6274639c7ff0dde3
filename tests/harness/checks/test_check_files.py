"""The reviewed files of accuracy checks (regression locks, method targets, known
gaps): validated like scene files, bounds applied as max/min/band, and a missing or
unreadable file is an error naming it, never "no checks"."""

from __future__ import annotations

import math

import pytest

from harness.checks import GAPS_FILE, LOCKS_FILE, TARGETS_FILE
from harness.checks.bounds import (
    ChecksFileError,
    check_locks,
    load_gaps,
    load_locks,
    load_targets,
)
from harness.checks.golden import GOLDEN_SCENES
from harness.checks.physical import CHECK_NAMES
from harness.checks.targets import check_targets
from reports.records import MetricValue
from scenes import SceneError

GOOD = """
[[lock]]
scene = "s"
view = "receiver0"
region = "caustic"
metric = "relmse"
kind = "max"
bound = 0.1
provenance = "test"

[[lock]]
scene = "s"
view = "receiver0"
region = "full"
metric = "flux_ratio"
kind = "band"
bound = 0.05
provenance = "test"

[[lock]]
scene = "s"
view = "camera"
region = "object_masked"
metric = "ssim"
kind = "min"
bound = 0.9
provenance = "test"
"""


def test_locks_apply(tmp_path):
    path = tmp_path / "t.toml"
    path.write_text(GOOD)
    locks = load_locks(path)
    metrics = [MetricValue("receiver0", "caustic", "relmse", 0.05),
               MetricValue("receiver0", "full", "flux_ratio", 1.07),
               MetricValue("camera", "object_masked", "ssim", math.nan)]
    checks = check_locks("s", metrics, locks)
    assert [c.passed for c in checks] == [True, False, False]  # NaN never passes
    assert {c.kind for c in checks} == {"regression lock"}
    assert check_locks("other", metrics, locks) == ()


def test_bad_file_names_field(tmp_path):
    path = tmp_path / "t.toml"
    path.write_text(GOOD.replace('metric = "relmse"', 'metric = "mse"'))
    with pytest.raises(SceneError, match=r"t.toml: lock\[0\].metric: unknown metric 'mse'"):
        load_locks(path)


def test_a_target_needs_a_reason_and_a_known_measure(tmp_path):
    path = tmp_path / "targets.toml"
    path.write_text('[[target]]\nscene = "s"\nmethod = "strong"\nmetric = "sharpness"\n'
                    'kind = "max"\nbound = 1.0\nreason = " "\n')
    with pytest.raises(SceneError) as error:
        load_targets(path)
    text = str(error.value)
    assert "target[0].metric: unknown measure 'sharpness'" in text
    assert "target[0].reason: must say where the number comes from" in text


@pytest.mark.parametrize("loader", [load_locks, load_targets, load_gaps])
def test_missing_file_is_an_error_naming_it(tmp_path, loader):
    """Never read as "no checks": the error names the path, on one line."""
    missing = tmp_path / "missing.toml"
    with pytest.raises(ChecksFileError) as error:
        loader(missing)
    assert str(error.value) == f"{missing}: no such file"
    bad = tmp_path / "bad.toml"
    bad.write_text("[[lock]\n")
    with pytest.raises(ChecksFileError, match=r"bad\.toml: TOML syntax error"):
        loader(bad)


def test_bundled_files_load_from_the_package():
    """The default paths are inside the installed package, not the working
    directory; every target and gap names its reason; gaps name real checks and
    scenes."""
    for path in (LOCKS_FILE, TARGETS_FILE, GAPS_FILE):
        assert "harness/checks/data" in path.as_posix() and path.is_absolute()
    assert load_locks(LOCKS_FILE)
    targets = load_targets(TARGETS_FILE)
    assert targets and all(t.reason for t in targets)
    for gap in load_gaps(GAPS_FILE):
        assert gap.check in CHECK_NAMES and gap.scene in GOLDEN_SCENES, gap


def test_a_target_missed_today_is_a_known_gap_not_a_failure(tmp_path):
    """A target with ``gap`` set reports "known gap" when missed (the test suite makes
    it a strict xfail) and "gap closed" when reached, so the entry is removed rather
    than the number loosened; without ``gap`` a miss is a plain failure."""
    path = tmp_path / "targets.toml"
    path.write_text('[[target]]\nscene = "s"\nmethod = "m"\nmetric = "relmse"\n'
                    'kind = "max"\nbound = 0.01\nreason = "r"\ngap = "not there yet"\n'
                    '[[target]]\nscene = "s"\nmethod = "m"\nmetric = "flux_ratio"\n'
                    'kind = "band"\nbound = 0.01\nreason = "r"\n')
    targets = load_targets(path)
    missed = check_targets(targets, scene="s", method="m",
                           measures={"relmse": 0.02, "flux_ratio": 1.05})
    assert [c.outcome for c in missed] == ["known gap", "FAIL"]
    assert {c.kind for c in missed} == {"method target"}
    reached = check_targets(targets, scene="s", method="m",
                            measures={"relmse": 0.005, "flux_ratio": 1.0})
    assert [c.outcome for c in reached] == ["gap closed", "pass"]
    assert check_targets(targets, scene="s", method="other", measures={}) == []
