"""Build every mesh of a scene once, in world space, for both renderers."""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np
import trimesh

from scenes.geometry.checks import (
    GeometryError,
    camera_warnings,
    light_problems,
    light_warnings,
    placement_problem,
    usable_mesh_problem,
)
from scenes.geometry.mesh import TriangleMesh, apply_transform, make_mesh, transform_matrix
from scenes.geometry.meshfile import builtin_mesh_path, load_mesh_file
from scenes.geometry.surfaces import evaluate_height, grid_mesh_arrays, water_height
from scenes.model import (
    CausticObject,
    DielectricMaterial,
    HeightfieldReceiver,
    Material,
    MeshObject,
    MeshReceiver,
    PlaneReceiver,
    Receiver,
    RingObject,
    Scene,
    Settings,
    SphereObject,
    WaterSurface,
)
from scenes.schema import Problem, SceneError

__all__ = ["ObjectGeometry", "ReceiverGeometry", "SceneGeometry", "build_geometry",
           "scene_warnings"]


@dataclass(frozen=True, eq=False)
class ReceiverGeometry:
    """A receiver's mesh and its (u, v) parameter domain.

    Attributes
    ----------
    mesh : TriangleMesh
        World-space triangles; ``mesh.uvs`` holds each vertex's (u, v).
    extent : tuple of float
        ``(umin, umax, vmin, vmax)`` of the irradiance map's domain, in (u, v) units
        (metres for planes and heightfields).
    albedo : tuple of float
        Diffuse reflectance, RGB.
    """

    mesh: TriangleMesh
    extent: tuple[float, float, float, float]
    albedo: tuple[float, float, float]


@dataclass(frozen=True, eq=False)
class ObjectGeometry:
    """A caustic object's mesh and material."""

    mesh: TriangleMesh
    material: Material


@dataclass(frozen=True, eq=False)
class SceneGeometry:
    """All meshes of a scene, indexed like ``scene.receivers`` and ``scene.objects``."""

    receivers: tuple[ReceiverGeometry, ...]
    objects: tuple[ObjectGeometry, ...]


def _frame(normal, u_axis) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Orthonormal (u, v, n) with u the projection of ``u_axis`` onto the plane."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    u = np.asarray(u_axis, float)
    u = u - n * (u @ n)
    u /= np.linalg.norm(u)
    return u, np.cross(n, u), n


def _extent(*values) -> tuple[float, float, float, float]:
    return tuple(float(v) for v in values)


def _receiver(rec: Receiver) -> ReceiverGeometry:
    if isinstance(rec, PlaneReceiver):
        u, v, n = _frame(rec.normal, rec.u_axis)
        half = np.array(rec.size) / 2
        uv = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * half
        pos = np.asarray(rec.center) + uv[:, :1] * u + uv[:, 1:] * v
        faces = [[0, 1, 2], [0, 2, 3]]
        mesh = make_mesh(pos, np.tile(n, (4, 1)), faces, uv)
        return ReceiverGeometry(mesh, _extent(-half[0], half[0], -half[1], half[1]), rec.albedo)
    if isinstance(rec, HeightfieldReceiver):
        def height(x, y):
            return evaluate_height(rec.height, x, y, rec.size)

        pos, nrm, faces, uv = grid_mesh_arrays(rec.size, rec.resolution, height)
        mesh = make_mesh(pos + np.asarray(rec.center), nrm, faces, uv)
        half = np.array(rec.size) / 2
        return ReceiverGeometry(mesh, _extent(-half[0], half[0], -half[1], half[1]), rec.albedo)
    if isinstance(rec, MeshReceiver):
        mesh = _checked(load_mesh_file(rec.file), closed_required=False)
        mesh = _placed(apply_transform(mesh, transform_matrix(rec.transform)))
        uvs = mesh.uvs if mesh.uvs is not None else mesh.positions[:, :2].astype(np.float64)
        mesh = make_mesh(mesh.positions, mesh.normals, mesh.faces, uvs)
        lo, hi = uvs.min(axis=0), uvs.max(axis=0)
        return ReceiverGeometry(mesh, _extent(lo[0], hi[0], lo[1], hi[1]), rec.albedo)
    raise TypeError(f"unknown receiver {rec!r}")


