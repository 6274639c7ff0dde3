"""The scene files that ship inside this package: paper scenes, ``hard/`` cases and
``meshes/``, found by name from any working directory.

A scene argument on the command line is a path when such a file exists, else the
name of a bundled scene (``glass_sphere``, ``hard/grazing_light`` or just
``grazing_light``). The default scene is the bundled ``glass_sphere``.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from scenes.schema import Problem, SceneError

__all__ = ["DEFAULT_SCENE", "SCENES_DIR", "bundled_scene_names", "default_scene_path",
           "resolve_bundled", "resolve_scene"]

#: Folder of the bundled scene files (the ``scenes`` package itself).
SCENES_DIR = Path(str(resources.files("scenes")))
#: Name of the default scene (paper Figs. 6, 7).
DEFAULT_SCENE = "glass_sphere"


def bundled_scene_names() -> tuple[str, ...]:
    """Names of every bundled scene: ``glass_sphere``, ..., ``hard/tiny_scale``."""
    top = sorted(p.stem for p in SCENES_DIR.glob("*.toml"))
    hard = sorted(f"hard/{p.stem}" for p in (SCENES_DIR / "hard").glob("*.toml"))
    return (*top, *hard)


def default_scene_path() -> Path:
    """The bundled default scene file, ``glass_sphere.toml``."""
    return SCENES_DIR / f"{DEFAULT_SCENE}.toml"


def resolve_bundled(argument: str | Path, folders: tuple[Path, ...], *, kind: str,
                    names: tuple[str, ...], error: type[SceneError] = SceneError) -> Path:
    """The file an argument names: an existing path, else the bundled ``<name>.toml``
    (``name`` the argument less any ``.toml``) found first under ``folders``, as a
    file of one of them (``hard/grazing_light`` is the file of ``SCENES_DIR / "hard"``;
    a name that leads into any other folder finds nothing).

    Raises
    ------
    SceneError
        (``error``, a subclass) Neither a file nor a bundled ``kind``; the message
        lists ``names``, the bundled names.
    """
    path = Path(argument)
    if path.is_file():
        return path
    name = str(argument).removesuffix(".toml")
    for folder in folders:
        candidate = folder / f"{name}.toml"
        if candidate.parent in folders and candidate.is_file():
            return candidate
    raise error([Problem(str(argument), "", f"no such file, and no bundled {kind} of that "
                         f"name (bundled: {', '.join(names) or 'none'})")])


def resolve_scene(argument: str | Path) -> Path:
    """The scene file an argument names: an existing path, else a bundled name
    (``glass_sphere``, ``hard/grazing_light`` or ``grazing_light``).

    Raises
    ------
    SceneError
        Neither a file nor a bundled scene; the message lists the bundled names.
    """
    return resolve_bundled(argument, (SCENES_DIR, SCENES_DIR / "hard"), kind="scene",
                           names=bundled_scene_names())
