"""Every writer of the tool, run from many threads at once (as under a threaded
in-process Dask worker), gives its files and folders the modes a plain ``open()``
and ``mkdir()`` would: atomic writes (``scenes/files.py``), EXRs
(``renderers/exr.py``), the reference cache's result directories
(``renderers/mitsuba/cache.py``), the sweep's results cache
(``harness/sweep/cache.py``) and staged outputs (``harness/compare/staging.py``).

A writer that read the umask by setting it and restoring it would, in between,
give a file another thread creates mode 0666: the test runs under umask 0o027, so
any such file (or folder 0777) shows. That window is only a few instructions wide
and is seldom hit, so the test also records every ``os.umask`` call and requires
none (the writers of the earlier code made 16 of them per round).

Kind: regression locks of the file contract (no accuracy is measured here)."""

from __future__ import annotations

import os
import stat
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from harness.compare.staging import staged_output
from harness.sweep.cache import ResultsCache
from renderers.exr import write_exr
from renderers.mitsuba.cache import write_result_dir
from renderers.results import ReceiverMap, RenderResult
from scenes.files import atomic_write_bytes

MASK = 0o027
THREADS = 8
ROUNDS = 50


@pytest.fixture
def umask_027(monkeypatch):
    """Umask 0o027 for the test (restored after), and the list of every os.umask
    call made meanwhile (the calls still work)."""
    real = os.umask
    previous = real(MASK)
    calls = []

    def recording(mask):
        calls.append(mask)
        return real(mask)

    monkeypatch.setattr(os, "umask", recording)
    yield calls
    real(previous)


def _result() -> RenderResult:
    rgb = np.full((2, 2, 3), 0.5, np.float32)
    return RenderResult(renderer="mitsuba", camera=rgb,
                        receivers=(ReceiverMap(rgb, (-1.0, 1.0, -1.0, 1.0), None),),
                        effects=(), timings={"total": 1.0}, timer="wall", metadata={})


def _page(folder) -> None:
    (folder / "index.html").write_text("row")
    (folder / "data").mkdir()
    (folder / "data" / "values.bin").write_bytes(b"\0")


def test_every_writer_in_eight_threads_gives_plain_modes(tmp_path, umask_027):
    """8 threads x 50 rounds, each round one write through each writer: every file
    under the output is 0640 (0666 & ~0o027) and every folder 0750 (0777 & ~0o027),
    and no writer called os.umask."""
    result, layers = _result(), {"RGB": np.zeros((2, 2, 3), np.float32)}
    start = threading.Barrier(THREADS)

    def work(t: int) -> None:
        cache = ResultsCache(tmp_path / "rows")
        start.wait()
        for i in range(ROUNDS):
            name = f"{t}-{i}"
            atomic_write_bytes(tmp_path / "atomic" / name, b"x")
            write_exr(tmp_path / "exr" / f"{name}.exr", layers)
            write_result_dir(tmp_path / "references" / name, result)
            cache.store(f"{t:02d}{i:062d}", {"round": i}, _page)
            with staged_output(tmp_path / "outputs" / name) as folder:
                (folder / "index.html").write_text(name)

    with ThreadPoolExecutor(THREADS) as pool:
        for future in [pool.submit(work, t) for t in range(THREADS)]:
            future.result()
    found = list(tmp_path.rglob("*"))
    rows = [p for p in (tmp_path / "rows").iterdir() if p.is_dir()]
    assert len(rows) == THREADS * ROUNDS
    wrong = {str(p.relative_to(tmp_path)): oct(stat.S_IMODE(p.stat().st_mode))
             for p in found
             if stat.S_IMODE(p.stat().st_mode) != (0o750 if p.is_dir() else 0o640)}
    assert wrong == {}
    assert umask_027 == []
