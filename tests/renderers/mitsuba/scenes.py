"""Small analytic test scenes (TOML text) and the ray optics of their ideal sphere,
shared by the Mitsuba tests and the caustic probe's."""

from __future__ import annotations

import numpy as np

from scenes import parse_scene
from scenes.geometry import build_geometry

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


def ideal_sphere_paths(radius, height, ior, half, n=1500):
    """Rays straight down through an ideal sphere (ray optics, NumPy): returns the
    equal-area impact samples' (lands on the |x|,|y| <= half receiver) mask and
    chord length inside. Midpoint rule in b^2 and in azimuth: n x n/2 samples."""
    b = radius * np.sqrt((np.arange(n) + 0.5) / n)
    phi = 2 * np.pi * (np.arange(n // 2) + 0.5) / (n // 2)
    bb, pp = np.meshgrid(b, phi)
    x0, y0 = bb * np.cos(pp), bb * np.sin(pp)
    sin_i = bb / radius
    sin_t = sin_i / ior
    theta = 2 * (np.arcsin(sin_i) - np.arcsin(sin_t))  # deviation after two refractions
    chord = 2 * radius * np.sqrt(1 - sin_t**2)
    # Exit point: rotate the entry point by (pi - 2 theta_t) in the meridian plane.
    ti, tt = np.arcsin(sin_i), np.arcsin(sin_t)
    alpha = ti + (np.pi - 2 * tt)  # polar angle of exit point from +z
    r_exit, z_exit = radius * np.sin(alpha), height + radius * np.cos(alpha)
    # Direction leaves tilted by theta toward the axis: (-sin, -cos) in (radial, z).
    dr_, dz = -np.sin(theta), -np.cos(theta)
    down = dz < 0
    t = np.where(down, -z_exit / np.where(down, dz, -1), 0)
    rad = r_exit + t * dr_
    xl, yl = rad * np.cos(pp), rad * np.sin(pp)
    lands = down & (np.abs(xl) <= half) & (np.abs(yl) <= half)
    del x0, y0
    return lands, chord


def inradius_deficit(scene):
    """Bound on the flux an icosphere of radius 1 m centred at z = 2 m misses against
    the ideal sphere: 1 - (r_in / R)^2, r_in its faces' least distance from the
    centre (the faces lie inside the ideal sphere)."""
    mesh = build_geometry(scene).objects[0].mesh
    p = mesh.positions.astype(float) - np.array([0.0, 0.0, 2.0])
    a, b, c = (p[mesh.faces[:, i]] for i in range(3))
    n = np.cross(b - a, c - a)
    dist = np.abs(np.einsum("ij,ij->i", n / np.linalg.norm(n, axis=1, keepdims=True), a))
    return 1 - (dist.min() / 1.0) ** 2
