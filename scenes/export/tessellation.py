"""Triangles of an exported scene: analytic shapes refined to a stated chord error.

The chord error of a tessellation is the largest distance between its triangles and
the analytic surface they stand for, in metres:

* sphere (icosphere of ``subdivisions`` levels, vertices on the sphere): each face's
  deepest point is its plane's foot from the centre (the faces are acute, so the foot
  lies inside them), at r - d_f from the sphere, d_f the plane's distance from the
  centre; error = r max_f (1 - d_f / r), measured on the unit icosphere (2.8e-4 r at 5
  levels, a quarter of that per level more);
* ring (a band of ``segments`` flat facets between generators on the cylinder):
  each facet's middle lies r (1 - cos(pi / segments)) inside the cylinder;
* plane receiver: exact (error 0).

Heightfield receivers, water surfaces and meshes are defined by their triangles (the
vertex grid of ``resolution`` over the height function, or the file's mesh): they are
exported as both renderers receive them, with no chord error of their own to state
(``chord_error`` None).

An analytic shape is refined from the scene's own level (never coarser: by default the
exported triangles are exactly those both renderers intersect) until its error is at
most the tolerance; a tolerance that the finest level the schema allows
(``subdivisions`` 7, ``segments`` 8192) cannot meet is an error naming the field.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np
import trimesh

from scenes.geometry import SceneGeometry, build_geometry
from scenes.model import (
    HeightfieldReceiver,
    MeshObject,
    MeshReceiver,
    PlaneReceiver,
    RingObject,
    Scene,
    SphereObject,
    WaterSurface,
)
from scenes.schema import Problem, SceneError

__all__ = ["DEFAULT_RELATIVE_TOLERANCE", "MAX_SEGMENTS", "MAX_SUBDIVISIONS", "Tessellation",
           "default_tolerance", "ring_chord_error", "sphere_chord_error", "tessellate"]

#: Default chord tolerance, as a fraction of the diagonal of the scene geometry's bounding
#: box (so the default scales with the scene: 1.2 mm for the 11.7 m glass_sphere).
DEFAULT_RELATIVE_TOLERANCE = 1e-4
#: The finest levels the scene schema allows.
MAX_SUBDIVISIONS = 7
MAX_SEGMENTS = 8192


@dataclass(frozen=True)
class Tessellation:
    """How one receiver's or object's triangles were made.

    Attributes
    ----------
    field : str
        Its path in the scene file (``objects[0]``, ``receivers[1]``).
    kind : str
        The scene's kind (``sphere``, ``ring``, ``plane``, ``heightfield``, ``mesh``,
        ``water_surface``).
    level : dict
        The refinement used (``{"subdivisions": 5}``, ``{"segments": 256}``; empty for
        the other kinds).
    chord_error : float or None
        Largest distance of the triangles from the analytic surface, m; None where the
        scene defines the surface by its triangles.
    """

    field: str
    kind: str
    level: dict
    chord_error: float | None


@functools.cache
def _unit_sphere_error(subdivisions: int) -> float:
    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    v = np.asarray(ico.vertices, np.float64)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    a, b, c = (v[ico.faces[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return float(1.0 - np.abs(np.einsum("ij,ij->i", n, a)).min())


def sphere_chord_error(radius: float, subdivisions: int) -> float:
    """Chord error (m) of an icosphere of ``subdivisions`` levels on a sphere of
    ``radius`` m."""
    return radius * _unit_sphere_error(subdivisions)


def ring_chord_error(radius: float, segments: int) -> float:
    """Chord error (m) of a band of ``segments`` facets on a cylinder of ``radius`` m."""
    return radius * (1.0 - math.cos(math.pi / segments))


def default_tolerance(scene: Scene) -> float:
    """:data:`DEFAULT_RELATIVE_TOLERANCE` times the diagonal of the bounding box of the
    scene's triangles as the renderers receive them, m."""
    geometry = build_geometry(scene)
    points = np.concatenate([g.mesh.positions for g in (*geometry.receivers,
                                                          *geometry.objects)])
    return DEFAULT_RELATIVE_TOLERANCE * float(np.linalg.norm(np.ptp(points.astype(np.float64),
                                                                    axis=0)))


