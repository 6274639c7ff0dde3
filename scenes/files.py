"""Files every layer writes: atomic writes and strict-JSON values.

A write goes to a temporary file in the same directory, is flushed to disk and
renamed into place, so a reader never sees a half-written file and an interrupted
run leaves the old file (or none) behind.

Every JSON file the tool writes is strict JSON (RFC 8259: no ``NaN``, no
``Infinity``), made by :func:`dumps_strict`. A non-finite float becomes ``null`` and
the document says why: a top-level ``"null_reasons"`` object maps the JSON Pointer
(RFC 6901) of each such ``null`` to ``"NaN"``, ``"+Infinity"`` or ``"-Infinity"``,
so a reader can tell a value that was never computed (a plain ``null``) from one
that was computed and is not a finite number.

File modes: ``mkstemp`` and ``mkdtemp`` create 0600 files and 0700 folders; every
file and folder the tool writes gets instead the mode a plain ``open()`` or
``mkdir()`` would give it, 0666 or 0777 less the process's umask
(:func:`process_umask`). The umask is read without changing it: setting it (even to
restore it at once) changes it for every thread of the process, and a file another
thread creates in between (under a threaded Dask worker) would get mode 0666.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["NULL_REASONS", "atomic_path", "atomic_write_bytes", "dumps_strict", "jsonable",
           "make_temporary_folder", "process_umask", "strict_json"]

#: Top-level key of a strict-JSON document that says why each ``null`` replaced a
#: non-finite float (JSON Pointer to reason).
NULL_REASONS = "null_reasons"


#: Where Linux (4.7 and later) shows a process's umask (the ``Umask:`` line, octal).
_PROC_STATUS = "/proc/self/status"


def _umask_from_proc() -> int | None:
    """The ``Umask:`` line of :data:`_PROC_STATUS`, or None where there is none."""
    try:
        with open(_PROC_STATUS, encoding="ascii", errors="replace") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        return None
    return None


def _umask_from_probe() -> int:
    """The umask as the kernel applies it: the bits it clears from a probe file
    created with mode 0777 in a fresh private temporary folder."""
    folder = tempfile.mkdtemp(prefix=".umask-probe-")
    try:
        fd = os.open(os.path.join(folder, "probe"), os.O_CREAT | os.O_EXCL | os.O_WRONLY,
                     0o777)
        try:
            return 0o777 & ~stat.S_IMODE(os.fstat(fd).st_mode)
        finally:
            os.close(fd)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def process_umask() -> int:
    """The process's file-mode creation mask, read without changing it.

    Linux: the ``Umask:`` line of ``/proc/self/status``. Elsewhere (or on a kernel
    older than 4.7): the bits the kernel clears from a probe file created with mode
    0777. Either way it is read on every call, so a umask the program changes later
    is followed; the umask itself is never set (see the module docstring).

    Returns
    -------
    int
        The umask, e.g. ``0o022``; a plain ``open()`` creates files with mode
        ``0o666 & ~umask``, ``mkdir()`` folders with ``0o777 & ~umask``.
    """
    mask = _umask_from_proc()
    return _umask_from_probe() if mask is None else mask


def make_temporary_folder(parent: str | Path, prefix: str) -> Path:
    """A new, uniquely named folder ``parent/PREFIXxxxxxxxx`` (``mkdtemp``) with the
    mode a plain ``mkdir()`` gives (0777 less the umask), not ``mkdtemp``'s 0700."""
    folder = Path(tempfile.mkdtemp(dir=parent, prefix=prefix))
    try:
        os.chmod(folder, 0o777 & ~process_umask())
    except BaseException:
        folder.rmdir()
        raise
    return folder


@contextlib.contextmanager
def atomic_path(path: str | Path, *, suffix: str = ".tmp") -> Iterator[Path]:
    """Yield a temporary path beside ``path`` to write into; on a normal exit it is
    renamed onto ``path`` in one step, on an exception (an interrupt too) deleted.

    The temporary file (``.NAME.XXXXXXXX`` + ``suffix``, in ``path``'s folder, so on
    the same file system) exists, empty, with the mode a plain ``open()`` gives
    (0666 less the umask); a writer that keeps the mode of the file it writes into
    passes it on to ``path``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
    os.close(fd)
    try:
        os.chmod(tmp, 0o666 & ~process_umask())
        yield Path(tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def atomic_write_bytes(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temp file, fsync, rename; see
    :func:`atomic_path`)."""
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        handle.write(data)
        handle.flush()
        os.fsync(handle.fileno())


def jsonable(value: Any) -> Any:
    """Plain JSON values: numpy to Python, NaN to null, ±inf to "inf"/"-inf"."""
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return jsonable(value.item())
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    return value


def _pointer_token(key: str) -> str:
    return key.replace("~", "~0").replace("/", "~1")


def _non_finite_reason(value: float) -> str:
    return "NaN" if math.isnan(value) else ("+Infinity" if value > 0 else "-Infinity")


def strict_json(value: Any) -> tuple[Any, dict[str, str]]:
    """Plain, strict JSON values, and why each ``null`` that replaced a number is there.

    NumPy scalars and arrays become Python numbers and lists, tuples lists, path-like
    values strings, mapping keys strings; every non-finite float becomes ``None``.

    Returns
    -------
    value
        The converted value: ``json.dumps(value, allow_nan=False)`` succeeds on it.
    reasons : dict of str to str
        JSON Pointer (RFC 6901, ``""`` is the whole value) of each replaced float to
        ``"NaN"``, ``"+Infinity"`` or ``"-Infinity"``; empty when every number was finite.
    """
    reasons: dict[str, str] = {}

    def convert(item: Any, pointer: str) -> Any:
        if isinstance(item, np.generic | np.ndarray):
            item = item.tolist()
        if isinstance(item, float) and not math.isfinite(item):
            reasons[pointer] = _non_finite_reason(item)
            return None
        if isinstance(item, dict):
            return {str(k): convert(v, f"{pointer}/{_pointer_token(str(k))}")
                    for k, v in item.items()}
        if isinstance(item, list | tuple):
            return [convert(v, f"{pointer}/{i}") for i, v in enumerate(item)]
        if isinstance(item, os.PathLike):
            return os.fspath(item)
        return item

    return convert(value, ""), reasons


def dumps_strict(value: Any, *, indent: int | None = 2, sort_keys: bool = False) -> str:
    """``value`` as strict JSON text (:func:`strict_json`; see the module docstring).

    When a non-finite float was replaced and ``value`` is a mapping, the document
    gets a top-level :data:`NULL_REASONS` object naming each such ``null``.

    Raises
    ------
    ValueError
        ``value`` already has a :data:`NULL_REASONS` key and a float was replaced
        (the two records could not be told apart).
    TypeError
        A value JSON cannot hold (an object, a set).
    """
    plain, reasons = strict_json(value)
    if reasons and isinstance(plain, dict):
        if NULL_REASONS in plain:
            raise ValueError(f"the document already has a {NULL_REASONS!r} key")
        plain = {**plain, NULL_REASONS: reasons}
    return json.dumps(plain, indent=indent, sort_keys=sort_keys, allow_nan=False)
