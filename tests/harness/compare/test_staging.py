"""A run's outputs appear all at once: staged beside ``-o`` and swapped in, so an
interrupted rerun never mixes two runs' files and never deletes foreign files."""

from __future__ import annotations

import os
import stat
import time

import pytest

from harness.compare.staging import MARKER, STALE_SECONDS, staged_output
from scenes.files import process_umask


def _previous_run(out):
    with staged_output(out) as folder:
        (folder / "index.html").write_text("old run")
        (folder / "scene-paper").mkdir()
        (folder / "scene-paper" / "metrics.json").write_text('{"run": "old"}')


def _siblings(out):
    return sorted(p.name for p in out.parent.iterdir() if p.name != out.name)


def test_interrupted_rerun_leaves_the_old_output_intact(tmp_path):
    """Regression lock: an interrupt (or any error) before the swap leaves the
    previous run's files exactly as they were, and no staging folder behind."""
    out = tmp_path / "out"
    _previous_run(out)
    with pytest.raises(KeyboardInterrupt), staged_output(out) as folder:
        assert folder != out and folder.parent == out.parent  # same file system
        (folder / "index.html").write_text("new run")
        (folder / "scene-paper").mkdir()
        (folder / "scene-paper" / "metrics.json").write_text('{"run": "new"}')
        raise KeyboardInterrupt
    assert (out / "index.html").read_text() == "old run"
    assert (out / "scene-paper" / "metrics.json").read_text() == '{"run": "old"}'
    assert _siblings(out) == []


def test_finished_run_replaces_the_old_output_whole(tmp_path):
    """Regression lock: after the swap only the new run's files are there (a page
    of the old run that the new one did not write is gone), no aside folder is left,
    and the folder has a plain mkdir's mode, not mkdtemp's 0700."""
    out = tmp_path / "out"
    _previous_run(out)
    with staged_output(out) as folder:
        (folder / "index.html").write_text("new run")
    assert (out / "index.html").read_text() == "new run"
    assert not (out / "scene-paper").exists()
    assert (out / MARKER).is_file()
    assert _siblings(out) == []
    assert stat.S_IMODE(out.stat().st_mode) == 0o777 & ~process_umask()


def test_a_folder_of_other_files_is_written_in_place_not_replaced(tmp_path, capsys):
    """Regression lock: `-o` naming a folder this tool did not write (no marker)
    is never deleted: the run writes into it, with one warning line."""
    out = tmp_path / "mine"
    out.mkdir()
    (out / "thesis.tex").write_text("precious")
    with staged_output(out) as folder:
        assert folder == out
        (folder / "index.html").write_text("run")
    assert (out / "thesis.tex").read_text() == "precious"
    assert capsys.readouterr().err.startswith("warning: ")


def test_new_and_empty_folders_are_staged(tmp_path):
    """Regression lock: a missing (nested) or empty `-o` is staged and swapped."""
    for out in (tmp_path / "a" / "b", tmp_path / "empty"):
        if out.name == "empty":
            out.mkdir()
        with staged_output(out) as folder:
            assert folder != out
            (folder / "index.html").write_text("x")
        assert (out / "index.html").is_file()


def test_a_killed_runs_leftovers_are_removed_once_stale(tmp_path):
    """Regression lock: staging and old folders a killed run left (they hold the
    marker) are removed by the next run once older than STALE_SECONDS; a young one
    (perhaps a run still going) and a foreign folder of the same pattern are kept."""
    out = tmp_path / "report"
    stale = tmp_path / ".report.staging-dead"
    young = tmp_path / ".report.staging-live"
    foreign = tmp_path / ".report.old-mine"
    for folder in (stale, young, foreign):
        folder.mkdir()
        (folder / "index.html").write_text("x")
    (stale / MARKER).write_text("m")
    (young / MARKER).write_text("m")
    old = time.time() - STALE_SECONDS - 60
    os.utime(stale, (old, old))
    os.utime(foreign, (old, old))
    with staged_output(out) as folder:
        (folder / "index.html").write_text("new")
    assert not stale.exists()
    assert young.exists() and foreign.exists()
