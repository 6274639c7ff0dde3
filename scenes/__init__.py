"""Scene description: the bundled TOML files and the code that reads them into frozen,
validated dataclasses (schema, model, loader, effects; geometry in :mod:`scenes.geometry`).

The lowest layer: it imports no other package of the project.
"""

from scenes.bundled import (
    DEFAULT_SCENE,
    SCENES_DIR,
    bundled_scene_names,
    default_scene_path,
    resolve_scene,
)
from scenes.effects import EFFECTS, effects_of, event_chain
from scenes.loader import load_scene, parse_override, parse_scene, with_settings
from scenes.model import Scene, Settings
from scenes.schema import Problem, SceneError

__all__ = [
    "DEFAULT_SCENE",
    "EFFECTS",
    "SCENES_DIR",
    "Problem",
    "Scene",
    "SceneError",
    "Settings",
    "bundled_scene_names",
    "default_scene_path",
    "effects_of",
    "event_chain",
    "load_scene",
    "parse_override",
    "parse_scene",
    "resolve_scene",
    "with_settings",
]
