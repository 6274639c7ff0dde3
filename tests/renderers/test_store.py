"""The content-addressed store under both caches (``renderers/store.py``): whole
entries or none, every defect a :class:`StoreError` naming the path, nothing left
by an error or an interrupt, one writer per key at a time.

Kind: regression locks of the store's contract (no accuracy is measured here)."""

from __future__ import annotations

import hashlib
import json
import os
import threading
import time

import pytest

from renderers.store import (
    DIGEST,
    FILES,
    STALE_AFTER,
    ContentStore,
    StoreError,
    document_digest,
    entry_lock,
    read_entry,
    write_entry,
)

KEY = "ab" * 32
MANIFEST = "manifest.json"


def _fill(staging):
    """Two files, one in a sub-folder, under ``data/``; the rest of the manifest."""
    (staging / "data" / "sub").mkdir()
    (staging / "data" / "a.txt").write_text("alpha")
    (staging / "data" / "sub" / "b.bin").write_bytes(bytes(range(256)))
    return {"value": 0.5, "missing": float("nan")}


def _store(root) -> ContentStore:
    return ContentStore(root=root, manifest=MANIFEST, files_under="data")


def test_entry_round_trip_with_file_hashes_and_its_own_digest(tmp_path):
    """The manifest lists each file's SHA-256 (computed here with hashlib), its key,
    and the digest of the rest of it; a NaN is null with its reason."""
    written = _store(tmp_path).write(KEY, _fill)
    entry = _store(tmp_path).read(KEY)
    assert entry.manifest == written.manifest
    assert entry.folder == tmp_path / KEY
    assert entry.manifest[FILES] == {
        "a.txt": hashlib.sha256(b"alpha").hexdigest(),
        "sub/b.bin": hashlib.sha256(bytes(range(256))).hexdigest()}
    assert entry.manifest["key"] == KEY and entry.manifest["missing"] is None
    assert entry.manifest["null_reasons"] == {"/missing": "NaN"}
    on_disk = json.loads((tmp_path / KEY / MANIFEST).read_text())
    rest = {k: v for k, v in on_disk.items() if k != DIGEST}
    assert on_disk[DIGEST] == hashlib.sha256(
        json.dumps(rest, sort_keys=True, separators=(",", ":")).encode()).hexdigest()
    assert _store(tmp_path).read("cd" * 32) is None


def _damage(entry, how):
    manifest = entry / MANIFEST
    if how == "truncated file":
        (entry / "data" / "sub" / "b.bin").write_bytes(b"\0")
    elif how == "missing file":
        (entry / "data" / "a.txt").unlink()
    elif how == "extra file":
        (entry / "data" / "stray.txt").write_text("x")
    elif how == "edited manifest":
        document = json.loads(manifest.read_text())
        document["value"] = 0.25
        manifest.write_text(json.dumps(document))
    elif how == "garbage manifest":
        manifest.write_bytes(b"\xff{not json")
    elif how == "missing manifest":
        manifest.unlink()
    elif how == "array manifest":
        manifest.write_text("[1, 2]")
    elif how == "no digest":
        document = json.loads(manifest.read_text())
        del document[DIGEST]
        manifest.write_text(json.dumps(document))
    elif how in ("path outside", "other key"):  # re-signed: only the checks catch it
        document = json.loads(manifest.read_text())
        if how == "path outside":
            document[FILES]["../a.txt"] = document[FILES].pop("a.txt")
        else:
            document["key"] = "ef" * 32
        document[DIGEST] = document_digest(document)
        manifest.write_text(json.dumps(document))


DAMAGE = {"truncated file": "b.bin", "missing file": "a.txt", "extra file": "stray.txt",
          "edited manifest": "does not match its recorded SHA-256",
          "garbage manifest": "unreadable", "missing manifest": "unreadable",
          "array manifest": "not a JSON object", "no digest": "no 'document_sha256'",
          "path outside": "outside the entry", "other key": "stored under another key"}


