"""LuxCore tests: scenes written inline, and a fixture that skips without pyluxcore."""

from __future__ import annotations

import pytest

from scenes import parse_scene

PLANE = """
[[receivers]]
type = "plane"
center = [0.0, 0.0, 0.0]
size = [4.0, 4.0]
albedo = [0.5, 0.5, 0.5]
"""

GLASS_SPHERE = """
[[objects]]
type = "sphere"
center = [0.0, 0.0, 1.5]
radius = 0.5
subdivisions = 4
material = { type = "dielectric", ior = 1.5, fresnel = true }
"""

CAMERA = """
[camera]
position = [0.0, -6.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov = 40.0
resolution = [32, 32]
"""


def make_scene(*, light: str, objects: str = GLASS_SPHERE,
               settings: str = "all_specular_paths = true"):
    """A scene over a 4 m x 4 m plane; ``light`` is the body of ``[light]``."""
    text = (f'[scene]\nname = "luxcore_test"\n\n[light]\n{light}\n{PLANE}{objects}{CAMERA}'
            f"\n[settings]\n{settings}\n")
    return parse_scene(text, file="luxcore_test.toml")


@pytest.fixture(scope="session")
def luxcore():
    """pyluxcore's version, from the render worker; the test is skipped when the
    worker cannot import pyluxcore (it is never imported into the test process)."""
    from renderers.luxcore import LuxCoreUnavailable, luxcore_version  # noqa: PLC0415

    try:
        return luxcore_version()
    except LuxCoreUnavailable as error:
        pytest.skip(f"pyluxcore not importable: {error}")
