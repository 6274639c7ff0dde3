"""Settings: defaults, per-scene values and command-line overrides, all validated."""

from __future__ import annotations

import pytest

from scenes import SceneError, load_scene, parse_override, parse_scene, with_settings
from tests.conftest import SCENES


def test_defaults(minimal_scene_text):
    """The paper preset by default; the choices it makes are left unset (None) in the
    scene, so that a preset chosen later fills them."""
    s = parse_scene(minimal_scene_text).settings
    assert (s.preset, s.grid, s.normalization) == ("paper", 128, "radiometric")
    assert (s.estimator, s.iterations, s.safeguarded, s.splat) == (None, None, None, None)


def test_per_scene_settings():
    s = load_scene(SCENES / "hard" / "newton_oscillation.toml").settings
    assert (s.estimator, s.iterations) == ("newton", 8)


def test_command_line_override_keeps_other_settings():
    scene = load_scene(SCENES / "hard" / "newton_oscillation.toml")
    changed = with_settings(scene, dict([parse_override("grid=64"),
                                         parse_override("safeguarded=true")]))
    assert (changed.settings.grid, changed.settings.safeguarded) == (64, True)
    assert changed.settings.estimator == "newton" and changed.source == scene.source


def test_none_overrides_are_ignored(minimal_scene_text):
    scene = parse_scene(minimal_scene_text)
    assert with_settings(scene, {"grid": None}) is scene


@pytest.mark.parametrize(
    ("item", "message"),
    [
        ("grid=0", "command line: settings.grid: must be >= 2, got 0"),
        ("estimator=bisect", "command line: settings.estimator: must be one of"),
        ("gird=64", "command line: settings.gird: unknown key"),
    ],
)
def test_bad_override_names_the_setting(minimal_scene_text, item, message):
    scene = parse_scene(minimal_scene_text)
    with pytest.raises(SceneError) as info:
        with_settings(scene, dict([parse_override(item)]))
    assert str(info.value).startswith(message)


def test_override_without_equals():
    with pytest.raises(SceneError, match="expected NAME=VALUE"):
        parse_override("grid")