def _object(obj: CausticObject) -> TriangleMesh:
    if isinstance(obj, SphereObject):

        ico = trimesh.creation.icosphere(subdivisions=obj.subdivisions, radius=1.0)
        unit = np.asarray(ico.vertices, float)
        unit /= np.linalg.norm(unit, axis=1, keepdims=True)
        # Analytic normals: the sphere's, not the facets'.
        return make_mesh(unit * obj.radius + obj.center, unit, ico.faces, closed=True)
    if isinstance(obj, MeshObject):
        if obj.file.startswith("builtin:"):
            path = builtin_mesh_path(obj.file.removeprefix("builtin:"))
        else:
            path = obj.file
        # `closed` is the file's watertightness: an open conductor stays open (drawn
        # two-sided, never culled); an open dielectric is refused here.
        dielectric = isinstance(obj.material, DielectricMaterial)
        mesh = _checked(load_mesh_file(path), closed_required=dielectric)
        if obj.fit_size is not None:
            lo, hi = mesh.bounds
            fit = np.eye(4)
            fit[:3, :3] *= obj.fit_size / float(np.max(hi - lo))
            fit[:3, 3] = -fit[:3, :3] @ ((lo + hi) / 2)
            mesh = apply_transform(mesh, fit)
        return _placed(apply_transform(mesh, transform_matrix(obj.transform)))
    if isinstance(obj, WaterSurface):
        def height(x, y):
            return water_height(obj, x, y)

        pos, nrm, faces, _ = grid_mesh_arrays(obj.size, obj.resolution, height)
        return make_mesh(pos + np.asarray(obj.center), nrm, faces)
    if isinstance(obj, RingObject):
        return _ring(obj)
    raise TypeError(f"unknown object {obj!r}")


def _checked(mesh: TriangleMesh, *, closed_required: bool) -> TriangleMesh:
    problem = usable_mesh_problem(mesh, closed_required=closed_required)
    if problem:
        raise GeometryError("file", problem)
    return mesh


def _placed(mesh: TriangleMesh) -> TriangleMesh:
    problem = placement_problem(mesh)
    if problem:
        raise GeometryError("transform", problem)
    return mesh


def _ring(ring: RingObject) -> TriangleMesh:
    """Open band; normals point inward (toward the axis), where light reflects to
    form the ring's cardioid caustic. Renderers treat it as two-sided."""
    axis = np.asarray(ring.axis, float) / np.linalg.norm(ring.axis)
    helper = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    phi = np.linspace(0, 2 * np.pi, ring.segments, endpoint=False)
    radial = np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2
    base = np.asarray(ring.center) + ring.radius * radial
    pos = np.concatenate([base, base + ring.height * axis])
    nrm = np.concatenate([-radial, -radial])
    k = np.arange(ring.segments)
    k1 = (k + 1) % ring.segments
    top = k + ring.segments
    top1 = k1 + ring.segments
    # Wound counter-clockwise seen from inside (from the axis).
    faces = np.concatenate([np.stack([k, top, k1], 1), np.stack([k1, top, top1], 1)])
    return make_mesh(pos, nrm, faces)


def build_geometry(scene: Scene) -> SceneGeometry:
    """All meshes of ``scene``, built once and shared by both renderers.

    Raises
    ------
    SceneError
        A mesh or height file cannot be read or is unusable (degenerate; open for a
        dielectric; placed beyond float32's range), or the light is inside a closed
        object (:mod:`scenes.geometry.checks`); each problem names the scene file and
        the field path (``objects[1].file``).
    """
    # Settings never change geometry: a scene's variants (presets, sweeps, and
    # effects_of asking whether a mesh is open) share one build.
    return _build(dataclasses.replace(scene, settings=_SETTINGS))


_SETTINGS = Settings()


@functools.lru_cache(maxsize=8)
def _build(scene: Scene) -> SceneGeometry:
    receivers, objects, problems = [], [], []
    for i, rec in enumerate(scene.receivers):
        try:
            receivers.append(_receiver(rec))
        except GeometryError as error:
            problems.append(Problem(scene.source, f"receivers[{i}].{error.field}", str(error)))
        except (ValueError, OSError) as error:
            field = "height.file" if hasattr(rec, "height") else "file"
            problems.append(Problem(scene.source, f"receivers[{i}].{field}", str(error)))
    for i, obj in enumerate(scene.objects):
        try:
            objects.append(ObjectGeometry(_object(obj), obj.material))
        except GeometryError as error:
            problems.append(Problem(scene.source, f"objects[{i}].{error.field}", str(error)))
        except (ValueError, OSError) as error:
            problems.append(Problem(scene.source, f"objects[{i}].file", str(error)))
    if problems:
        raise SceneError(problems)
    geometry = SceneGeometry(tuple(receivers), tuple(objects))
    problems = light_problems(scene, geometry)
    if problems:
        raise SceneError(problems)
    return geometry


def scene_warnings(scene: Scene) -> list[Problem]:
    """Problems of a legal but suspect scene, one line each (see
    :mod:`scenes.geometry.checks`): the camera inside a closed object, no specular
    object, a specular object the light cannot reach. Builds the geometry.

    Raises
    ------
    SceneError
        As :func:`build_geometry`.
    """
    geometry = build_geometry(scene)
    return camera_warnings(scene, geometry) + light_warnings(scene, geometry)
