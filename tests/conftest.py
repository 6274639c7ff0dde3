"""Shared fixtures: paths into the repository, a minimal valid scene, the GL
context in the style of moderngl's own tests/conftest.py (ONE context factory for
the session, and a ``ctx`` fixture asserting GL_NO_ERROR before and after a test),
one headless Chromium per test process (``chromium``, ``tests/browser.py``), and the run's
one Mitsuba reference cache.

The reference cache is content-addressed and locks per key, so one folder serves
every test and every xdist worker: the controller makes it before the workers start
and hands it to them (and to every subprocess) as ``$CAUSTICS_CACHE_DIR``. It is
fresh per run, so each reference a test needs is traced once per run and no run
trusts an earlier one's traces; ``--reference-cache DIR`` reuses DIR across runs
instead. A test that must trace into its own cache (the cache's own tests) says why.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import settings as hypothesis_settings

from renderers.caustics_mapping import create_context
from renderers.mitsuba.cache import CACHE_ENV
from tests import browser

REPO = Path(__file__).resolve().parents[1]

# On CI, property-based tests draw the same examples every run (reproducible
# verdicts); locally they explore new ones each time.
hypothesis_settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    hypothesis_settings.load_profile("ci")
SCENES = REPO / "scenes"
#: Every bundled scene file: the paper scenes, the hard cases and their sub-folders (not
#: the sweeps' scenes).
BUNDLED_FILES = tuple(sorted(p for p in SCENES.rglob("*.toml") if "sweeps" not in p.parts))


def bundled_id(path: Path) -> str:
    """A bundled scene file's test id: ``glass_sphere``, ``hard/concave/bowl_deep_sun30``."""
    return path.relative_to(SCENES).with_suffix("").as_posix()

MINIMAL_SCENE = """
[scene]
name = "minimal"

[light]
type = "point"
position = [0.0, 0.0, 6.0]
intensity = [30.0, 30.0, 30.0]

[[receivers]]
type = "plane"
center = [0.0, 0.0, 0.0]
size = [8.0, 8.0]
albedo = [0.5, 0.5, 0.5]

[[objects]]
type = "sphere"
center = [0.0, 0.0, 2.0]
radius = 1.0
material = { type = "dielectric", ior = 1.5 }

[camera]
position = [0.0, -9.0, 7.0]
look_at = [0.0, 0.0, 0.5]
fov = 40.0
resolution = [64, 64]
"""


@pytest.fixture
def repo() -> Path:
    """Repository root."""
    return REPO


@pytest.fixture
def minimal_scene_text() -> str:
    """TOML text of a small valid scene (glass sphere, point light)."""
    return MINIMAL_SCENE


def all_scene_files() -> list[Path]:
    """Every committed scene file: paper scenes and hard cases."""
    return sorted(SCENES.glob("*.toml")) + sorted((SCENES / "hard").glob("*.toml"))


@pytest.fixture(scope="session")
def context_factory():
    """The one place a GL context is created; shared by the whole session."""
    ctx = create_context()
    yield lambda: ctx
    ctx.release()


@pytest.fixture(scope="session")
def chromium():
    """The process's one headless Chromium (one per xdist worker: at most two in the
    default run, which keeps each test file on one worker); modules open contexts on it."""
    browser.require_browser()
    with browser.launch() as instance:
        yield instance


@pytest.fixture
def ctx(context_factory):
    """The session's context, asserting GL_NO_ERROR before and after the test."""
    context = context_factory()
    with context:  # current again, whatever other contexts came and went
        assert context.error == "GL_NO_ERROR"
        yield context
        assert context.error == "GL_NO_ERROR"


#: Markers of the three kinds of accuracy check (harness.checks); every check test
#: carries one, and records how many checks it made with ``record_property("checks", n)``.
CHECK_MARKERS = {"physical_requirement": "physical requirements",
                 "method_target": "method targets",
                 "regression_lock": "regression locks"}


#: The per-run cache folder this process made (removed when the run ends).
_OWNED_CACHE = pytest.StashKey[str]()


def pytest_addoption(parser):
    parser.addoption("--reference-cache", metavar="DIR", default=None,
                     help="Mitsuba reference cache to reuse across runs (default: a "
                          "fresh one per run, shared by every test and worker)")


def pytest_configure(config):
    for marker, kind in CHECK_MARKERS.items():
        config.addinivalue_line("markers", f"{marker}: an accuracy check test ({kind})")
    if hasattr(config, "workerinput"):
        return  # an xdist worker: the controller's cache is already in the environment
    chosen = config.getoption("--reference-cache")
    if chosen:
        os.environ[CACHE_ENV] = str(Path(chosen).resolve())
    else:
        fresh = tempfile.mkdtemp(prefix="caustics-test-references-")
        config.stash[_OWNED_CACHE] = fresh
        os.environ[CACHE_ENV] = fresh


def pytest_unconfigure(config):
    fresh = config.stash.get(_OWNED_CACHE, None)
    if fresh is not None:
        shutil.rmtree(fresh, ignore_errors=True)



def pytest_terminal_summary(terminalreporter, exitstatus, config):
    """Say how many accuracy checks of each kind, and how many hard cases, this run
    checked: checks are counted from each test's ``checks`` property (1 if none),
    tests by outcome (an xfail is a known gap)."""
    outcomes = ("passed", "failed", "xfailed", "xpassed")
    reports = [(outcome, r) for outcome in outcomes
               for r in terminalreporter.stats.get(outcome, [])
               if getattr(r, "when", "call") == "call"]
    counts = {kind: {"checks": 0, **{o: 0 for o in outcomes}} for kind in CHECK_MARKERS}
    hard_cases = set()
    for outcome, report in reports:
        for marker in CHECK_MARKERS:
            if marker in report.keywords:
                n = dict(report.user_properties).get("checks", 1)
                counts[marker]["checks"] += int(n)
                counts[marker][outcome] += 1
        if "test_stability.py::test_hard_case_is_stable[" in report.nodeid:
            hard_cases.add(report.nodeid.split("[", 1)[1].rstrip("]").split("-")[-1])
    if not (hard_cases or any(c["checks"] for c in counts.values())):
        return
    terminalreporter.write_sep("-", "accuracy checks and stability")
    for marker, kind in CHECK_MARKERS.items():
        c = counts[marker]
        tests = sum(c[o] for o in outcomes)
        parts = [f"{c['passed']} passed"]
        parts += [f"{c['failed']} FAILED"] if c["failed"] else []
        parts += [f"{c['xfailed']} known gaps (xfail)"] if c["xfailed"] else []
        parts += [f"{c['xpassed']} gaps closed (xpass)"] if c["xpassed"] else []
        terminalreporter.write_line(f"{kind} checked: {c['checks']} in {tests} tests "
                                    f"({', '.join(parts)})")
    if hard_cases:
        terminalreporter.write_line(f"hard cases checked: {len(hard_cases)} "
                                    f"({', '.join(sorted(hard_cases))})")
