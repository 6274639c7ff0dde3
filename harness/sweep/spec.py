"""The sweep file: scenes × methods × a grid of settings × reference seeds.

A sweep file is TOML with one table, ``[sweep]``::

    [sweep]
    name = "estimators"
    scenes = ["glass_sphere", "water_pool"]    # bundled names, or paths relative to this file
    presets = ["paper", "strong"]              # and/or methods = ["toy-double", ...]
    repeats = 5                                # timed renders per row (median after a warm-up)

    [sweep.settings]                           # fixed overrides for every row (optional)
    receiver_map = [128, 128]

    [sweep.grid]                               # every combination of these (optional)
    iterations = [1, 3, 5]
    grid = [64, 128]

    [sweep.reference]                          # the reference's budget (optional)
    photons = 4000000
    seeds = 4

It is validated the way a scene file is: every problem is collected and names the
file and the field path (``sweeps/x.toml: sweep.grid.iterations[2]: must be <= 64,
got 65``), never a traceback; a scene the sweep names is loaded and checked in full
(meshes too), and its own problems name the scene file. The fixed tables
(``[sweep]``, ``[sweep.reference]``) are declared once below with
:func:`scenes.schema.spec` and read by the scene schema's machinery; the open
tables (``[sweep.settings]``, ``[sweep.grid]``) are checked value by value against
the scene's ``[settings]`` declarations, so a grid value is legal exactly when the
same value in a scene file would be.

Settings that choose the method (``preset``) or size the reference (``photons``,
``seeds``, ``seed``, ``spp``, ``target_noise``, ``reference_time_cap``) are refused
in ``[sweep.settings]`` and ``[sweep.grid]``: the first belong in ``presets``, the
others in ``[sweep.reference]``, where every row of a scene shares one reference.
"""

from __future__ import annotations

import dataclasses
import itertools
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar, Literal

from renderers.methods import available_methods
from scenes import (
    SCENES_DIR,
    Problem,
    Scene,
    SceneError,
    Settings,
    load_scene,
    resolve_scene,
    with_settings,
)
from scenes.bundled import resolve_bundled
from scenes.geometry import build_geometry, scene_warnings
from scenes.schema import build, spec

__all__ = ["REFERENCE_KEYS", "SWEEPS_DIR", "ReferenceTable", "Setting", "Sweep",
           "SweepFileError", "SweepTable", "bundled_sweep_names", "load_sweep", "parse_sweep",
           "resolve_sweep"]

#: Settings that size the reference; set them in ``[sweep.reference]``.
REFERENCE_KEYS = ("photons", "seeds", "seed", "spp", "target_noise", "reference_time_cap")
#: Settings a sweep may not override: the method's preset (use ``presets``).
METHOD_KEYS = ("preset",)
#: Methods compared when the file names none: both caustics-mapping presets.
DEFAULT_METHODS = ("paper", "strong")
#: The bundled sweep files (package data beside the bundled scenes).
SWEEPS_DIR = SCENES_DIR / "sweeps"


class SweepFileError(SceneError):
    """A sweep file (or a scene it names) is invalid; ``problems`` lists every reason,
    each naming the file and the field path."""


@dataclass(frozen=True)
class ReferenceTable:
    """The reference every row of a scene is compared with (Mitsuba photon tracer,
    one Dask task per seed), and the independent reference on the next K seeds
    (the noise floor beside each metric, as in ``caustics compare``). Unset values
    keep the scene's own settings."""

    section: ClassVar[str] = "`[sweep.reference]`"

    photons: int | None = spec(None, doc="Photon budget per seed.", ge=1)
    seeds: int | None = spec(
        None, doc="Independent seeds K, one task each (the variance needs two or more).",
        ge=1, le=64)
    seed: int | None = spec(None, doc="First seed.", ge=0)
    spp: int | None = spec(None, doc="Reference camera samples per pixel per seed.", ge=1)
    target_noise: float | None = spec(
        None, doc="Stop at this relative noise (checked after each round of 2^20 photons "
        "per seed, as in a single-process reference).", gt=0)
    reference_time_cap: float | None = spec(
        None, doc="Time cap of the launches past the starting budget (all seeds, wall "
        "clock), as in a single-process reference.", unit="s", gt=0)

    def overrides(self) -> dict[str, Any]:
        """The settings this table sets (unset ones left out)."""
        return {k: getattr(self, k) for k in REFERENCE_KEYS if getattr(self, k) is not None}


