"""A content-addressed store: a key names a folder of files and a JSON manifest that
hashes them; the reference cache (:mod:`renderers.mitsuba.cache`) and the sweep's
results cache (:mod:`harness.sweep.cache`) are both built on it.

An entry is a folder ``ROOT/KEY/`` holding its files and a manifest (a JSON object,
its name chosen by the user of the store) recording

* ``files``: the SHA-256 (hex) of every file under the entry's files folder (the
  entry folder or one folder in it), by path relative to it (``/``-separated);
* ``document_sha256``: the SHA-256 of the rest of the manifest in its canonical
  form (keys sorted, no whitespace; :func:`document_digest`), so the manifest covers
  itself as well as the files;

and whatever else its user keeps there. Every manifest is strict JSON
(:func:`scenes.files.dumps_strict`).

Writing (:func:`write_entry`, :meth:`ContentStore.write`): the files and the manifest
(last) go into a fresh temporary folder beside the entry, ``.NAME.tmp-XXXXXXXX`` (the
same file system), which is renamed into place in one step (:func:`publish`; an entry
already there is renamed aside first and then deleted). A writer that raises (an
interrupt too) removes its temporary folder; one that is killed leaves it, and the
next write beside it removes temporary folders older than :data:`STALE_AFTER`.
Writers of one key serialise on an exclusive ``fcntl`` lock on ``ROOT/KEY.lock``
(:func:`entry_lock`).

Reading (:func:`read_entry`, :meth:`ContentStore.read`): the manifest parses, is an
object, its digest matches, the user's own checks pass, and every listed file is
there with its recorded SHA-256 (with ``exact``, no other file is). Anything else
(a truncated file, a killed writer, garbage, a hand edit) raises :class:`StoreError`
naming the path; the caches take it for a miss and compute the entry again.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import re
import shutil
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

from scenes.errors import HarnessError
from scenes.files import dumps_strict, make_temporary_folder

__all__ = ["DIGEST", "FILES", "STALE_AFTER", "ContentStore", "Entry", "StoreError",
           "document_digest", "entry_lock", "file_sha256", "publish", "read_entry",
           "read_manifest", "remove_stale_temporaries", "verify_files", "write_entry"]

#: Manifest key of the digest over the rest of the manifest.
DIGEST = "document_sha256"
#: Manifest key of the files' SHA-256 by relative path.
FILES = "files"
#: Seconds after which a temporary folder left by a killed writer is removed.
STALE_AFTER = 3600.0

_SHA256 = re.compile(r"[0-9a-f]{64}")


class StoreError(HarnessError, ValueError):
    """A store entry is missing, partial or corrupt (the message names the path)."""


def file_sha256(path: str | Path) -> str:
    """Hex SHA-256 of the bytes of the file at ``path``."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def document_digest(document: dict[str, Any]) -> str:
    """Hex SHA-256 of ``document`` without its :data:`DIGEST` key, in the canonical
    form (keys sorted, no whitespace) that a parse and re-dump reproduce."""
    rest = {k: v for k, v in document.items() if k != DIGEST}
    text = json.dumps(rest, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _temp_prefix(name: str) -> str:
    return f".{name}.tmp-"


def remove_stale_temporaries(parent: Path, *, now: float | None = None) -> None:
    """Remove temporary folders (``.NAME.tmp-*``) in ``parent`` older than
    :data:`STALE_AFTER`: what writers killed mid-write left behind. Younger ones
    may belong to a writer still at work and are kept."""
    now = time.time() if now is None else now
    with contextlib.suppress(OSError):
        for path in parent.glob(".*.tmp-*"):
            with contextlib.suppress(OSError):
                if path.is_dir() and now - path.stat().st_mtime > STALE_AFTER:
                    shutil.rmtree(path, ignore_errors=True)


@contextlib.contextmanager
def entry_lock(root: Path, key: str) -> Iterator[None]:
    """Exclusive lock on one key, ``root/KEY.lock`` (released on exit, or by the OS
    if the process is killed)."""
    root.mkdir(parents=True, exist_ok=True)
    with open(root / f"{key}.lock", "a+b") as handle:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle.fileno(), fcntl.LOCK_UN)


def _always(_: Path) -> bool:
    return True


