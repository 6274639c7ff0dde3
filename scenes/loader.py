"""Read scene files and apply setting overrides; every failure is a SceneError."""

from __future__ import annotations

import dataclasses
import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from scenes.bundled import SCENES_DIR
from scenes.model import Scene, Settings
from scenes.schema import OUTSIDE_PATHS_VARIABLE, Problem, SceneError, build

__all__ = ["containment_root", "load_scene", "outside_paths_allowed", "parse_override",
           "parse_scene", "with_settings"]


def outside_paths_allowed(allow: bool | None = None) -> bool:
    """``allow`` if given, else whether ``CAUSTICS_ALLOW_OUTSIDE_PATHS`` is 1 (or
    true/yes): the explicit opt-in for file paths outside the containment folder."""
    if allow is not None:
        return allow
    return os.environ.get(OUTSIDE_PATHS_VARIABLE, "").strip().lower() in {"1", "true", "yes"}


def containment_root(scene_file: Path) -> Path:
    """Folder the files a scene file names must lie in: the scene file's own folder,
    or for the bundled scenes the whole ``scenes`` package (``hard/`` scenes share
    ``meshes/`` with the paper scenes as ``../meshes/...``)."""
    folder = scene_file.resolve().parent
    bundled = SCENES_DIR.resolve()
    return bundled if folder.is_relative_to(bundled) else folder


def parse_scene(
    text: str, *, file: str = "<string>", base_dir: Path | None = None,
    root: Path | None = None, allow_outside_paths: bool | None = None,
) -> Scene:
    """Parse TOML text into a validated :class:`Scene`.

    Parameters
    ----------
    text
        TOML source.
    file
        Name used in error messages and recorded as ``Scene.source``.
    base_dir
        Directory that relative file paths (meshes, height arrays) are resolved against;
        defaults to the current directory.
    root
        Folder every file path must resolve inside (after ``..`` and symlinks);
        defaults to ``base_dir``.
    allow_outside_paths
        Accept paths outside ``root``; None reads ``CAUSTICS_ALLOW_OUTSIDE_PATHS``.

    Raises
    ------
    SceneError
        With one problem per invalid field, each naming ``file`` and the field path.
    """
    try:
        table = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise SceneError([Problem(file, "", f"TOML syntax error: {error}")]) from None
    base_dir = base_dir or Path.cwd()
    scene = build(Scene, table, file=file, base_dir=base_dir, root=root or base_dir,
                  allow_outside_paths=outside_paths_allowed(allow_outside_paths))
    return dataclasses.replace(scene, source=file)


def load_scene(path: str | Path, *, allow_outside_paths: bool | None = None) -> Scene:
    """Read and validate a scene file (see :func:`parse_scene`); the files it names
    must lie in :func:`containment_root` unless outside paths are allowed."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as error:
        raise SceneError([Problem(str(path), "", f"cannot read file: {error.strerror}")]) from None
    try:
        # TOML is UTF-8; a byte-order mark (Windows editors write one) is dropped.
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise SceneError([Problem(str(path), "", f"not UTF-8 text: {error.reason}")]) from None
    return parse_scene(text, file=str(path), base_dir=path.resolve().parent,
                       root=containment_root(path), allow_outside_paths=allow_outside_paths)


def parse_override(item: str) -> tuple[str, Any]:
    """Split ``name=value``; the value is read as a TOML value, else as a bare string.

    >>> parse_override("grid=64")
    ('grid', 64)
    >>> parse_override("estimator=newton")
    ('estimator', 'newton')
    """
    name, sep, value = item.partition("=")
    if not sep or not name.strip():
        raise SceneError([Problem("command line", item, "expected NAME=VALUE")])
    try:
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        parsed = value.strip()
    return name.strip(), parsed


def with_settings(
    scene: Scene, overrides: Mapping[str, Any], *, origin: str = "command line"
) -> Scene:
    """Return ``scene`` with some settings replaced, validated like the scene file.

    Parameters
    ----------
    overrides
        Setting name to TOML-like value (``{"grid": 64, "estimator": "newton"}``);
        ``None`` values are ignored so CLI options can be passed through unset.
    origin
        Name shown in error messages.
    """
    changes = {k: v for k, v in overrides.items() if v is not None}
    if not changes:
        return scene
    current = {
        f.name: _to_toml(getattr(scene.settings, f.name))
        for f in dataclasses.fields(Settings)
        if getattr(scene.settings, f.name) is not None
    }
    current.update(changes)
    settings = build(Settings, current, file=origin, base_dir=Path.cwd(), path="settings")
    return dataclasses.replace(scene, settings=settings)


def _to_toml(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value