@dataclass(frozen=True)
class SweepTable:
    """The ``[sweep]`` table: what to run. ``[sweep.settings]`` and ``[sweep.grid]``
    (tables of scene settings) are checked against the scene's ``[settings]``."""

    section: ClassVar[str] = "`[sweep]`"

    name: str = spec(doc="Sweep name (the index page's title).")
    scenes: tuple[str, ...] = spec(
        doc="Scene files (relative to the sweep file) or bundled scene names.")
    description: str = spec("", doc="What the sweep asks.")
    presets: tuple[Literal["paper", "strong"], ...] = spec(
        (), doc="Caustics-mapping presets to compare.")
    methods: tuple[str, ...] = spec(
        (), doc="Registered methods (entry-point group caustics_harness.methods) to "
        "compare; with `presets`, both lists. Neither: both presets.")
    repeats: int = spec(
        5, doc="Timed renders per row after a warm-up render; the median is "
        "`time_warm_ms`.", ge=1, le=100)
    # A field specifier with schema metadata, as in scenes/model.py.
    reference: ReferenceTable = spec(ReferenceTable(), doc="The reference's budget.")  # noqa: RUF009

    def validate(self) -> list[tuple[str, str]]:
        problems = []
        if not self.name.strip():
            problems.append(("name", "must not be empty"))
        if not self.scenes:
            problems.append(("scenes", "needs at least one scene"))
        for field in ("scenes", "presets", "methods"):
            values = getattr(self, field)
            for i, value in enumerate(values):
                if value in values[:i]:
                    problems.append((f"{field}[{i}]", f"{value!r} is listed twice"))
        return problems


@dataclass(frozen=True)
class Setting:
    """One combination of the grid: ``(name, value)`` pairs in the file's order."""

    items: tuple[tuple[str, Any], ...] = ()

    def as_dict(self) -> dict[str, Any]:
        """The overrides, as ``with_settings`` takes them."""
        return {name: list(v) if isinstance(v, tuple) else v for name, v in self.items}

    @property
    def shown(self) -> tuple[tuple[str, str], ...]:
        """``(name, value as text)`` pairs (``receiver_map`` 64x64, floats with %g)."""
        return tuple((k, _show(v)) for k, v in self.items)

    @property
    def label(self) -> str:
        """``iterations=3, grid=64`` (``defaults`` for the empty grid)."""
        return ", ".join(f"{k}={_show(v)}" for k, v in self.items) or "defaults"

    @property
    def slug(self) -> str:
        """``iterations3-grid64``: a folder-name part ("" for the empty grid)."""
        return "-".join(f"{k}{_show(v).replace(' ', '')}" for k, v in self.items)


def _show(value: Any) -> str:
    if isinstance(value, tuple):
        return "x".join(_show(v) for v in value)
    if isinstance(value, bool):
        return "true" if value else "false"
    return f"{value:g}" if isinstance(value, float) else str(value)


@dataclass(frozen=True)
class Sweep:
    """A validated sweep file.

    Attributes
    ----------
    name, description, file : str
        From ``[sweep]``; ``file`` is the sweep file's path.
    scenes : tuple of Scene
        Every scene, loaded and checked (geometry built once), in the file's order.
    methods : tuple of str
        Method names: ``presets`` then ``methods``, each once.
    settings : tuple of (str, value)
        Fixed overrides of every row (``[sweep.settings]``), converted like a scene's.
    grid : tuple of (str, tuple of values)
        Settings varied (``[sweep.grid]``), in the file's order.
    reference : ReferenceTable
    repeats : int
    """

    name: str
    description: str
    file: str
    scenes: tuple[Scene, ...]
    methods: tuple[str, ...]
    settings: tuple[tuple[str, Any], ...]
    grid: tuple[tuple[str, tuple[Any, ...]], ...]
    reference: ReferenceTable
    repeats: int
    warnings: tuple[Problem, ...] = ()

    @property
    def columns(self) -> tuple[str, ...]:
        """The settings the grid varies (one ``results.csv`` column each)."""
        return tuple(name for name, _ in self.grid)

    def combinations(self) -> tuple[Setting, ...]:
        """Every combination of the grid (one, empty, when there is no grid)."""
        names = self.columns
        values = [v for _, v in self.grid]
        return tuple(Setting(tuple(zip(names, combo, strict=True)))
                     for combo in itertools.product(*values))

    def scene_for(self, scene: Scene, setting: Setting) -> Scene:
        """``scene`` with the reference budget, the fixed settings and ``setting``
        applied (before the method configures it)."""
        overrides = {**self.reference.overrides(), **dict(self.settings), **setting.as_dict()}
        return with_settings(scene, {k: list(v) if isinstance(v, tuple) else v
                                     for k, v in overrides.items()}, origin=self.file)


