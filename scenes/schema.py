"""Schema machinery: turn TOML tables into frozen dataclasses, collecting every problem.

The scene model (``scenes.model``) declares each field once, with its type,
unit, documentation and bounds in the field's metadata. This module reads those
declarations to

* convert a parsed TOML table into the dataclass, reporting *every* problem with
  the file and the dotted field path (``objects[0].material.ior: must be >= 1``);
* reject unknown keys, wrong types, vectors of the wrong length, non-finite numbers,
  numbers outside single precision (both renderers compute in float32: a number
  must stay finite in float32, and one that must be positive must stay positive),
  integers outside TOML's 64-bit range, and out-of-range values;
* keep file paths inside a containment folder (the scene file's), unless the caller
  allows outside paths;
* resolve tagged unions by their ``type`` key (``type = "point"``);
* render the field reference that the README documents (``describe_schema``).

Nothing here raises anything but :class:`SceneError`, whatever the input.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from dataclasses import MISSING, dataclass
from pathlib import Path
from typing import Any, Literal, Union

import numpy as np

from scenes.errors import HarnessError

__all__ = [
    "FLOAT32_MAX",
    "OUTSIDE_PATHS_VARIABLE",
    "Problem",
    "SceneError",
    "build",
    "describe_schema",
    "float32_overflows",
    "spec",
    "tag_of",
]


@dataclass(frozen=True)
class Problem:
    """One validation problem: where it is and what is wrong."""

    file: str
    path: str
    message: str

    def __str__(self) -> str:
        where = f"{self.path}: " if self.path else ""
        return f"{self.file}: {where}{self.message}"


class SceneError(HarnessError, ValueError):
    """A scene description could not be read; ``problems`` lists every reason.

    ``str(error)`` is one line per problem, each naming the file and field path.
    """

    def __init__(self, problems: list[Problem]):
        self.problems = list(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


def spec(
    default: Any = MISSING,
    *,
    doc: str,
    unit: str = "",
    ge: float | None = None,
    gt: float | None = None,
    le: float | None = None,
    lt: float | None = None,
    nonzero: bool = False,
    path: bool = False,
    key: str | None = None,
    internal: bool = False,
) -> Any:
    """Declare a schema field.

    Parameters
    ----------
    default
        Default value; omitted means the field is required. Tuples are used for
        vectors so the dataclasses stay hashable.
    doc, unit
        Text and SI unit shown in the field reference.
    ge, gt, le, lt
        Bounds applied to a number or to every component of a vector.
    nonzero
        A vector must not be all zeros (directions, axes).
    path
        The string names a file relative to the scene file; it must exist
        unless it starts with ``builtin:``.
    key
        TOML key when it differs from the attribute name.
    internal
        Set by the loader, never read from TOML (e.g. the source path).
    """
    meta = {
        "doc": doc,
        "unit": unit,
        "ge": ge,
        "gt": gt,
        "le": le,
        "lt": lt,
        "nonzero": nonzero,
        "path": path,
        "key": key,
        "internal": internal,
    }
    return dataclasses.field(default=default, metadata=meta)


def tag_of(cls: type) -> str | None:
    """The ``type`` tag of a tagged-union member class, or None."""
    return getattr(cls, "kind", None)


class _Invalid:
    """Sentinel for a value that failed conversion (a problem was recorded)."""


_INVALID = _Invalid()


#: Largest finite float32; the renderers (GLSL, Mitsuba's single-precision variants)
#: hold every scene number in this format.
FLOAT32_MAX = float(np.finfo(np.float32).max)


#: Environment variable that, set to 1, lets file paths leave the containment folder.
OUTSIDE_PATHS_VARIABLE = "CAUSTICS_ALLOW_OUTSIDE_PATHS"


def float32_overflows(value: float) -> bool:
    """Whether ``value`` (finite in float64) becomes infinite when cast to float32."""
    with np.errstate(over="ignore"):
        return bool(np.isinf(np.float32(value)))


@dataclass
class _Context:
    file: str
    base_dir: Path
    problems: list[Problem]
    # Folder that every file path must resolve inside; None allows any path.
    root: Path | None = None

    def add(self, path: str, message: str) -> _Invalid:
        self.problems.append(Problem(self.file, path, message))
        return _INVALID


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _type_name(value: Any) -> str:
    names = {bool: "boolean", int: "integer", float: "number", str: "string",
             list: "array", dict: "table"}
    return names.get(type(value), type(value).__name__)


def _union_members(tp: Any) -> tuple[Any, ...] | None:
    origin = typing.get_origin(tp)
    if origin is Union or origin is types.UnionType:
        return typing.get_args(tp)
    return None


def _is_tagged_union(tp: Any) -> bool:
    members = _union_members(tp)
    return bool(members) and all(
        dataclasses.is_dataclass(m) and tag_of(m) for m in members
    )


def _number(value: Any, path: str, ctx: _Context, *, integer: bool) -> Any:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        want = "an integer" if integer else "a number"
        return ctx.add(path, f"expected {want}, got {_type_name(value)}")
    if integer and not isinstance(value, int):
        return ctx.add(path, f"expected an integer, got {value!r}")
    if isinstance(value, int) and not -(2**63) <= value < 2**63:
        # tomllib accepts integers of any size; float() of a huge one raises.
        return ctx.add(path, "must fit in 64 bits (TOML's integer range)")
    if integer:
        return int(value)
    number = float(value)
    if not math.isfinite(number):
        return ctx.add(path, f"must be finite, got {value!r}")
    if float32_overflows(number):
        return ctx.add(path, f"{number:g} overflows float32 (largest {FLOAT32_MAX:.3g}); "
                             "the renderers compute in single precision")
    return number


def _check_bounds(value: Any, meta: dict, path: str, ctx: _Context) -> Any:
    comps = value if isinstance(value, tuple) else (value,)
    if not all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in comps):
        return value
    checks = [
        ("ge", lambda c, b: c >= b, ">="),
        ("gt", lambda c, b: c > b, ">"),
        ("le", lambda c, b: c <= b, "<="),
        ("lt", lambda c, b: c < b, "<"),
    ]
    for name, ok, symbol in checks:
        bound = meta.get(name)
        if bound is not None and not all(ok(c, bound) for c in comps):
            return ctx.add(path, f"must be {symbol} {bound:g}, got {_show(value)}")
    gt = meta.get("gt")
    if gt is not None and any(
        isinstance(c, float) and not float(np.float32(c)) > gt for c in comps
    ):
        # 1e-50 > 0 in float64 but is 0 in float32: a radius or size the GPU sees as 0.
        return ctx.add(path, f"must be > {gt:g} in float32 too, got {_show(value)}, "
                             "which single precision rounds to the bound")
    if meta.get("nonzero") and all(c == 0 for c in comps):
        return ctx.add(path, "must not be the zero vector")
    return value


def _show(value: Any) -> str:
    if isinstance(value, tuple):
        return "[" + ", ".join(f"{c:g}" for c in value) + "]"
    return f"{value:g}" if isinstance(value, float) else repr(value)


def _convert(value: Any, tp: Any, path: str, ctx: _Context, meta: dict) -> Any:
    """Convert one TOML value to ``tp``; record a problem and return _INVALID on failure."""
    if dataclasses.is_dataclass(tp):
        return _build_dataclass(tp, value, path, ctx)
    if _is_tagged_union(tp):
        return _build_tagged(typing.get_args(tp), value, path, ctx)
    members = _union_members(tp)
    if members is not None:
        non_none = [m for m in members if m is not type(None)]
        if value is None and len(non_none) < len(members):
            return None
        # Untagged unions (float | RGB): pick by the TOML value's shape.
        if len(non_none) == 1:
            return _convert(value, non_none[0], path, ctx, meta)
        scalar = [m for m in non_none if m in (int, float, str, bool)]
        vector = [m for m in non_none if typing.get_origin(m) is tuple]
        if isinstance(value, list) and vector:
            return _convert(value, vector[0], path, ctx, meta)
        if scalar and not isinstance(value, list):
            return _convert(value, scalar[0], path, ctx, meta)
        return ctx.add(path, f"expected a number or an array, got {_type_name(value)}")
    origin = typing.get_origin(tp)
    if origin is Literal:
        choices = typing.get_args(tp)
        if value not in choices or isinstance(value, bool):
            options = ", ".join(repr(c) for c in choices)
            return ctx.add(path, f"must be one of {options}, got {value!r}")
        return value
    if origin is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, list):
            return ctx.add(path, f"expected an array, got {_type_name(value)}")
        if len(args) == 2 and args[1] is Ellipsis:
            items = [
                _convert(v, args[0], f"{path}[{i}]", ctx, meta) for i, v in enumerate(value)
            ]
        else:
            if len(value) != len(args):
                return ctx.add(
                    path, f"expected an array of {len(args)} numbers, got {len(value)}"
                )
            items = [
                _convert(v, a, f"{path}[{i}]", ctx, {})
                for i, (v, a) in enumerate(zip(value, args, strict=True))
            ]
        if any(i is _INVALID for i in items):
            return _INVALID
        return _check_bounds(tuple(items), meta, path, ctx)
    if tp is bool:
        if not isinstance(value, bool):
            return ctx.add(path, f"expected a boolean, got {_type_name(value)}")
        return value
    if tp in (int, float):
        number = _number(value, path, ctx, integer=tp is int)
        if number is _INVALID:
            return number
        return _check_bounds(number, meta, path, ctx)
    if tp is str:
        if not isinstance(value, str):
            return ctx.add(path, f"expected a string, got {_type_name(value)}")
        if meta.get("path"):
            return _resolve_path(value, path, ctx)
        return value
    raise TypeError(f"schema type {tp!r} is not supported")  # a bug in the model


def _resolve_path(value: str, path: str, ctx: _Context) -> Any:
    if value.startswith("builtin:"):
        return value
    if not value:
        return ctx.add(path, "must name a file")
    try:
        resolved = (ctx.base_dir / value).resolve()
    except (OSError, RuntimeError, ValueError) as error:  # symlink loop, NUL byte
        return ctx.add(path, f"cannot resolve {value!r}: {error}")
    # Checked before existence, so a refused path says nothing about what lies outside.
    if ctx.root is not None and not resolved.is_relative_to(ctx.root):
        return ctx.add(
            path, f"{value} resolves to {resolved}, outside the scene's folder "
            f"{ctx.root}; set {OUTSIDE_PATHS_VARIABLE}=1 to allow files outside it")
    if not resolved.is_file():
        return ctx.add(path, f"file not found: {value} (looked at {resolved})")
    return str(resolved)


def _fields(cls: type) -> list[tuple[dataclasses.Field, Any, str]]:
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        if not f.init or f.metadata.get("internal"):
            continue
        out.append((f, hints[f.name], f.metadata.get("key") or f.name))
    return out


def _build_dataclass(cls: type, table: Any, path: str, ctx: _Context) -> Any:
    if not isinstance(table, dict):
        return ctx.add(path, f"expected a table, got {_type_name(table)}")
    fields = _fields(cls)
    known = {key for _, _, key in fields}
    if tag_of(cls):
        known.add("type")
    before = len(ctx.problems)
    for key in table:
        if key not in known:
            allowed = ", ".join(sorted(known))
            ctx.add(_join(path, str(key)), f"unknown key (allowed: {allowed})")
    kwargs = {}
    for f, tp, key in fields:
        sub = _join(path, key)
        if key not in table:
            if f.default is MISSING and f.default_factory is MISSING:
                ctx.add(sub, "missing required field")
            continue
        value = _convert(table[key], tp, sub, ctx, dict(f.metadata))
        if value is not _INVALID:
            kwargs[f.name] = value
    if len(ctx.problems) > before:
        return _INVALID
    obj = cls(**kwargs)
    check = getattr(obj, "validate", None)
    if check is not None:
        for sub, message in check():
            ctx.add(_join(path, sub), message)
        if len(ctx.problems) > before:
            return _INVALID
    return obj


def _build_tagged(members: tuple[type, ...], table: Any, path: str, ctx: _Context) -> Any:
    if not isinstance(table, dict):
        return ctx.add(path, f"expected a table, got {_type_name(table)}")
    tags = {tag_of(m): m for m in members}
    options = ", ".join(repr(t) for t in tags)
    if "type" not in table:
        return ctx.add(_join(path, "type"), f"missing required field (one of {options})")
    tag = table["type"]
    if not isinstance(tag, str) or tag not in tags:
        return ctx.add(_join(path, "type"), f"unknown type {tag!r} (one of {options})")
    return _build_dataclass(tags[tag], table, path, ctx)


def build(
    cls: type, table: Any, *, file: str, base_dir: Path, path: str = "",
    root: Path | None = None, allow_outside_paths: bool = False,
) -> Any:
    """Build dataclass ``cls`` from a TOML table, or raise :class:`SceneError`.

    Parameters
    ----------
    cls
        A dataclass declared with :func:`spec` fields.
    table
        The parsed TOML value (normally a dict).
    file
        Name shown in every problem (the scene file, or ``command line``).
    base_dir
        Directory against which file fields are resolved.
    path
        Field path prefix for nested builds (``settings`` for overrides).
    root
        Folder every file path must resolve inside (symlinks and ``..`` resolved);
        defaults to ``base_dir``.
    allow_outside_paths
        Accept file paths anywhere (absolute paths, ``..`` out of ``root``).
    """
    if allow_outside_paths:
        contained = None
    else:
        contained = Path(root if root is not None else base_dir).resolve()
    ctx = _Context(file=file, base_dir=base_dir, problems=[], root=contained)
    result = _build_dataclass(cls, table, path, ctx)
    if ctx.problems or result is _INVALID:
        raise SceneError(ctx.problems)
    return result


# ---------------------------------------------------------------------------
# Field reference (README documentation is generated from the same metadata).


def _describe_type(tp: Any) -> str:
    if dataclasses.is_dataclass(tp):
        return "table"
    if _is_tagged_union(tp):
        return "table (by `type`: " + ", ".join(
            f"`{tag_of(m)}`" for m in typing.get_args(tp)
        ) + ")"
    members = _union_members(tp)
    if members is not None:
        parts = [_describe_type(m) for m in members if m is not type(None)]
        return " or ".join(parts)
    origin = typing.get_origin(tp)
    if origin is Literal:
        return " \\| ".join(f'`"{c}"`' for c in typing.get_args(tp))
    if origin is tuple:
        args = typing.get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            return f"array of {_describe_type(args[0])}"
        return f"[{len(args)} × {_describe_type(args[0])}]"
    return {bool: "bool", int: "int", float: "float", str: "string"}[tp]


def _describe_default(f: dataclasses.Field) -> str:
    if f.default is MISSING and f.default_factory is MISSING:
        return "required"
    value = f.default if f.default is not MISSING else f.default_factory()
    if value is None:
        return "none"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, tuple) and value and not dataclasses.is_dataclass(value[0]):
        return "[" + ", ".join(_describe_default_scalar(v) for v in value) + "]"
    if isinstance(value, tuple):
        return "[]"
    if dataclasses.is_dataclass(value):
        return "see table"
    return _describe_default_scalar(value)


def _describe_default_scalar(value: Any) -> str:
    if isinstance(value, str):
        return f'"{value}"'
    return f"{value:g}" if isinstance(value, float) else str(value)


def _bounds_text(meta: dict) -> str:
    parts = []
    for name, symbol in (("ge", "≥"), ("gt", ">"), ("le", "≤"), ("lt", "<")):
        if meta.get(name) is not None:
            parts.append(f"{symbol} {meta[name]:g}")
    if meta.get("nonzero"):
        parts.append("non-zero")
    if meta.get("path"):
        parts.append("file path, relative to the scene file, inside its folder")
    return "; ".join(parts)


def describe_schema(cls: type, *, title: str, seen: set | None = None) -> list[str]:
    """Markdown tables, one per dataclass reachable from ``cls``, in visiting order."""
    seen = set() if seen is None else seen
    if cls in seen:
        return []
    seen.add(cls)
    lines = [f"#### {title}", ""]
    doc = (cls.__doc__ or "").strip().split("\n\n")[0].replace("\n", " ")
    if doc:
        lines += [doc, ""]
    lines += ["| field | type | unit | default | constraints | meaning |",
              "|---|---|---|---|---|---|"]
    nested: list[tuple[type, str]] = []
    for f, tp, key in _fields(cls):
        meta = f.metadata
        lines.append(
            f"| `{key}` | {_describe_type(tp)} | {meta.get('unit') or '–'} | "
            f"{_describe_default(f)} | {_bounds_text(meta) or '–'} | {meta.get('doc', '')} |"
        )
        for sub in _nested_classes(tp):
            nested.append((sub, _nested_title(sub)))
    lines.append("")
    for sub, sub_title in nested:
        lines += describe_schema(sub, title=sub_title, seen=seen)
    return lines


def _nested_title(cls: type) -> str:
    tag = tag_of(cls)
    section = getattr(cls, "section", cls.__name__)
    return f"{section} `type = \"{tag}\"`" if tag else section


def _nested_classes(tp: Any) -> list[type]:
    if dataclasses.is_dataclass(tp):
        return [tp]
    out: list[type] = []
    for arg in typing.get_args(tp):
        if arg is Ellipsis:
            continue
        out += _nested_classes(arg)
    return out

