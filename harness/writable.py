"""Can we write there? Output folders and the reference cache, checked before any
rendering, so a typo in ``-o`` costs seconds, not a run.

A real probe (create and remove a hidden file) rather than ``os.access``: access
says yes to root on a read-only folder and cannot see a read-only mount.
Imports nothing heavy: the CLI checks ``-o`` before it loads a handler.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from harness.terminal import warn
from scenes.errors import HarnessError

__all__ = ["OutputDirError", "check_output_dir", "usable_cache"]


class OutputDirError(HarnessError):
    """An output folder cannot be written (not a folder, read-only, ...)."""


def _probe(directory: Path) -> str | None:
    """Why a file cannot be created in ``directory``, or None when it can."""
    try:
        fd, name = tempfile.mkstemp(dir=directory, prefix=".caustics-write-probe-")
    except OSError as error:
        return error.strerror or type(error).__name__
    os.close(fd)
    os.unlink(name)
    return None


def _exists(path: Path) -> bool:
    try:
        return path.exists()
    except OSError:  # e.g. a parent we may not search: treat as absent, the probe says why
        return False


def check_output_dir(path: str | os.PathLike, *, what: str = "output directory") -> Path:
    """Raise :class:`OutputDirError` unless ``path`` is, or can be created as, a
    folder we can write in; creates nothing.

    A missing folder is judged by its nearest existing ancestor (it will be created
    there). The error is one line naming ``path``.
    """
    path = Path(path)
    if _exists(path) and not path.is_dir():
        raise OutputDirError(f"{what} {path}: exists and is not a directory")
    existing = path
    while not _exists(existing) and existing.parent != existing:
        existing = existing.parent
    if not existing.is_dir():
        raise OutputDirError(f"{what} {path}: {existing} is not a directory")
    problem = _probe(existing)
    if problem is not None:
        where = "" if existing == path else f" (in {existing})"
        raise OutputDirError(f"{what} {path}: cannot write{where}: {problem}")
    return path


def usable_cache(root: str | os.PathLike) -> bool:
    """Whether the reference cache at ``root`` can be used: it is created if missing
    and must take a new file (the cache writes entries and lock files). When it
    cannot, one warning line says so and the caller renders without the cache."""
    root = Path(root)
    problem = None
    if _exists(root) and not root.is_dir():
        problem = "not a directory"
    else:
        try:
            root.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            problem = error.strerror or type(error).__name__
    problem = problem or _probe(root)
    if problem is None:
        return True
    warn(f"reference cache {root}: cannot write ({problem}); rendering references "
         "without the cache")
    return False
