"""Every failure is one line: unexpected exceptions, system errors and long
messages end in one ``error:`` line and a distinct exit status; every option has
help text."""

from __future__ import annotations

import argparse
import subprocess
import sys

import pytest

from harness import cli
from harness.cli import EXIT_CODES, build_parser, main
from scenes.errors import HarnessError
from tests.conftest import REPO


def _raising(error: BaseException):
    def handler(args):
        raise error
    return lambda spec: handler


def test_every_option_of_every_command_has_help():
    """Regression lock: `caustics CMD --help` explains every option and argument."""
    parser = build_parser()
    missing = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                missing += [f"{name} {a.option_strings or a.dest}" for a in sub._actions
                            if not a.help or a.help == argparse.SUPPRESS]
        elif not action.help:
            missing.append(str(action.option_strings))
    assert missing == []


def test_exit_codes_are_distinct():
    """Regression lock: each outcome has its own exit status; 2 stays argparse's."""
    assert len(set(EXIT_CODES.values())) == len(EXIT_CODES)
    with pytest.raises(SystemExit) as info:
        build_parser().parse_args(["compare", "--no-such-option"])
    assert info.value.code == EXIT_CODES["usage"]


def test_unexpected_exception_is_one_line_exit_70(monkeypatch, capsys):
    """Regression lock: a bug (any exception the harness does not raise on purpose)
    is one line, ``error: <Type>: <message>`` with the --debug hint, exit 70; a
    message over several lines is joined, control characters are shown inert."""
    monkeypatch.delenv("CAUSTICS_DEBUG", raising=False)
    monkeypatch.setattr(cli, "_handler", _raising(ValueError("bad\nthing \x1b[31mred")))
    assert main(["validate"]) == 70  # the README's exit codes: 70 internal error
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("error: ValueError: bad thing \\x1b[31mred (rerun with --debug")


def test_library_warnings_are_one_line(monkeypatch, capsys):
    """Regression lock: a warning from the library (a cut-flux or invalid cache entry
    warning) prints as one ``warning:`` line, control characters inert, without
    Python's source line; the previous warning display is restored afterwards."""
    import warnings  # noqa: PLC0415 - only this test warns

    monkeypatch.delenv("CAUSTICS_DEBUG", raising=False)

    def handler(args):
        warnings.warn("scene x: cut off 1e-3\x1b[31m", UserWarning, stacklevel=1)
        return 0

    before = warnings.showwarning
    monkeypatch.setattr(cli, "_handler", lambda spec: handler)
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        assert main(["validate"]) == 0
        assert warnings.showwarning is before
    err = capsys.readouterr().err
    assert err == "warning: scene x: cut off 1e-3\\x1b[31m\n"


@pytest.mark.parametrize("how", ["flag-before", "flag-after", "env"])
def test_debug_prints_the_traceback(monkeypatch, capsys, how):
    """Regression lock: --debug (before or after the command) or CAUSTICS_DEBUG=1
    adds the traceback; the exit status stays 70."""
    monkeypatch.setattr(cli, "_handler", _raising(KeyError("k")))
    argv = {"flag-before": ["--debug", "validate"], "flag-after": ["validate", "--debug"],
            "env": ["validate"]}[how]
    if how == "env":
        monkeypatch.setenv("CAUSTICS_DEBUG", "1")
    else:
        monkeypatch.delenv("CAUSTICS_DEBUG", raising=False)
    assert main(argv) == 70
    err = capsys.readouterr().err
    assert "Traceback" in err and err.rstrip().endswith("error: KeyError: 'k'")


def test_system_error_is_exit_1(monkeypatch, capsys):
    """Regression lock: an OSError (disk full, permission) is the user's to fix:
    one line, exit 1."""
    monkeypatch.delenv("CAUSTICS_DEBUG", raising=False)
    monkeypatch.setattr(cli, "_handler", _raising(OSError(28, "No space left on device")))
    assert main(["validate"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "No space left on device" in err


def test_long_harness_error_is_one_line(monkeypatch, capsys):
    """Regression lock: a typed error whose message has a tail (a worker's output)
    prints its first line and how to see the rest; exit 1."""
    monkeypatch.delenv("CAUSTICS_DEBUG", raising=False)
    monkeypatch.setattr(cli, "_handler", _raising(HarnessError("LuxCore failed\nl1\nl2")))
    assert main(["validate"]) == 1
    assert capsys.readouterr().err == ("error: LuxCore failed (2 more lines: --debug shows "
                                       "them)\n")


def test_keyboard_interrupt_is_130(monkeypatch, capsys):
    """Regression lock: Ctrl-C is exit 130 and one line."""
    monkeypatch.setattr(cli, "_handler", _raising(KeyboardInterrupt()))
    assert main(["validate"]) == 130
    assert capsys.readouterr().err == "interrupted\n"


def test_no_traceback_from_a_bug_in_a_real_process():
    """Regression lock: the installed entry point, with a handler that divides by
    zero, prints one line and exits 70 (no traceback reaches the user)."""
    script = ("import sys\nimport harness.cli as c\n"
              "c._handler = lambda spec: (lambda args: 1 / 0)\nc.run()\n")
    proc = subprocess.run([sys.executable, "-c", script, "validate"], capture_output=True,
                          text=True, cwd=REPO, check=False,
                          env={"PATH": "/usr/bin:/bin", "PYTHONPATH": str(REPO)})
    assert proc.returncode == 70
    assert "Traceback" not in proc.stderr and proc.stderr.count("\n") == 1
    assert proc.stderr.startswith("error: ZeroDivisionError: division by zero")
