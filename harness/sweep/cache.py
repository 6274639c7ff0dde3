"""The results cache: one entry per sweep row, content-addressed by its key.

An entry is a folder ``ROOT/KEY/`` holding ``row.json`` and ``page/`` (the row's
page and data files as ``caustics compare`` writes them: ``index.html``,
``metrics.json``, the EXR originals, previews). ``row.json`` holds the row's
values (metrics, warm time, worker, ...), the SHA-256 of every file under
``page/`` and ``document_sha256``, the SHA-256 of the rest of the JSON (keys
sorted, no whitespace), so the manifest covers the JSON as well as the files.

An entry is one of the content-addressed store (:mod:`renderers.store`, ``row.json``
its manifest, ``page/`` its files folder), which writes and verifies it.

Writing (:meth:`ResultsCache.store`): the entry is built in a temporary folder
``ROOT/.KEY.tmp-XXXXXXXX`` and renamed into place in one step, under the same
exclusive lock per key as the reference cache (:func:`renderers.store.entry_lock`),
so a reader sees a whole entry or none; Ctrl-C or a crash leaves at most a
temporary folder, which later writes remove once it is an hour old. Reading
(:meth:`ResultsCache.load`) checks the document, its digest, its key and every
file (no more, no fewer than listed); anything else (a truncated file, an edit,
garbage) is a miss with one :class:`InvalidResultWarning` line, and the row is
computed again.

The default root is ``sweep-results/`` inside the reference cache's root, so one
``--cache-dir`` (or ``$CAUSTICS_CACHE_DIR``) holds both, and one folder is deleted
to start over.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from renderers.store import STALE_AFTER, ContentStore, StoreError

__all__ = ["PAGE", "ROW_JSON", "STALE_AFTER", "CachedRow", "InvalidResultWarning",
           "ResultsCache", "results_dir"]

ROW_JSON = "row.json"
PAGE = "page"
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


def _check_row(document: dict[str, Any], path: Path) -> None:
    if not isinstance(document.get("row"), dict):
        raise StoreError(f"{path}: 'row' missing or not an object")


class ResultsCache:
    """Rows by key under ``root`` (see the module docstring)."""

    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)
        self._store = ContentStore(root=self.root, manifest=ROW_JSON, files_under=PAGE)

    def load(self, key: str) -> CachedRow | None:
        """The cached row of ``key``, or None when there is none or it is invalid
        (then one :class:`InvalidResultWarning`)."""
        try:
            entry = self._store.read(key, check=_check_row)
        except StoreError as error:
            reason = " ".join(str(error).split())
            warnings.warn(f"invalid cached sweep row {key[:12]}, computing it again: {reason}",
                          InvalidResultWarning, stacklevel=2)
            return None
        return None if entry is None else CachedRow(key, entry.manifest["row"],
                                                     entry.folder / PAGE)

    def store(self, key: str, row: dict[str, Any], write_page: Callable[[Path], None]) -> CachedRow:
        """Write the entry of ``key``: ``write_page(folder)`` fills ``page/``, then
        ``row.json`` is written and the entry renamed into place (see the module
        docstring). An existing entry (a concurrent sweep's, or an invalid one) is
        replaced."""
        def fill(staging: Path) -> dict[str, Any]:
            write_page(staging / PAGE)
            return {"row": row}

        entry = self._store.write(key, fill)
        return CachedRow(key, entry.manifest["row"], entry.folder / PAGE)
