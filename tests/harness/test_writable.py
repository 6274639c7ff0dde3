"""Output folders and the reference cache are checked before any rendering: a bad
``-o`` fails in seconds with one line naming it; an unwritable cache is left out
with one warning."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
import time

import pytest

from harness import writable
from harness.cli import main
from harness.writable import OutputDirError, check_output_dir, usable_cache
from tests.conftest import REPO

COMMANDS = [["compare", "glass_sphere"], ["render", "glass_sphere"],
            ["reference", "glass_sphere"], ["figures"],
            ["crosscheck", "glass_sphere", "--with", "luxcore"]]


def _one_error_line(err: str, path) -> None:
    assert err.count("\n") == 1 and err.startswith("error: ") and str(path) in err
    assert "Traceback" not in err


def test_output_that_is_a_file_fails_fast_in_a_real_process(tmp_path):
    """Regression lock (behaviour, not a benchmark): `compare -o FILE` exits 1 with
    one line naming FILE, well before anything is imported or rendered (< 5 s)."""
    target = tmp_path / "report"
    target.write_text("not a folder")
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "harness", "compare", "glass_sphere",
                           "-o", str(target)], capture_output=True, text=True, cwd=REPO,
                          check=False)
    seconds = time.perf_counter() - start
    assert proc.returncode == 1, proc.stderr
    _one_error_line(proc.stderr, target)
    assert "not a directory" in proc.stderr
    assert seconds < 5, f"took {seconds:.1f} s"


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: c[0])
def test_every_output_command_checks_its_folder_first(tmp_path, capsys, command):
    """Regression lock: each command with ``-o DIR`` refuses a path under a file
    (one line, exit 1) before its handler runs."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    target = blocker / "out"
    assert main([*command, "-o", str(target)]) == 1
    _one_error_line(capsys.readouterr().err, target)


def test_read_only_output_fails_with_one_line(tmp_path, capsys, monkeypatch):
    """Regression lock: a folder the probe cannot write in (here a simulated
    read-only file system: root ignores permission bits) fails with one line."""
    def refuse(*args, **kwargs):
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(writable.tempfile, "mkstemp", refuse)
    target = tmp_path / "out"
    assert main(["compare", "glass_sphere", "-o", str(target)]) == 1
    err = capsys.readouterr().err
    _one_error_line(err, target)
    assert "Read-only file system" in err
    assert not target.exists()  # the check creates nothing


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into a read-only folder")
def test_read_only_folder_by_permissions(tmp_path):
    """Regression lock: a folder without write permission is refused, with one line."""
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        with pytest.raises(OutputDirError, match="cannot write"):
            check_output_dir(folder)
        with pytest.raises(OutputDirError, match=r"cannot write \(in "):
            check_output_dir(folder / "new" / "deeper")
    finally:
        folder.chmod(0o755)


def test_missing_output_under_a_writable_folder_is_fine(tmp_path):
    """Regression lock: a folder that does not exist yet is accepted (it will be
    created) and the check leaves no file behind."""
    target = tmp_path / "a" / "b"
    assert check_output_dir(target) == target
    assert list(tmp_path.iterdir()) == []


def test_unwritable_cache_falls_back_with_one_warning(tmp_path, capsys):
    """Regression lock: a cache path that cannot be a folder is not used: one
    warning line; a usable one is created."""
    blocker = tmp_path / "cache"
    blocker.write_text("")
    assert usable_cache(blocker / "reference") is False
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("warning: reference cache ")
    assert "without the cache" in err
    assert usable_cache(blocker) is False
    capsys.readouterr()
    assert usable_cache(tmp_path / "fresh") is True and (tmp_path / "fresh").is_dir()
    assert capsys.readouterr().err == ""


def test_reference_command_renders_without_an_unwritable_cache(tmp_path, capsys,
                                                               monkeypatch):
    """Regression lock: `reference --cache-dir FILE` warns once and renders with
    use_cache=False instead of failing inside the cache."""
    from harness.commands import reference as command  # noqa: PLC0415 - loads Mitsuba

    seen = {}

    def fake_render(scene, *, cache, use_cache, progress, camera):
        seen["use_cache"] = use_cache
        raise KeyboardInterrupt  # stop before writing: the decision is what we check

    monkeypatch.setattr(command, "render_reference", fake_render)
    blocker = tmp_path / "cache"
    blocker.write_text("")
    assert main(["reference", "glass_sphere", "-o", str(tmp_path / "out"),
                 "--cache-dir", str(blocker), "-q"]) == 130
    assert seen == {"use_cache": False}
    assert "warning: reference cache" in capsys.readouterr().err


@pytest.mark.parametrize("writable", [False, True], ids=["unwritable", "writable"])
def test_compare_command_leaves_an_unwritable_cache_out(tmp_path, capsys, monkeypatch,
                                                        writable):
    """Regression lock: ``caustics compare --cache-dir DIR`` (the CLI's own path, down
    to the pipeline's options) renders without the cache, with one warning, when DIR
    cannot be written, and with it, silently, when it can. The pipeline is stopped
    where it would render: what it was handed is what we check."""
    from harness import api  # noqa: PLC0415 - loads the renderers

    seen = []

    def fake_run(scene, method, *, options, checks, crosscheck):
        seen.append((options.use_cache, options.cache))
        raise KeyboardInterrupt  # stop before rendering: the decision is what we check

    monkeypatch.setattr(api, "run_comparison", fake_run)
    cache = tmp_path / "cache"
    if writable:
        cache.mkdir()
    else:
        cache.write_text("")  # a file where the cache folder should be
    assert main(["compare", "glass_sphere", "-o", str(tmp_path / "out"), "--studies",
                 "metrics", "--preset", "paper", "--cache-dir", str(cache), "-q"]) == 130
    assert seen == [(writable, str(cache))]
    warnings = [line for line in capsys.readouterr().err.splitlines()
                if line.startswith("warning: reference cache")]
    assert len(warnings) == (0 if writable else 1)
    assert not (tmp_path / "out").exists()  # stopped before anything was written
