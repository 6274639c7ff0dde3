"""Scenes the drei tests share: the bundled glass sphere under the sun, and variants
of it written as TOML so that a refusal names a real file and field."""

from __future__ import annotations

from pathlib import Path

from scenes import Scene, load_scene
from tests.conftest import SCENES

#: The bundled glass sphere under a directional light (0.3, 0.2, -1), E0 = 5 W/m².
SUN_SCENE = SCENES / "glass_sphere_sun.toml"
#: Where the light ray through the sphere's centre (0, 0, 2) meets the floor: the
#: centre of both the true caustic and drei's (the sphere is symmetric about that ray):
#: (0, 0, 2) + 2 (0.3, 0.2, -1).
AXIS_ON_FLOOR = (0.6, 0.4)


def sun_scene(tmp_path: Path, *, replace: tuple[tuple[str, str], ...] = (),
              append: str = "") -> Scene:
    """The bundled sun scene with text replaced and appended, written to
    ``tmp_path / "variant.toml"`` and loaded from there."""
    text = SUN_SCENE.read_text()
    for old, new in replace:
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / "variant.toml"
    path.write_text(text + append)
    return load_scene(path)
