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
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["NULL_REASONS", "atomic_write_bytes", "dumps_strict", "jsonable", "strict_json"]

#: Top-level key of a strict-JSON document that says why each ``null`` replaced a
#: non-finite float (JSON Pointer to reason).
NULL_REASONS = "null_reasons"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write_bytes(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temp file, fsync, rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        # mkstemp creates 0600; give the file the mode a plain open() would have.
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


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
