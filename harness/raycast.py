"""Exact ray casting against the scene's own triangles (Mitsuba's ray tracer).

The convergence tables compare each estimator's hit distance with the exact distance
along the same ray (v, r) to the receivers; this module provides that exact distance
from the very triangles both renderers were given (``scenes.geometry``).
:class:`SurfaceTracer` also returns what a light path needs at each hit (the shape,
its shading and geometric normals), on the reference's own Mitsuba scene, for the
exact light paths of the error decomposition (``harness.studies.exact_paths``).
"""

from __future__ import annotations

import numpy as np

from renderers.mitsuba import load_mitsuba
from renderers.mitsuba.exporter import export_scene
from scenes.camera import camera_rays
from scenes.geometry import SceneGeometry, TriangleMesh, build_geometry
from scenes.model import Scene

#: ``camera_rays`` (the scene camera's primary rays, :mod:`scenes.camera`) is
#: importable from here beside the tracers that cast them.
__all__ = ["RayHits", "ReceiverTracer", "SurfaceHits", "SurfaceTracer", "camera_rays",
           "cast_rays"]


def _mitsuba():
    """Mitsuba with its variant set (the renderer's one loader, ``llvm_ad_rgb``)."""
    return load_mitsuba()[0]


def _mesh_scene(mi, mesh: TriangleMesh, name: str):
    """A one-shape Mitsuba scene holding exactly ``mesh``'s triangles."""
    shape = mi.Mesh(name, vertex_count=len(mesh.positions), face_count=len(mesh.faces),
                    has_vertex_normals=False, has_vertex_texcoords=False)
    params = mi.traverse(shape)
    params["vertex_positions"] = mesh.positions.astype(np.float32).ravel()
    params["faces"] = mesh.faces.astype(np.uint32).ravel()
    params.update()
    return mi.load_dict({"type": "scene", name: shape})


class RayHits:
    """Nearest receiver hits of a batch of rays.

    Attributes
    ----------
    distance : ndarray (N,), float64
        Distance along the unit direction to the nearest receiver, metres; ``inf``
        where no receiver is hit.
    receiver : ndarray (N,), int
        Index into ``scene.receivers`` of the receiver hit, −1 for none.
    position : ndarray (N, 3), float64
        Hit points, metres (NaN rows where there is no hit).
    """

    def __init__(self, distance, receiver, position):
        self.distance = distance
        self.receiver = receiver
        self.position = position


class MeshTracer:
    """Nearest hits against a list of meshes: ``tracer(origins, directions) -> RayHits``
    (``RayHits.receiver`` is then the index into ``meshes``)."""

    def __init__(self, meshes: list[TriangleMesh]):
        mi = _mitsuba()
        self._mi = mi
        self._scenes = [_mesh_scene(mi, mesh, f"mesh{i}") for i, mesh in enumerate(meshes)]

    def __call__(self, origins, directions) -> RayHits:
        """Cast rays from ``origins`` (N, 3) along ``directions`` (N, 3), metres.

        Directions are normalised here, so distances are in metres.
        """
        mi = self._mi
        o = np.asarray(origins, np.float64).reshape(-1, 3)
        d = np.asarray(directions, np.float64).reshape(-1, 3)
        if len(o) == 0:  # Dr.Jit aborts on zero-sized launches
            return RayHits(np.zeros(0), np.zeros(0, int), np.zeros((0, 3)))
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        ray = mi.Ray3f(mi.Point3f(o.T.astype(np.float32)), mi.Vector3f(d.T.astype(np.float32)))
        best = np.full(len(o), np.inf)
        index = np.full(len(o), -1)
        for i, scene in enumerate(self._scenes):
            si = scene.ray_intersect(ray)
            t = np.where(np.asarray(si.is_valid()), np.asarray(si.t, np.float64), np.inf)
            closer = t < best
            best[closer], index[closer] = t[closer], i
        hit = np.isfinite(best)
        position = np.where(hit[:, None], o + np.where(hit, best, 0.0)[:, None] * d, np.nan)
        return RayHits(best, index, position)


class ReceiverTracer(MeshTracer):
    """Build once per geometry, then ``tracer(origins, directions) -> RayHits``."""

    def __init__(self, geometry: SceneGeometry):
        super().__init__([rec.mesh for rec in geometry.receivers])