@pytest.mark.parametrize("how", sorted(DAMAGE))
def test_a_damaged_entry_is_a_store_error_naming_its_path(tmp_path, how):
    """Each damage raises StoreError whose message names the entry's path and what
    is wrong; the next write replaces the entry whole."""
    store = _store(tmp_path)
    store.write(KEY, _fill)
    _damage(tmp_path / KEY, how)
    with pytest.raises(StoreError) as caught:
        store.read(KEY)
    message = str(caught.value)
    assert str(tmp_path / KEY) in message and DAMAGE[how] in message, message
    store.write(KEY, _fill)
    assert store.read(KEY).manifest["value"] == 0.5
    assert not (tmp_path / KEY / "data" / "stray.txt").exists()


def test_the_users_own_check_runs_after_the_digest(tmp_path):
    """``check`` sees the verified manifest and its path; what it raises is the
    answer."""
    store = _store(tmp_path)
    store.write(KEY, _fill)
    seen = []

    def check(document, path):
        seen.append((document["value"], path))
        raise StoreError(f"{path}: no good")

    with pytest.raises(StoreError, match="no good"):
        store.read(KEY, check=check)
    assert seen == [(0.5, tmp_path / KEY / MANIFEST)]


@pytest.mark.parametrize("interrupt", [RuntimeError("disk full"), KeyboardInterrupt()])
def test_a_failed_write_leaves_no_entry_and_no_temporary(tmp_path, interrupt):
    """A filler that raises half way (an interrupt too): no new entry, no temporary
    folder, and an entry that was there before is kept as it was."""
    store = _store(tmp_path)

    def half(staging):
        (staging / "data" / "a.txt").write_text("half")
        raise interrupt

    with pytest.raises(type(interrupt)):
        store.write(KEY, half)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"{KEY}.lock"]
    store.write(KEY, _fill)
    with pytest.raises(type(interrupt)):
        store.write(KEY, half)
    assert store.read(KEY).manifest["value"] == 0.5
    assert sorted(p.name for p in tmp_path.iterdir()) == [KEY, f"{KEY}.lock"]


def test_stale_temporaries_go_and_young_ones_stay(tmp_path):
    """A killed writer's ``.NAME.tmp-*`` older than STALE_AFTER is removed by the
    next write beside it; a younger one may be a live writer's and stays."""
    old, young = tmp_path / f".{KEY}.tmp-old", tmp_path / f".{KEY}.tmp-young"
    for folder in (old, young):
        folder.mkdir()
    past = time.time() - STALE_AFTER - 10
    os.utime(old, (past, past))
    _store(tmp_path).write("cd" * 32, _fill)
    assert not old.exists() and young.exists()


def test_writing_into_a_foreign_folder_keeps_its_other_files(tmp_path):
    """A target folder ``replace_whole`` refuses (not an old entry) gets the files
    moved in, and its other files stay; the entry then reads back (files beside the
    listed ones allowed without ``exact``)."""
    target = tmp_path / "out"
    target.mkdir()
    (target / "thesis.tex").write_text("precious")

    def fill(staging):
        (staging / "a.txt").write_text("alpha")
        return {}

    write_entry(target, fill, manifest=MANIFEST, replace_whole=lambda folder: False)
    assert (target / "thesis.tex").read_text() == "precious"
    document = read_entry(target, manifest=MANIFEST, exact=False)
    assert document[FILES] == {"a.txt": hashlib.sha256(b"alpha").hexdigest()}
    with pytest.raises(StoreError, match=r"thesis\.tex"):
        read_entry(target, manifest=MANIFEST, exact=True)


def test_writers_of_one_key_take_turns(tmp_path):
    """While one holder has a key's lock, a second thread asking for it waits
    (checked 0.3 s later: a margin far above a thread's start-up) and gets it once
    the first lets go."""
    acquired = threading.Event()

    def second():
        with entry_lock(tmp_path, KEY):
            acquired.set()

    with entry_lock(tmp_path, KEY):
        thread = threading.Thread(target=second)
        thread.start()
        assert not acquired.wait(0.3)
    assert acquired.wait(10)
    thread.join()