def publish(staging: Path, target: Path, *, manifest: str,
            replace_whole: Callable[[Path], bool] = _always) -> None:
    """Make the finished folder ``staging`` the entry ``target``.

    Absent ``target``: one rename. A ``target`` folder that ``replace_whole`` accepts
    (an old entry: the default accepts every folder): renamed aside, ``staging``
    renamed in, the old one deleted. Any other folder (or a link to one): the files
    are moved in one by one, ``manifest`` last (until it lands, the old manifest's
    hashes no longer match the new files, so a reader sees a miss, never a mix).
    """
    try:
        staging.rename(target)
        return
    except OSError:
        if not target.is_dir():
            raise
    if not target.is_symlink() and replace_whole(target):
        old = make_temporary_folder(target.parent, _temp_prefix(target.name))
        target.rename(old / target.name)
        staging.rename(target)
        shutil.rmtree(old, ignore_errors=True)
        return
    names = sorted(p.name for p in staging.iterdir())
    for name in [n for n in names if n != manifest] + [manifest]:
        os.replace(staging / name, target / name)
    staging.rmdir()


def _hash_files(folder: Path) -> dict[str, str]:
    return {p.relative_to(folder).as_posix(): file_sha256(p)
            for p in sorted(folder.rglob("*")) if p.is_file()}


def write_entry(directory: str | Path, fill: Callable[[Path], dict[str, Any]], *,
                manifest: str, files_under: str | None = None,
                replace_whole: Callable[[Path], bool] = _always) -> dict[str, Any]:
    """Write the entry ``directory`` atomically; return its manifest as written.

    Parameters
    ----------
    directory
        The entry folder (created, or replaced as :func:`publish` says).
    fill
        ``fill(staging)`` writes the entry's files into the temporary folder
        ``staging`` (under ``files_under``, which exists already) and returns the
        rest of the manifest: a mapping without :data:`FILES` and :data:`DIGEST`
        (any such keys are overwritten).
    manifest
        File name of the manifest in the entry folder.
    files_under
        Folder inside the entry whose files (all of them) are hashed into
        :data:`FILES`; None for the entry folder itself.
    replace_whole
        Passed to :func:`publish`.

    Returns
    -------
    dict
        The manifest as a reader parses it (strict JSON: a non-finite float is
        ``null``, with its reason under ``null_reasons``).
    """
    directory = Path(directory)
    directory.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(directory.parent)
    staging = make_temporary_folder(directory.parent, _temp_prefix(directory.name))
    try:
        files_folder = staging if files_under is None else staging / files_under
        files_folder.mkdir(exist_ok=True)
        document = dict(fill(staging))
        document[FILES] = _hash_files(files_folder)
        # The digest is taken over the document as a reader will parse it (tuples
        # become lists, keys strings, non-finite numbers null), so the reader's
        # re-dump reproduces it.
        document = json.loads(dumps_strict(document, sort_keys=True))
        document[DIGEST] = document_digest(document)
        with open(staging / manifest, "wb") as handle:
            handle.write(dumps_strict(document, indent=2, sort_keys=True).encode("utf-8"))
            handle.flush()
            os.fsync(handle.fileno())
        publish(staging, directory, manifest=manifest, replace_whole=replace_whole)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return document


def read_manifest(path: str | Path) -> dict[str, Any]:
    """The manifest at ``path``, parsed, checked to be an object whose
    :data:`DIGEST` matches the rest of it.

    Raises
    ------
    StoreError
        Missing or unreadable file, text that is not JSON, not an object, no digest,
        or content that does not match its digest (edited or corrupt).
    """
    path = Path(path)
    try:
        document = json.loads(path.read_text("utf-8"))
    except (OSError, ValueError) as error:  # UnicodeDecodeError is a ValueError
        raise StoreError(f"{path}: unreadable ({error})") from None
    if not isinstance(document, dict):
        raise StoreError(f"{path}: not a JSON object but {type(document).__name__}")
    if not isinstance(document.get(DIGEST), str):
        raise StoreError(f"{path}: no {DIGEST!r}")
    if document[DIGEST] != document_digest(document):
        raise StoreError(f"{path}: content does not match its recorded SHA-256 "
                         "(edited or corrupt)")
    return document


def _inside(name: str) -> bool:
    """Whether the relative path ``name`` stays inside its folder."""
    parts = PurePosixPath(name).parts
    return bool(parts) and not PurePosixPath(name).is_absolute() and ".." not in parts