class SurfaceHits:
    """Nearest surface hits of a batch of rays, with what a specular event needs.

    Attributes
    ----------
    distance : ndarray (N,), float64
        Distance along the unit direction, metres; ``inf`` where nothing is hit.
    kind : ndarray (N,), int
        :data:`SurfaceTracer.NONE`, :data:`SurfaceTracer.RECEIVER` or
        :data:`SurfaceTracer.OBJECT`.
    index : ndarray (N,), int
        Index into ``scene.receivers`` or ``scene.objects`` (by ``kind``), −1 for none.
    position : ndarray (N, 3), float64
        Hit points (Mitsuba's, float32 precision), metres; zeros where nothing is hit.
    shading_normal, geometric_normal : ndarray (N, 3), float64
        Unit normals at the hit: the interpolated vertex normal (the meshes' own, as
        both renderers shade with) and the triangle's; zeros where nothing is hit.
    """

    def __init__(self, distance, kind, index, position, *, shading_normal, geometric_normal):
        self.distance = distance
        self.kind = kind
        self.index = index
        self.position = position
        self.shading_normal = shading_normal
        self.geometric_normal = geometric_normal


class SurfaceTracer:
    """Nearest hits on the reference's own Mitsuba scene (``export_scene``: the same
    triangles and vertex normals both renderers use): ``tracer(origins, directions,
    leaving=None) -> SurfaceHits``.

    Parameters
    ----------
    scene : Scene
    geometry : SceneGeometry, optional
    objects : bool
        Include the caustic objects (False: the receivers alone).
    """

    NONE, RECEIVER, OBJECT = 0, 1, 2

    def __init__(self, scene: Scene, geometry: SceneGeometry | None = None, *,
                 objects: bool = True):
        mi, dr, _ = load_mitsuba()
        self._mi, self._dr = mi, dr
        exported = export_scene(scene, geometry=geometry or build_geometry(scene),
                                include_objects=objects)
        self._scene = exported.scene
        self._ids = {int(i): (self.RECEIVER, k) for k, i in enumerate(exported.receiver_ids)}
        self._ids |= {int(i): (self.OBJECT, k) for k, i in enumerate(exported.object_ids)}

    def __call__(self, origins, directions, *, leaving=None) -> SurfaceHits:
        """Cast rays from ``origins`` (N, 3) along ``directions`` (N, 3), metres.

        ``leaving`` (N, 3): the geometric normals of the surfaces the rays leave; each
        origin is then moved off its surface as Mitsuba's
        ``SurfaceInteraction3f.spawn_ray`` does (the reference photon tracer's rule),
        so a ray does not hit the surface it starts on. Directions are normalised here.
        """
        mi, dr = self._mi, self._dr
        o = np.asarray(origins, np.float64).reshape(-1, 3)
        d = np.asarray(directions, np.float64).reshape(-1, 3)
        n = len(o)
        if n == 0:  # Dr.Jit aborts on zero-sized launches
            z3 = np.zeros((0, 3))
            return SurfaceHits(np.zeros(0), np.zeros(0, int), np.zeros(0, int), z3,
                               shading_normal=z3, geometric_normal=z3)
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        direction = mi.Vector3f(d.T.astype(np.float32))
        if leaving is None:
            ray = mi.Ray3f(mi.Point3f(o.T.astype(np.float32)), direction)
        else:
            start = dr.zeros(mi.SurfaceInteraction3f, n)
            start.p = mi.Point3f(o.T.astype(np.float32))
            start.n = mi.Normal3f(np.asarray(leaving, np.float64).reshape(-1, 3).T
                                  .astype(np.float32))
            ray = start.spawn_ray(direction)
        si = self._scene.ray_intersect(ray)
        valid, shape = si.is_valid(), dr.reinterpret_array(mi.UInt32, si.shape)
        dr.eval(valid, shape, si.t, si.p, si.n, si.sh_frame.n)  # one kernel for all fields
        valid, shape = np.asarray(valid, bool), np.asarray(shape, np.int64)
        kind = np.zeros(n, int)
        index = np.full(n, -1)
        for sid, (k, i) in self._ids.items():
            here = valid & (shape == sid)
            kind[here], index[here] = k, i
        hit = kind != self.NONE
        distance = np.where(hit, np.asarray(si.t, np.float64), np.inf)

        def field(values) -> np.ndarray:
            xyz = np.stack([np.asarray(c, np.float64) for c in (values.x, values.y, values.z)],
                           axis=1)
            return np.where(hit[:, None], xyz, 0.0)

        return SurfaceHits(distance, kind, index, field(si.p),
                           shading_normal=field(si.sh_frame.n), geometric_normal=field(si.n))


def cast_rays(geometry: SceneGeometry, origins, directions) -> RayHits:
    """One-shot convenience: nearest receiver hit of each ray (see ``ReceiverTracer``)."""
    return ReceiverTracer(geometry)(origins, directions)
