"""Load scenes as every command and the Python API do: by file path or bundled name,
fully validated (meshes and height files read, the geometry built and checked).

Imports nothing heavy, so that ``validate --no-trace``, ``describe`` and ``schema`` run
where Mitsuba, Dr.Jit and moderngl cannot be imported.
"""

from __future__ import annotations

from collections.abc import Callable

from scenes import Problem, SceneError, default_scene_path, load_scene, resolve_scene
from scenes.geometry import build_geometry, scene_warnings
from scenes.model import Scene

__all__ = ["check_scenes", "load_scenes"]


def check_scenes(paths: list[str]) -> tuple[list[Scene], list[Problem], list[Problem]]:
    """Load and fully validate scenes: ``(scenes, errors, warnings)``.

    Each entry is a file path or a bundled scene name (:func:`scenes.resolve_scene`);
    with none, the bundled default scene. Everything ``compare`` would refuse is an
    error here (meshes and height files are read, the geometry checked); a scene
    with an error is left out of ``scenes``.
    """
    scenes, problems, warnings = [], [], []
    for path in paths or [str(default_scene_path())]:
        try:
            scene = load_scene(resolve_scene(path))
            build_geometry(scene)
            warnings += scene_warnings(scene)
            scenes.append(scene)
        except SceneError as error:
            problems += error.problems
    return scenes, problems, warnings


def load_scenes(paths: list[str], *,
                on_warning: Callable[[Problem], None] | None = None) -> list[Scene]:
    """Load and fully validate scenes (:func:`check_scenes`), handing each warning (a
    legal but suspect scene) to ``on_warning``.

    Raises
    ------
    SceneError
        One error holding the problems of every file.
    """
    scenes, problems, warnings = check_scenes(paths)
    for warning in warnings:
        if on_warning is not None:
            on_warning(warning)
    if problems:
        raise SceneError(problems)
    return scenes
