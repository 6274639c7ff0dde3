"""Scene description: TOML files parsed into frozen, validated dataclasses."""

from harness.scene.effects import EFFECTS, effects_of, event_chain
from harness.scene.loader import load_scene, parse_override, parse_scene, with_settings
from harness.scene.model import Scene, Settings
from harness.scene.schema import Problem, SceneError

__all__ = [
    "EFFECTS",
    "Problem",
    "Scene",
    "SceneError",
    "Settings",
    "effects_of",
    "event_chain",
    "load_scene",
    "parse_override",
    "parse_scene",
    "with_settings",
]
