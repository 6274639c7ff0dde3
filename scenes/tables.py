"""Scene dataclasses back to the TOML tables they are read from.

:func:`to_table` is the inverse of :func:`scenes.schema.build`: ``build(type(x),
to_table(x))`` gives ``x`` again for every scene dataclass (tuples become arrays, a
tagged-union member gets its ``type`` key, ``None`` fields are left out because TOML has
no null and ``None`` is every optional field's default). The importers write scene files
with it, and the glTF and Mitsuba XML exports store each shape's exact table in the
file (:func:`portable_table`: without this machine's paths).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from scenes.schema import tag_of

__all__ = ["portable_table", "to_table"]


def to_table(value: Any) -> Any:
    """``value`` (a scene dataclass, tuple, or plain value) as TOML values.

    Internal fields (``Scene.source``) are left out; a field with its own TOML key
    (``Scene.info`` is ``[scene]``) is written under that key.
    """
    if dataclasses.is_dataclass(value):
        table: dict[str, Any] = {}
        if tag_of(type(value)):
            table["type"] = tag_of(type(value))
        for field in dataclasses.fields(value):
            item = getattr(value, field.name)
            if field.metadata.get("internal") or item is None:
                continue
            table[field.metadata.get("key") or field.name] = to_table(item)
        return table
    if isinstance(value, tuple | list):
        return [to_table(item) for item in value]
    return value


def portable_table(table: Any) -> Any:
    """A shape's table without the paths of the files it names (they are this machine's;
    an export carries the triangles themselves): a ``builtin:`` mesh keeps its name."""
    if isinstance(table, dict):
        return {k: portable_table(v) for k, v in table.items()
                if not (k == "file" and not str(v).startswith("builtin:"))}
    if isinstance(table, list):
        return [portable_table(item) for item in table]
    return table