def verify_files(folder: str | Path, files: Any, *, exact: bool) -> None:
    """Check that every file of ``files`` (relative path to hex SHA-256) is in
    ``folder`` with that digest; with ``exact``, also that no other file is.

    Raises
    ------
    StoreError
        ``files`` is not such a mapping, names a path outside ``folder``, or a file
        is missing, extra or does not match its digest (the message names it).
    """
    folder = Path(folder)
    if not (isinstance(files, dict)
            and all(isinstance(v, str) and _SHA256.fullmatch(v) for v in files.values())):
        raise StoreError(f"{folder}: {FILES!r} is not a mapping of file names to SHA-256")
    outside = sorted(name for name in files if not _inside(name))
    if outside:
        raise StoreError(f"{folder}: {FILES!r} names paths outside the entry: {outside}")
    try:
        if exact:
            present = {p.relative_to(folder).as_posix()
                       for p in folder.rglob("*") if p.is_file()}
            extra = sorted(present - set(files))
            if extra:
                raise StoreError(f"{folder}: files not in the manifest: {extra}")
        for name, digest in sorted(files.items()):
            path = folder / name
            if not path.is_file() or file_sha256(path) != digest:
                raise StoreError(f"{path}: missing or does not match its recorded SHA-256")
    except OSError as error:
        raise StoreError(f"{error.filename or folder}: unreadable ({error.strerror})") from None


def read_entry(directory: str | Path, *, manifest: str, files_under: str | None = None,
               exact: bool = True,
               check: Callable[[dict[str, Any], Path], None] | None = None) -> dict[str, Any]:
    """The verified manifest of the entry ``directory`` (see the module docstring).

    Parameters
    ----------
    directory
        The entry folder.
    manifest, files_under
        As for :func:`write_entry`.
    exact
        Also fail on files under the files folder that the manifest does not list.
    check
        ``check(document, manifest_path)``: the user's own checks of the manifest
        (its schema), run after the digest and before the files; it raises
        :class:`StoreError` (or a subclass of it).

    Raises
    ------
    StoreError
        The entry fails a check (:func:`read_manifest`, ``check``,
        :func:`verify_files`).
    """
    directory = Path(directory)
    path = directory / manifest
    document = read_manifest(path)
    if check is not None:
        check(document, path)
    files_folder = directory if files_under is None else directory / files_under
    verify_files(files_folder, document.get(FILES), exact=exact)
    return document


@dataclass(frozen=True)
class Entry:
    """A verified entry: its key, folder and manifest."""

    key: str
    folder: Path
    manifest: dict[str, Any]


@dataclass(frozen=True, kw_only=True)
class ContentStore:
    """Entries by key under ``root`` (see the module docstring).

    Attributes
    ----------
    root : Path
        The store's folder: ``ROOT/KEY/`` entries, ``ROOT/KEY.lock`` locks.
    manifest : str
        File name of the manifest in each entry.
    files_under : str or None
        Folder inside each entry whose files the manifest lists (None: the entry).
    key_field : str
        Manifest key recording the entry's own key: an entry found under another key
        (a folder moved or copied) is invalid.
    """

    root: Path
    manifest: str
    files_under: str | None = None
    key_field: str = "key"

    def folder(self, key: str) -> Path:
        """The folder of ``key``'s entry (which may not exist)."""
        return self.root / key

    def read(self, key: str, *,
             check: Callable[[dict[str, Any], Path], None] | None = None) -> Entry | None:
        """The verified entry of ``key``; None when there is none.

        Raises
        ------
        StoreError
            The entry is there but fails a check (:func:`read_entry`, every file
            listed and no other), or records another key.
        """
        folder = self.folder(key)
        if not folder.exists():
            return None

        def check_key(document: dict[str, Any], path: Path) -> None:
            if document.get(self.key_field) != key:
                raise StoreError(f"{path}: stored under another key")
            if check is not None:
                check(document, path)

        document = read_entry(folder, manifest=self.manifest, files_under=self.files_under,
                              exact=True, check=check_key)
        return Entry(key, folder, document)

    def write(self, key: str, fill: Callable[[Path], dict[str, Any]]) -> Entry:
        """Write ``key``'s entry under its lock (:func:`write_entry`; the manifest
        records ``key`` as :attr:`key_field`); an entry already there (a concurrent
        writer's, or an invalid one) is replaced whole."""
        self.root.mkdir(parents=True, exist_ok=True)
        with entry_lock(self.root, key):
            document = write_entry(
                self.folder(key), lambda staging: {**fill(staging), self.key_field: key},
                manifest=self.manifest, files_under=self.files_under)
        return Entry(key, self.folder(key), document)
