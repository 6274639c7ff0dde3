"""The results cache: whole entries or none, every defect detected, nothing half
written by an error or an interrupt.

Kind: regression locks of the cache's contract (no accuracy is measured here)."""

from __future__ import annotations

import json
import math
import os
import shutil
import time

import pytest

from harness.sweep.cache import (
    PAGE,
    ROW_JSON,
    STALE_AFTER,
    InvalidResultWarning,
    ResultsCache,
)

KEY = "ab" * 32
ROW = {"scene": "glass_sphere", "method": "paper", "values": {"relmse": 0.25,
                                                               "ssim": float("nan")},
       "time_warm_ms": 12.5, "worker": "tcp://127.0.0.1:1"}


def _page(folder):
    (folder / "index.html").write_text("<html>row</html>")
    (folder / "sub").mkdir()
    (folder / "sub" / "data.bin").write_bytes(bytes(range(256)))


def test_entry_round_trip(tmp_path):
    """Regression lock: a stored row reads back as written (a NaN as null, with its
    reason in the document), its page files beside it, listed with their SHA-256."""
    cache = ResultsCache(tmp_path)
    stored = cache.store(KEY, ROW, _page)
    loaded = cache.load(KEY)
    assert loaded.row == stored.row
    assert loaded.row["values"] == {"relmse": 0.25, "ssim": None}
    assert (loaded.page / "sub" / "data.bin").read_bytes() == bytes(range(256))
    document = json.loads((tmp_path / KEY / ROW_JSON).read_text())
    assert sorted(document["files"]) == ["index.html", "sub/data.bin"]
    assert document["null_reasons"] == {"/row/values/ssim": "NaN"}
    assert cache.load("cd" * 32) is None


@pytest.mark.parametrize("damage", ["truncated page file", "extra page file", "edited row",
                                    "garbage json", "missing row.json", "other key"])
def test_damaged_entry_is_a_miss_with_one_warning_and_is_replaced(tmp_path, damage):
    """Regression lock (the cache's contract: a damaged entry is never read as a result):
    each kind of damage makes ``load`` warn once and miss; the next ``store``
    replaces the entry whole."""
    cache = ResultsCache(tmp_path)
    cache.store(KEY, ROW, _page)
    entry = tmp_path / KEY
    if damage == "truncated page file":
        (entry / PAGE / "sub" / "data.bin").write_bytes(b"\0")
    elif damage == "extra page file":
        (entry / PAGE / "stray.txt").write_text("x")
    elif damage == "edited row":
        document = json.loads((entry / ROW_JSON).read_text())
        document["row"]["values"]["relmse"] = 0.001
        (entry / ROW_JSON).write_text(json.dumps(document))
    elif damage == "garbage json":
        (entry / ROW_JSON).write_bytes(b"\xff{not json")
    elif damage == "missing row.json":
        (entry / ROW_JSON).unlink()
    else:  # a whole, self-consistent entry of another row, moved under this key
        other = ResultsCache(tmp_path / "elsewhere").store("ef" * 32, ROW, _page)
        shutil.rmtree(entry)
        shutil.copytree(other.page.parent, entry)
    with pytest.warns(InvalidResultWarning) as caught:
        assert cache.load(KEY) is None
    assert len(caught) == 1 and KEY[:12] in str(caught[0].message)
    cache.store(KEY, ROW, _page)
    assert cache.load(KEY).row["values"]["relmse"] == 0.25


@pytest.mark.parametrize("interrupt", [RuntimeError("page failed"), KeyboardInterrupt()])
def test_a_failed_or_interrupted_write_leaves_nothing(tmp_path, interrupt):
    """Regression lock (the cache's contract: Ctrl-C leaves it consistent): a page writer that
    raises, or is interrupted, half way through leaves no entry and no temporary
    folder; an entry that was there before is kept as it was."""
    cache = ResultsCache(tmp_path)

    def half(folder):
        (folder / "index.html").write_text("half")
        raise interrupt

    with pytest.raises(type(interrupt)):
        cache.store(KEY, ROW, half)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"{KEY}.lock"]
    cache.store(KEY, ROW, _page)
    with pytest.raises(type(interrupt)):
        cache.store(KEY, {**ROW, "time_warm_ms": 99.0}, half)
    assert cache.load(KEY).row["time_warm_ms"] == 12.5
    assert not list(tmp_path.glob(".*.tmp-*"))


def test_stale_temporary_folders_of_killed_writers_are_removed(tmp_path):
    """Regression lock: a writer killed outright leaves ``.KEY.tmp-*``; the next
    store removes those older than an hour and keeps younger ones (a writer still at
    work)."""
    old = tmp_path / f".{KEY}.tmp-old"
    young = tmp_path / f".{KEY}.tmp-young"
    for folder in (old, young):
        folder.mkdir(parents=True)
    past = time.time() - STALE_AFTER - 10
    os.utime(old, (past, past))
    ResultsCache(tmp_path).store("cd" * 32, ROW, _page)
    assert not old.exists() and young.exists()
    assert math.isclose(ResultsCache(tmp_path).load("cd" * 32).row["time_warm_ms"], 12.5)
