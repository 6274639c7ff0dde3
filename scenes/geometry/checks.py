"""Checks that need the built meshes: usable meshes, and where the light and the
camera sit relative to the closed objects.

Errors (a :class:`GeometryError` while building, or :class:`~scenes.schema.Problem`
lists) are scenes the renderers cannot render faithfully; warnings are legal scenes
that are probably not what the author meant.

* a mesh with no area, or (closed) no volume -> error;
* a dielectric mesh that is open (not watertight) -> error: both renderers need a
  closed boundary to enter and leave a refractive object (``L T T D``);
* a mesh placed beyond :data:`~scenes.precision.LENGTH_LIMIT` -> error;
* the light (point, spot position; area light centre or a corner) inside a closed
  object -> error: both renderers model light reaching a closed object from
  outside (the ``L T T D`` chain enters it first; the shadow map is seen from the
  light); from inside, a dielectric's light takes ``L T D`` paths neither counts,
  and a conductor's is trapped;
* the camera inside a closed object -> warning: legal, and the receiver irradiance
  maps (what is compared) do not depend on the camera, but the camera images look
  out through the object's surface from within, which the caustics-mapping camera
  pass does not model (it shades object surfaces as seen from outside);
* no specular object, or a specular object the light cannot reach (wholly outside a
  spot light's cone or behind an area light) -> warning: no caustic forms there.
"""

from __future__ import annotations

import math

import numpy as np

from scenes.geometry.mesh import TriangleMesh
from scenes.precision import LENGTH_LIMIT
from scenes.schema import Problem

__all__ = ["GeometryError", "camera_warnings", "light_problems", "light_warnings",
           "placement_problem", "usable_mesh_problem", "winding_number"]


class GeometryError(ValueError):
    """A built mesh cannot be rendered; ``field`` is the field path below the
    object or receiver (``file``, ``transform``) that the problem belongs to."""

    def __init__(self, field: str, message: str):
        super().__init__(message)
        self.field = field


def usable_mesh_problem(mesh: TriangleMesh, *, closed_required: bool) -> str | None:
    """Why a loaded mesh cannot be rendered, or None.

    Zero-area faces are allowed among others (a file may hold a few); a mesh of
    nothing else is not. "Zero" is relative to the mesh's size, as float32 positions
    carry about seven digits.
    """
    p = mesh.positions.astype(np.float64)
    if closed_required and len(p) < 4:
        return f"has {len(p)} vertices; a closed object needs at least 4"
    extent = float(np.max(p.max(axis=0) - p.min(axis=0)))
    a, b, c = p[mesh.faces[:, 0]], p[mesh.faces[:, 1]], p[mesh.faces[:, 2]]
    cross = np.cross(b - a, c - a)
    if extent == 0 or not np.any(np.linalg.norm(cross, axis=1) > 1e-12 * extent**2):
        return "is degenerate: every face has zero area"
    if closed_required and not mesh.closed:
        return "mesh is open (not watertight); a refractive object must be closed"
    if mesh.closed:
        volume = abs(float(np.einsum("ij,ij->", a, np.cross(b, c)))) / 6
        if volume <= 1e-9 * extent**3:
            return "is degenerate: the closed mesh encloses no volume"
    return None


def placement_problem(mesh: TriangleMesh) -> str | None:
    """Why a placed (world-space) mesh is out of single-precision range, or None."""
    if not np.all(np.isfinite(mesh.positions)):
        return "places vertices beyond float32's range (3.4e38 m)"
    reach = float(np.abs(mesh.positions).max())
    if reach > LENGTH_LIMIT:
        return (f"places vertices {reach:.3g} m out, beyond {LENGTH_LIMIT:g} m, where "
                "squared distances overflow float32 in the renderers")
    return None


def winding_number(mesh: TriangleMesh, point) -> float:
    """Generalised winding number of ``mesh`` about ``point``: the solid angles of its
    triangles seen from the point, summed, over 4π (Van Oosterom & Strackee 1983).
    About ±1 inside a closed mesh, 0 outside; needs no connectivity, so it works on
    flat-shaded meshes whose corners are repeated per face."""
    p = mesh.positions.astype(np.float64) - np.asarray(point, np.float64)
    a, b, c = p[mesh.faces[:, 0]], p[mesh.faces[:, 1]], p[mesh.faces[:, 2]]
    la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    div = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc
           + np.einsum("ij,ij->i", b, c) * la + np.einsum("ij,ij->i", c, a) * lb)
    return float(np.sum(2 * np.arctan2(det, div)) / (4 * math.pi))


