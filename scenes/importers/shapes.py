"""What a triangle mesh can be in the scene model, decided from its triangles (scene
coordinates, +z up): a rectangle (a plane receiver), a height field over (x, y) (a mesh
receiver), a closed surface; and the checks every imported mesh passes first."""

from __future__ import annotations

import math

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from scenes.geometry.meshfile import watertight

__all__ = ["ABSURD_SIZE", "is_closed", "is_height_field", "mesh_problem", "rectangle"]

#: Meshes whose bounding-box diagonal lies outside this range (m) are refused: a file in
#: millimetres or kilometres read as metres, or a point-sized stray.
ABSURD_SIZE = (1e-5, 1e5)


def _face_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unnormalised normals, |n| = twice the triangle's area, by the right-hand rule."""
    a, b, c = (positions[faces[:, k]] for k in range(3))
    return np.cross(b - a, c - a)


def mesh_problem(positions: np.ndarray, faces: np.ndarray) -> str | None:
    """Why the mesh cannot be imported (no triangles, an index out of range, a
    non-finite coordinate, degenerate triangles, an absurd size), or None."""
    if len(faces) == 0 or len(positions) == 0:
        return "holds no triangles"
    if faces.min() < 0 or faces.max() >= len(positions):
        return f"a face index is out of range (the mesh has {len(positions)} vertices)"
    if not np.isfinite(positions).all():
        return "has non-finite vertex coordinates"
    diagonal = float(np.linalg.norm(np.ptp(positions, axis=0)))
    if not ABSURD_SIZE[0] <= diagonal <= ABSURD_SIZE[1]:
        return (f"is {diagonal:.3g} m across: outside {ABSURD_SIZE[0]:g} to "
                f"{ABSURD_SIZE[1]:g} m (a file in other units than metres?)")
    area = np.linalg.norm(_face_normals(positions, faces), axis=1) / 2
    degenerate = int((area <= 1e-12 * diagonal**2).sum())
    if degenerate == len(faces):
        return "is degenerate: every triangle has zero area"
    if degenerate:
        return f"is degenerate: {degenerate} of {len(faces)} triangles have zero area"
    return None


def is_closed(positions: np.ndarray, faces: np.ndarray) -> bool:
    """Whether the triangles close a volume (every edge shared by two faces)."""
    return watertight(positions, faces)


def is_height_field(positions: np.ndarray, faces: np.ndarray) -> bool:
    """Whether every triangle faces up (+z): the mesh is z = h(x, y) seen from above,
    a receiver whose (u, v) are its x, y projection."""
    return bool((_face_normals(positions, faces)[:, 2] > 0).all())


def rectangle(positions: np.ndarray, faces: np.ndarray) -> dict | None:
    """A plane receiver's table (centre, size, normal, u_axis) if the triangles are one
    rectangle (four distinct corners, right angles to 1e-6 for float32 files, all faces
    to one side), else None."""
    corners = np.unique(np.round(positions, 12), axis=0)
    if len(corners) != 4 or len(faces) != 2:
        return None
    normals = _face_normals(positions, faces)
    normal = normals.sum(axis=0)
    if np.linalg.norm(normal) == 0 or (normals @ normal <= 0).any():
        return None
    normal /= np.linalg.norm(normal)
    centre = corners.mean(axis=0)
    # The corner farthest from the first is its diagonal opposite; the two others are its
    # neighbours along the sides.
    far = np.argmax(np.linalg.norm(corners - corners[0], axis=1))
    e1, e2 = (corners[k] - corners[0] for k in range(1, 4) if k != far)
    scale = np.linalg.norm(e1) * np.linalg.norm(e2)
    planar = abs(np.dot(corners[far] - corners[0], normal)) <= 1e-6 * np.sqrt(scale)
    if abs(np.dot(e1, e2)) > 1e-6 * scale or not planar:
        return None
    # u runs along the side closest to +x (then +y): a file does not say which side is u,
    # and this rule gives back the harness's own default frame (u = +x, v = +y).
    sides = [side * sign for side in (e1, e2) for sign in (1.0, -1.0)]
    u = max(sides, key=lambda side: tuple(np.round(side / np.linalg.norm(side), 9)[:2]))
    v = e2 if u is sides[0] or u is sides[1] else e1
    return {"type": "plane", "center": centre.tolist(),
            "size": [float(np.linalg.norm(u)), float(np.linalg.norm(v))],
            "normal": normal.tolist(), "u_axis": (u / np.linalg.norm(u)).tolist()}


def _snapped(value: float, quantum: float) -> float:
    """``value`` on the grid of ``quantum`` (a power of ten), printed short: 2.0000001
    read from float32 becomes 2.0 when the grid is 1e-6."""
    return float(f"{round(value / quantum) * quantum:.12g}")


def icosphere(positions: np.ndarray, faces: np.ndarray) -> dict | None:
    """A sphere object's table (centre, radius, subdivisions) if the vertices are those
    of the harness's own icosphere (the one ``trimesh.creation.icosphere`` makes, so a
    sphere the harness or trimesh tessellated), to 1e-6 of the radius; else None.

    The sphere then renders with analytic normals and the same triangles as the file,
    and the centre and radius are snapped to a 1e-6 r grid when that keeps the match
    (a float32 file's 2.0000001 is the scene's 2.0).
    """
    count, triangles = len(positions), len(faces)
    level = round(math.log((count - 2) / 10, 4)) if count > 12 else 0
    if not 1 <= level <= 7 or count != 10 * 4**level + 2 or triangles != 20 * 4**level:
        return None
    centre = positions.mean(axis=0)
    distance = np.linalg.norm(positions - centre, axis=1)
    radius = float(distance.mean())
    if radius <= 0 or np.abs(distance - radius).max() > 1e-6 * radius:
        return None
    unit = np.asarray(trimesh.creation.icosphere(subdivisions=level, radius=1.0).vertices)
    unit /= np.linalg.norm(unit, axis=1, keepdims=True)
    tree = cKDTree(positions)

    def matches(c, r) -> bool:
        return bool(tree.query(unit * r + c)[0].max() <= 1e-6 * r)

    quantum = 10.0 ** math.floor(math.log10(1e-6 * radius))
    snapped = np.array([_snapped(v, quantum) for v in centre]), _snapped(radius, quantum)
    if matches(*snapped):
        centre, radius = snapped
    elif not matches(centre, radius):
        return None
    return {"type": "sphere", "center": [float(v) for v in centre], "radius": float(radius),
            "subdivisions": level}
