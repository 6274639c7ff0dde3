"""File writing shared by every layer (``scenes/files.py``): the umask read without
changing it, atomic writes with a plain ``open()``'s mode, temporary folders with
a plain ``mkdir()``'s mode.

Kind: regression locks of the file contract (no accuracy is measured here)."""

from __future__ import annotations

import os
import stat
import threading
from concurrent.futures import ThreadPoolExecutor

import pytest

from scenes import files
from scenes.files import atomic_path, atomic_write_bytes, make_temporary_folder, process_umask

#: Umasks the tests run under: the usual default, group-only, owner-only, group-write.
UMASKS = [0o022, 0o027, 0o077, 0o002]


@pytest.fixture
def set_umask():
    """Set the process's umask for one test (``set_umask(mask)``), restored after."""
    previous = os.umask(0o022)
    yield os.umask
    os.umask(previous)


@pytest.fixture
def umask_calls(monkeypatch):
    """Every call of ``os.umask`` while the test runs (it still works, so a caller
    that sets the umask is seen, not broken)."""
    calls, real = [], os.umask

    def recording(mask):
        calls.append(mask)
        return real(mask)

    monkeypatch.setattr(os, "umask", recording)
    return calls


def _mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


@pytest.mark.parametrize("mask", UMASKS)
def test_process_umask_is_the_umask_the_kernel_applies(set_umask, tmp_path, umask_calls, mask):
    """Under each umask, process_umask returns it (read from /proc and by the probe
    file alike), equal to the bits a plain open() clears from 0666 and mkdir() from
    0777, and it never calls os.umask."""
    set_umask(mask)
    umask_calls.clear()
    assert process_umask() == mask
    assert files._umask_from_probe() == mask
    (tmp_path / "plain").write_bytes(b"")
    (tmp_path / "folder").mkdir()
    assert _mode(tmp_path / "plain") == 0o666 & ~process_umask()
    assert _mode(tmp_path / "folder") == 0o777 & ~process_umask()
    assert umask_calls == []


def test_without_proc_the_probe_file_gives_the_umask(set_umask, monkeypatch):
    """Where /proc/self/status has no ``Umask:`` line (not Linux, or a kernel before
    4.7), the probe file answers, and follows a umask changed since the last call."""
    monkeypatch.setattr(files, "_PROC_STATUS", "/nonexistent/status")
    assert files._umask_from_proc() is None
    for mask in (0o027, 0o007):
        set_umask(mask)
        assert process_umask() == mask


@pytest.mark.parametrize("mask", [0o022, 0o077])
def test_atomic_files_and_temporary_folders_get_plain_modes(set_umask, tmp_path, mask):
    """Not mkstemp's 0600 nor mkdtemp's 0700: 0666 and 0777 less the umask."""
    set_umask(mask)
    atomic_write_bytes(tmp_path / "a.bin", b"data")
    folder = make_temporary_folder(tmp_path, ".staging-")
    assert (tmp_path / "a.bin").read_bytes() == b"data"
    assert _mode(tmp_path / "a.bin") == 0o666 & ~mask
    assert _mode(folder) == 0o777 & ~mask
    assert folder.name.startswith(".staging-")


def test_an_interrupted_atomic_write_leaves_the_old_file(tmp_path):
    """The temporary file is deleted and the old file stays as it was."""
    path = tmp_path / "a.txt"
    atomic_write_bytes(path, b"old")
    with pytest.raises(KeyboardInterrupt), atomic_path(path) as tmp:
        tmp.write_bytes(b"half")
        raise KeyboardInterrupt
    assert path.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]


def test_threads_writing_at_once_get_plain_modes(set_umask, tmp_path, umask_calls):
    """8 threads x 50 atomic writes and temporary folders each, under umask 0o027,
    beside plain open() / mkdir() in the same threads: every file is 0640, every
    folder 0750, and os.umask is never called (a writer that set and restored it
    would give a file created meanwhile by another thread mode 0666)."""
    mask, threads, writes = 0o027, 8, 50
    set_umask(mask)
    umask_calls.clear()
    start = threading.Barrier(threads)

    def work(t: int) -> None:
        start.wait()
        for i in range(writes):
            atomic_write_bytes(tmp_path / f"atomic-{t}-{i}", b"x")
            make_temporary_folder(tmp_path, f".folder-{t}-{i}-")
            (tmp_path / f"plain-{t}-{i}").write_bytes(b"")
            (tmp_path / f"dir-{t}-{i}").mkdir()

    with ThreadPoolExecutor(threads) as pool:
        for future in [pool.submit(work, t) for t in range(threads)]:
            future.result()
    paths = list(tmp_path.iterdir())
    assert len(paths) == 4 * threads * writes
    modes = {p.name: _mode(p) for p in paths}
    wrong = {name: oct(m) for name, m in modes.items()
             if m != (0o750 if (tmp_path / name).is_dir() else 0o640)}
    assert wrong == {}
    assert umask_calls == []