def _settings_fields() -> dict[str, dataclasses.Field]:
    return {f.metadata.get("key") or f.name: f for f in dataclasses.fields(Settings)
            if not f.metadata.get("internal")}


def _unknown_setting() -> str:
    allowed = sorted(k for k in _settings_fields() if k not in (*METHOD_KEYS, *REFERENCE_KEYS))
    return f"unknown setting (allowed: {', '.join(allowed)})"


def _refused(key: str, table: str) -> str | None:
    if key in METHOD_KEYS:
        return "the preset is chosen by the method: list it in `presets` (or `methods`)"
    if key in REFERENCE_KEYS:
        return f"sizes the reference: set it in [sweep.reference], not in [sweep.{table}]"
    return None


def _check_value(key: str, value: Any, *, file: str, path: str,
                 problems: list[Problem]) -> Any:
    """``value`` of setting ``key`` converted as a scene file's would be, or None
    with its problems (renamed to ``path``) added."""
    try:
        built = build(Settings, {key: value}, file=file, base_dir=Path.cwd(),
                      path="settings")
    except SceneError as error:
        prefix = f"settings.{key}"
        for p in error.problems:
            rest = p.path[len(prefix):] if p.path.startswith(prefix) else ""
            problems.append(Problem(file, path + rest, p.message))
        return None
    return getattr(built, _settings_fields()[key].name)


def _setting_entries(table: Any, name: str, *, file: str,
                     problems: list[Problem]) -> Iterator[tuple[str, str, Any]]:
    """(key, path, value) of each entry of ``[sweep.<name>]`` whose key a sweep may
    set there; a table that is not one, an unknown key and a key refused in this
    table each add their problem instead."""
    if not isinstance(table, dict):
        problems.append(Problem(file, f"sweep.{name}", "expected a table"))
        return
    known = _settings_fields()
    for key, value in table.items():
        path = f"sweep.{name}.{key}"
        if key not in known:
            problems.append(Problem(file, path, _unknown_setting()))
        elif (why := _refused(key, name)) is not None:
            problems.append(Problem(file, path, why))
        else:
            yield key, path, value


def _settings_table(table: Any, *, file: str, problems: list[Problem]) -> tuple:
    """``[sweep.settings]``: fixed overrides, each checked as a scene's setting."""
    out = []
    for key, path, value in _setting_entries(table, "settings", file=file, problems=problems):
        converted = _check_value(key, value, file=file, path=path, problems=problems)
        if converted is not None:
            out.append((key, converted))
    return tuple(out)


def _grid_table(table: Any, *, file: str, problems: list[Problem]) -> tuple:
    """``[sweep.grid]``: each key a setting, each value a non-empty array of values
    that setting takes; every value checked and named by its index."""
    out = []
    for key, path, values in _setting_entries(table, "grid", file=file, problems=problems):
        if not isinstance(values, list) or not values:
            problems.append(Problem(file, path, "expected a non-empty array of values "
                                    f"(e.g. {key} = [a, b])"))
            continue
        converted = []
        for i, value in enumerate(values):
            item = _check_value(key, value, file=file, path=f"{path}[{i}]", problems=problems)
            if item is not None and item in converted:
                problems.append(Problem(file, f"{path}[{i}]", f"{_show(item)} is listed twice"))
            converted.append(item)
        out.append((key, tuple(converted)))
    return tuple(out)


def _scene_file(entry: str, sweep_dir: Path) -> Path:
    """A scene entry: a file relative to the sweep file, else a bundled name."""
    local = sweep_dir / entry
    return local if local.is_file() else resolve_scene(entry)


