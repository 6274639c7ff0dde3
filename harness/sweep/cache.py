"""The results cache: one entry per sweep row, content-addressed by its key.

An entry is a folder ``ROOT/KEY/`` holding ``row.json`` and ``page/`` (the row's
page and data files as ``caustics compare`` writes them: ``index.html``,
``metrics.json``, the EXR originals, previews). ``row.json`` holds the row's
values (metrics, warm time, worker, ...), the SHA-256 of every file under
``page/`` and ``document_sha256``, the SHA-256 of the rest of the JSON (keys
sorted, no whitespace), so the manifest covers the JSON as well as the files.

Writing (:meth:`ResultsCache.store`): the entry is built in a temporary folder
``ROOT/.KEY.tmp-XXXXXXXX`` and renamed into place in one step, under the same
exclusive lock per key as the reference cache (:func:`renderers.mitsuba.cache.entry_lock`),
so a reader sees a whole entry or none; Ctrl-C or a crash leaves at most a
temporary folder, which later writes remove once it is an hour old. Reading
(:meth:`ResultsCache.load`) checks the document, its digest, its key and every
file; anything else (a truncated file, an edit, garbage) is a miss with one
:class:`InvalidResultWarning` line, and the row is computed again.

The default root is ``sweep-results/`` inside the reference cache's root, so one
``--cache-dir`` (or ``$CAUSTICS_CACHE_DIR``) holds both, and one folder is deleted
to start over.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import tempfile
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from renderers.mitsuba.cache import entry_lock
from scenes.files import dumps_strict

__all__ = ["PAGE", "ROW_JSON", "STALE_AFTER", "CachedRow", "InvalidResultWarning",
           "ResultsCache", "results_dir"]

ROW_JSON = "row.json"
PAGE = "page"
#: Seconds after which a temporary folder left by a killed writer is removed.
STALE_AFTER = 3600.0
_FOLDER = "sweep-results"


class InvalidResultWarning(UserWarning):
    """A results-cache entry failed its checks and is computed again."""


def results_dir(reference_root: str | os.PathLike) -> Path:
    """The results cache's root inside the reference cache's ``reference_root``."""
    return Path(reference_root) / _FOLDER


@dataclass(frozen=True)
class CachedRow:
    """A row read from the cache: its values and its page folder."""

    key: str
    row: dict[str, Any]
    page: Path


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _digest(document: dict) -> str:
    rest = {k: v for k, v in document.items() if k != "document_sha256"}
    return hashlib.sha256(json.dumps(rest, sort_keys=True, separators=(",", ":"))
                          .encode()).hexdigest()


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


class ResultsCache:
    """Rows by key under ``root`` (see the module docstring)."""

    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)

    def _check(self, key: str) -> CachedRow:
        """The entry of ``key``, or ValueError/OSError saying what is wrong."""
        entry = self.root / key
        document = json.loads((entry / ROW_JSON).read_text("utf-8"))
        if not isinstance(document, dict):
            raise ValueError(f"{ROW_JSON} is not a JSON object")
        for name, kind in (("key", str), ("row", dict), ("files", dict),
                           ("document_sha256", str)):
            if not isinstance(document.get(name), kind):
                raise ValueError(f"{ROW_JSON}: {name!r} missing or of the wrong type")
        if document["document_sha256"] != _digest(document):
            raise ValueError(f"{ROW_JSON}: content does not match its recorded SHA-256")
        if document["key"] != key:
            raise ValueError("stored under another key")
        page = entry / PAGE
        listed = set(document["files"])
        present = {p.relative_to(page).as_posix() for p in page.rglob("*") if p.is_file()}
        if listed != present:
            raise ValueError(f"files differ from the manifest: missing "
                             f"{sorted(listed - present)}, extra {sorted(present - listed)}")
        for name, digest in document["files"].items():
            if _sha256(page / name) != digest:
                raise ValueError(f"{PAGE}/{name} does not match its recorded SHA-256")
        return CachedRow(key, document["row"], page)

    def load(self, key: str) -> CachedRow | None:
        """The cached row of ``key``, or None when there is none or it is invalid
        (then one :class:`InvalidResultWarning`)."""
        if not (self.root / key).exists():
            return None
        try:
            return self._check(key)
        except (OSError, ValueError, UnicodeDecodeError) as error:
            reason = " ".join(str(error).split())
            warnings.warn(f"invalid cached sweep row {key[:12]}, computing it again: {reason}",
                          InvalidResultWarning, stacklevel=2)
            return None

    def _remove_stale(self) -> None:
        now = time.time()
        with contextlib.suppress(OSError):
            for path in self.root.glob(".*.tmp-*"):
                with contextlib.suppress(OSError):
                    if path.is_dir() and now - path.stat().st_mtime > STALE_AFTER:
                        shutil.rmtree(path, ignore_errors=True)

    def store(self, key: str, row: dict[str, Any], write_page: Callable[[Path], None]) -> CachedRow:
        """Write the entry of ``key``: ``write_page(folder)`` fills ``page/``, then
        ``row.json`` is written and the entry renamed into place (see the module
        docstring). An existing entry (a concurrent sweep's, or an invalid one) is
        replaced."""
        self.root.mkdir(parents=True, exist_ok=True)
        self._remove_stale()
        with entry_lock(self.root, key):
            staging = Path(tempfile.mkdtemp(dir=self.root, prefix=f".{key}.tmp-"))
            try:
                os.chmod(staging, 0o777 & ~_umask())
                page = staging / PAGE
                page.mkdir()
                write_page(page)
                files = {p.relative_to(page).as_posix(): _sha256(p)
                         for p in sorted(page.rglob("*")) if p.is_file()}
                document = json.loads(dumps_strict({"key": key, "row": row, "files": files},
                                                   sort_keys=True))
                document["document_sha256"] = _digest(document)
                with open(staging / ROW_JSON, "wb") as handle:
                    handle.write(dumps_strict(document, sort_keys=True).encode("utf-8"))
                    handle.flush()
                    os.fsync(handle.fileno())
                entry = self.root / key
                if entry.exists():
                    old = Path(tempfile.mkdtemp(dir=self.root, prefix=f".{key}.tmp-"))
                    entry.rename(old / key)
                    staging.rename(entry)
                    shutil.rmtree(old, ignore_errors=True)
                else:
                    staging.rename(entry)
            except BaseException:
                shutil.rmtree(staging, ignore_errors=True)
                raise
        return CachedRow(key, document["row"], entry / PAGE)
