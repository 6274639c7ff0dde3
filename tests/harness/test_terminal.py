"""Text from scene files reaches the terminal inert: control characters escaped, Rich
markup escaped, the compare summary printed whatever the scene is called."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from rich.console import Console

from harness.terminal import error_line, markup, plain
from reports.records import SceneFailure
from tests.reports.conftest import make_comparison

HOSTILE = "evil[/]\x1b[31mred\x1b]0;title\x07[bold]\nsecond\u202eline\\"


@pytest.mark.parametrize(("text", "expected"), [
    ("glass_sphere", "glass_sphere"),
    ("a\x1b[31mb", "a\\x1b[31mb"),
    ("one\ntwo\tthree\r", "one\\x0atwo\\x09three\\x0d"),
    ("right\u202eto left", "right\\u202eto left"),
    ("c1\x9bcontrol", "c1\\x9bcontrol"),
    ("Wasser über Glas ≤ 1 µm", "Wasser über Glas ≤ 1 µm"),
])
def test_plain_escapes_control_characters(text, expected):
    """Regression lock: C0/C1 controls, DEL and bidi overrides are shown as escapes;
    printable text (any script) is unchanged; the result is one line."""
    assert plain(text) == expected
    assert "\n" not in plain(text)


def test_markup_is_literal_in_rich():
    """Regression lock: `[/]` and `[bold]` in a name print literally through Rich
    (unescaped, `[/]` raises MarkupError)."""
    console = Console(width=200, record=True, color_system=None)
    console.print(markup(HOSTILE))
    shown = console.export_text()
    assert "evil[/]" in shown and "[bold]" in shown and "\\x1b[31m" in shown
    assert "\x1b" not in shown and "\n" not in shown.rstrip("\n")


def test_error_line_is_one_line():
    """Regression lock: an exception becomes `Type: message` on one line."""
    assert error_line(ValueError("a\n  b\x1b")) == "ValueError: a b\\x1b"
    assert error_line(RuntimeError()) == "RuntimeError: (no message)"


def test_compare_summary_prints_hostile_names_safely(capsys):
    """Regression lock: the final Rich summary of `compare` with a scene called
    `evil[/]<ESC>[31m...` (and a failed one) prints every name literally; before,
    Rich raised MarkupError after the whole run, and ANSI escapes reached the
    terminal raw."""
    from harness.commands.compare import print_summary  # noqa: PLC0415 - loads renderers

    comparison = replace(make_comparison(name=HOSTILE, checks=False), method="pa[/]per")
    failure = SceneFailure(name=HOSTILE, method="strong", source="x.toml",
                           error="ValueError: boom [/]", stage="comparison")
    print_summary([comparison, failure], Path("/tmp/out[/]"), 1.0)
    captured = capsys.readouterr()
    assert "\x1b" not in captured.out + captured.err
    assert "evil[/]" in captured.out and "pa[/]per" in captured.out
    assert "FAILED" in captured.out
    assert captured.err.count("\n") == 1 and "ValueError: boom [/]" in captured.err