def _load_scenes(entries: tuple[str, ...], *, file: str, sweep_dir: Path,
                 problems: list[Problem]) -> tuple[list[Scene], list[Problem]]:
    scenes, warnings = [], []
    for i, entry in enumerate(entries):
        try:
            path = _scene_file(entry, sweep_dir)
        except SceneError as error:
            problems += [Problem(file, f"sweep.scenes[{i}]", p.message) for p in error.problems]
            continue
        try:
            scene = load_scene(path)
            build_geometry(scene)  # meshes read and checked now, not on a worker
        except SceneError as error:
            problems += error.problems
            continue
        warnings += scene_warnings(scene)
        scenes.append(scene)
    names = [s.name for s in scenes]
    for i, name in enumerate(names):
        if name in names[:i]:
            problems.append(Problem(file, "sweep.scenes", f"two scenes are named {name!r}: "
                                    "rows and pages are named by scene"))
    return scenes, warnings


def _methods(table: SweepTable, *, file: str, problems: list[Problem]) -> tuple[str, ...]:
    known = available_methods()
    for i, name in enumerate(table.methods):
        if name not in known:
            problems.append(Problem(file, f"sweep.methods[{i}]", f"unknown method {name!r} "
                                    f"(registered: {', '.join(known) or 'none'})"))
    names = [*table.presets, *table.methods] or list(DEFAULT_METHODS)
    return tuple(dict.fromkeys(names))


def parse_sweep(text: str, *, file: str = "<string>", base_dir: Path | None = None) -> Sweep:
    """Parse and validate sweep-file ``text`` (TOML; see the module docstring), as
    :func:`scenes.parse_scene` parses a scene's: ``file`` names the text in every
    problem and is recorded as ``Sweep.file``; scene paths are relative to
    ``base_dir`` (default: the current folder).

    Raises
    ------
    SweepFileError
        With every problem: the sweep file's (file and field path) and those of
        the scenes it names (scene file and field path).
    """
    base_dir = base_dir or Path.cwd()
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise SweepFileError([Problem(file, "", f"TOML syntax error: {error}")]) from None
    problems: list[Problem] = []
    for key in document:
        if key != "sweep":
            problems.append(Problem(file, key, "unknown key (allowed: sweep)"))
    raw = document.get("sweep")
    if not isinstance(raw, dict):
        problems.append(Problem(file, "sweep", "missing required table [sweep]"
                                if raw is None else "expected a table"))
        raise SweepFileError(problems)
    raw = dict(raw)
    settings = _settings_table(raw.pop("settings", {}), file=file, problems=problems)
    grid = _grid_table(raw.pop("grid", {}), file=file, problems=problems)
    try:
        table = build(SweepTable, raw, file=file, base_dir=base_dir, path="sweep")
    except SceneError as error:
        raise SweepFileError(problems + error.problems) from None
    methods = _methods(table, file=file, problems=problems)
    scenes, warnings = _load_scenes(table.scenes, file=file, sweep_dir=base_dir,
                                    problems=problems)
    if problems:
        raise SweepFileError(problems)
    return Sweep(name=table.name, description=table.description, file=file,
                 scenes=tuple(scenes), methods=methods, settings=settings, grid=grid,
                 reference=table.reference, repeats=table.repeats,
                 warnings=tuple(warnings))


def bundled_sweep_names() -> tuple[str, ...]:
    """Names of the bundled sweep files (``estimators``, ...)."""
    return tuple(sorted(p.stem for p in SWEEPS_DIR.glob("*.toml")))


def resolve_sweep(argument: str | Path) -> Path:
    """The sweep file an argument names: an existing path, else a bundled name.

    Raises
    ------
    SweepFileError
        Neither a file nor a bundled sweep; the message lists the bundled names.
    """
    return resolve_bundled(argument, (SWEEPS_DIR,), kind="sweep",
                           names=bundled_sweep_names(), error=SweepFileError)


def load_sweep(path: str | Path) -> Sweep:
    """Read and validate a sweep file (:func:`parse_sweep`), a path or a bundled name
    (:func:`resolve_sweep`); scene paths in it are relative to its folder.

    Raises
    ------
    SweepFileError
        No such file, it cannot be read, is not UTF-8 TOML, or holds any problem.
    """
    path = resolve_sweep(path)
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except OSError as error:
        raise SweepFileError([Problem(str(path), "",
                                      f"cannot read file: {error.strerror}")]) from None
    except UnicodeDecodeError as error:
        raise SweepFileError([Problem(str(path), "", f"not UTF-8 text: {error.reason}")]) \
            from None
    return parse_sweep(text, file=str(path), base_dir=path.resolve().parent)
