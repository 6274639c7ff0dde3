"""Shared fixtures: paths into the repository, a minimal valid scene, and the GL
context in the style of moderngl's own tests/conftest.py: ONE context factory for
the session, and a ``ctx`` fixture asserting GL_NO_ERROR before and after a test."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import settings as hypothesis_settings

from harness.checks import THRESHOLDS_FILE
from renderers.caustics_mapping import create_context

REPO = Path(__file__).resolve().parents[1]

# On CI, property-based tests draw the same examples every run (reproducible
# verdicts); locally they explore new ones each time.
hypothesis_settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    hypothesis_settings.load_profile("ci")
SCENES = REPO / "scenes"

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


@pytest.fixture
def ctx(context_factory):
    """The session's context, asserting GL_NO_ERROR before and after the test."""
    context = context_factory()
    with context:  # current again, whatever other contexts came and went
        assert context.error == "GL_NO_ERROR"
        yield context
        assert context.error == "GL_NO_ERROR"


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    """Say how many accuracy bounds and hard cases this run checked."""
    reports = [r for key in ("passed", "failed") for r in terminalreporter.stats.get(key, [])
               if getattr(r, "when", "call") == "call"]
    bound_scenes, hard_cases = set(), set()
    for report in reports:
        node = report.nodeid
        if "test_accuracy_thresholds.py::test_bounds_hold[" in node:
            bound_scenes.add(node.split("[", 1)[1].rstrip("]"))
        if "test_stability.py::test_hard_case_is_stable[" in node:
            hard_cases.add(node.split("[", 1)[1].rstrip("]").split("-")[-1])
    if not (bound_scenes or hard_cases):
        return
    from harness.checks.thresholds import load_thresholds  # noqa: PLC0415

    bounds = [b for b in load_thresholds(THRESHOLDS_FILE)
              if b.scene in bound_scenes]
    terminalreporter.write_sep("-", "accuracy and stability")
    if bound_scenes:
        terminalreporter.write_line(f"accuracy bounds checked: {len(bounds)} "
                                    f"({len(bound_scenes)} scenes, {THRESHOLDS_FILE.name})")
    if hard_cases:
        terminalreporter.write_line(f"hard cases checked: {len(hard_cases)} "
                                    f"({', '.join(sorted(hard_cases))})")