def _refined(obj, field: str, tolerance: float, source: str):
    """(object at the level meeting ``tolerance``, its Tessellation)."""
    if isinstance(obj, SphereObject):
        for level in range(obj.subdivisions, MAX_SUBDIVISIONS + 1):
            error = sphere_chord_error(obj.radius, level)
            if error <= tolerance:
                return (dataclasses.replace(obj, subdivisions=level),
                        Tessellation(field, obj.kind, {"subdivisions": level}, error))
        finest = sphere_chord_error(obj.radius, MAX_SUBDIVISIONS)
        raise SceneError([Problem(source, f"{field}.subdivisions", (
            f"no icosphere meets the chord tolerance {tolerance:.3g} m: {MAX_SUBDIVISIONS} "
            f"levels leave {finest:.3g} m on radius {obj.radius:g} m (raise the tolerance)"))])
    if isinstance(obj, RingObject):
        # r (1 - cos(pi / n)) <= tol  <=>  n >= pi / acos(1 - tol / r).
        ratio = min(tolerance / obj.radius, 1.0)
        needed = math.ceil(math.pi / math.acos(1.0 - ratio)) if ratio < 1 else 1
        segments = max(obj.segments, needed)
        if segments > MAX_SEGMENTS:
            raise SceneError([Problem(source, f"{field}.segments", (
                f"no band meets the chord tolerance {tolerance:.3g} m: it needs {segments} "
                f"segments on radius {obj.radius:g} m, more than {MAX_SEGMENTS} "
                "(raise the tolerance)"))])
        return (dataclasses.replace(obj, segments=segments),
                Tessellation(field, obj.kind, {"segments": segments},
                             ring_chord_error(obj.radius, segments)))
    if isinstance(obj, PlaneReceiver):
        return obj, Tessellation(field, obj.kind, {}, 0.0)
    if isinstance(obj, HeightfieldReceiver | WaterSurface):
        return obj, Tessellation(field, obj.kind, {"resolution": list(obj.resolution)}, None)
    if isinstance(obj, MeshObject | MeshReceiver):
        return obj, Tessellation(field, obj.kind, {}, None)
    raise TypeError(f"unknown scene element {obj!r}")


def tessellate(scene: Scene, *, tolerance: float | None = None
               ) -> tuple[SceneGeometry, float, tuple[Tessellation, ...],
                          tuple[Tessellation, ...]]:
    """The scene's triangles with every analytic shape within ``tolerance``.

    Parameters
    ----------
    scene : Scene
    tolerance : float, optional
        Largest chord error allowed, m (> 0); default :func:`default_tolerance`.

    Returns
    -------
    geometry : SceneGeometry
        World-space triangles (scene coordinates), indexed like the scene's lists.
    tolerance : float
        The tolerance used, m.
    receivers, objects : tuple of Tessellation
        How each receiver's and object's triangles were made.

    Raises
    ------
    SceneError
        The tolerance is not a positive number, or a shape cannot meet it (naming the
        scene file and the field), or the geometry cannot be built.
    """
    if tolerance is None:
        tolerance = default_tolerance(scene)
    if not (isinstance(tolerance, int | float) and math.isfinite(tolerance) and tolerance > 0):
        raise SceneError([Problem(scene.source, "tolerance",
                                  f"must be a positive number of metres, got {tolerance!r}")])
    receivers = [_refined(r, f"receivers[{i}]", tolerance, scene.source)
                 for i, r in enumerate(scene.receivers)]
    objects = [_refined(o, f"objects[{i}]", tolerance, scene.source)
               for i, o in enumerate(scene.objects)]
    refined = dataclasses.replace(scene, objects=tuple(o for o, _ in objects))
    return (build_geometry(refined), float(tolerance), tuple(t for _, t in receivers),
            tuple(t for _, t in objects))
