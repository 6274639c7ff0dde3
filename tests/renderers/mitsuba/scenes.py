"""Small analytic test scenes (TOML text), shared by the Mitsuba tests."""

from __future__ import annotations

from scenes import parse_scene

CAMERA = """
[camera]
position = [0.0, -6.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov = 40.0
resolution = [16, 16]
"""


def make_scene(*, light: str, objects: str, receiver_size: float = 4.0,
               direct: bool = True, settings: str = "", name: str = "test") -> object:
    """A plane receiver at z = 0 (albedo 0.5), the given light and objects tables."""
    text = f"""
[scene]
name = "{name}"
direct_lighting = {str(direct).lower()}
shadows = {str(direct).lower()}

[light]
{light}

[[receivers]]
type = "plane"
center = [0.0, 0.0, 0.0]
size = [{receiver_size}, {receiver_size}]
albedo = [0.5, 0.5, 0.5]

{objects}
{CAMERA}
[settings]
{settings}
"""
    return parse_scene(text, file=f"<{name}>")


#: A tiny sphere far outside every light path: the scene model needs one object.
FAR_SPHERE = """
[[objects]]
type = "sphere"
center = [50.0, 50.0, 50.0]
radius = 0.1
subdivisions = 1
material = { type = "dielectric", ior = 1.5 }
"""


def glass_sphere(*, absorption=(0.0, 0.0, 0.0), radius: float = 1.0, height: float = 2.0) -> str:
    a = ", ".join(str(float(x)) for x in absorption)
    return f"""
[[objects]]
type = "sphere"
center = [0.0, 0.0, {height}]
radius = {radius}
material = {{ type = "dielectric", ior = 1.5, absorption = [{a}] }}
"""