def _inside(obj, mesh: TriangleMesh, point) -> bool:
    if not mesh.closed:
        return False
    if obj.kind == "sphere":  # the analytic sphere, not its tessellation
        return math.dist(point, obj.center) < obj.radius
    return abs(winding_number(mesh, point)) > 0.5


def _describe(i: int, obj) -> str:
    return f"objects[{i}] (a closed {obj.kind})"


def _light_points(light) -> list[tuple[str, np.ndarray]]:
    """(field, point) where the light emits: its position, or an area light's
    centre and corners (in the frame both renderers use)."""
    if light.kind in ("point", "spot"):
        return [("position", np.asarray(light.position, float))]
    if light.kind != "area":
        return []
    n = np.asarray(light.normal, float) / np.linalg.norm(light.normal)
    helper = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = np.cross(n, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    centre = np.asarray(light.center, float)
    half = np.asarray(light.size, float) / 2
    corners = [centre + s * half[0] * e1 + t * half[1] * e2
               for s in (-1, 1) for t in (-1, 1)]
    return [("center", centre)] + [("size", c) for c in corners]


def light_problems(scene, geometry) -> list[Problem]:
    """Errors: the light emits from inside a closed object."""
    for field, point in _light_points(scene.light):
        for i, (obj, geo) in enumerate(zip(scene.objects, geometry.objects, strict=True)):
            if _inside(obj, geo.mesh, point):
                where = "is" if field != "size" else "reaches"
                return [Problem(scene.source, f"light.{field}", (
                    f"the light {where} inside {_describe(i, obj)}; both renderers model "
                    "light reaching closed objects from outside (the L T T D chain, the "
                    "shadow map)"))]
    return []


def camera_warnings(scene, geometry) -> list[Problem]:
    """Warnings: the camera sits inside a closed object."""
    eye = np.asarray(scene.camera.position, float)
    return [
        Problem(scene.source, "camera.position", (
            f"the camera is inside {_describe(i, obj)}; the receiver maps are unaffected, "
            "but the camera images look out through its surface from within, which the "
            "caustics-mapping camera pass does not model"))
        for i, (obj, geo) in enumerate(zip(scene.objects, geometry.objects, strict=True))
        if _inside(obj, geo.mesh, eye)
    ]


def _bounding_sphere(mesh: TriangleMesh) -> tuple[np.ndarray, float]:
    p = mesh.positions.astype(np.float64)
    centre = (p.min(axis=0) + p.max(axis=0)) / 2
    return centre, float(np.linalg.norm(p - centre, axis=1).max())


def _unlit(light, mesh: TriangleMesh) -> str | None:
    """Why the light cannot reach any point of ``mesh`` (by its bounding sphere)."""
    centre, radius = _bounding_sphere(mesh)
    if light.kind == "spot":
        v = centre - np.asarray(light.position, float)
        d = float(np.linalg.norm(v))
        if d <= radius:
            return None
        axis = np.asarray(light.direction, float) / np.linalg.norm(light.direction)
        angle = math.degrees(math.acos(float(np.clip(v @ axis / d, -1, 1))))
        if angle - math.degrees(math.asin(radius / d)) > light.cutoff_angle:
            return (f"lies wholly outside the spot light's cone (cutoff "
                    f"{light.cutoff_angle:g} deg)")
    if light.kind == "area":
        n = np.asarray(light.normal, float) / np.linalg.norm(light.normal)
        if float((centre - np.asarray(light.center, float)) @ n) < -radius:
            return "lies wholly behind the area light's emitting side"
    return None


def light_warnings(scene, geometry) -> list[Problem]:
    """Warnings: no caustic-forming light path (no specular object, or none lit)."""
    specular = [i for i, obj in enumerate(scene.objects)
                if obj.material.kind in ("dielectric", "conductor")]
    if not specular:
        return [Problem(scene.source, "objects", (
            "no object is specular (dielectric or conductor), so the scene forms no "
            "caustic"))]
    warnings = []
    for i in specular:
        reason = _unlit(scene.light, geometry.objects[i].mesh)
        if reason:
            warnings.append(Problem(scene.source, f"objects[{i}]",
                                    f"{reason}: the light cannot reach it, so it forms "
                                    "no caustic"))
    return warnings
