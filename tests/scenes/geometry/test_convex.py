"""Convexity of closed meshes (``scenes.geometry.mesh.is_convex``), which lets the
strong preset skip its re-entry test on objects no leaving ray can meet again.

Kind: physical requirement (convexity is a property of the geometry; every case is
built so that its answer is known)."""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull

from scenes import load_scene
from scenes.geometry import build_geometry
from scenes.geometry.mesh import is_convex, make_mesh
from tests.conftest import SCENES


def _hull_mesh(points: np.ndarray, *, closed: bool = True):
    """The convex hull of ``points`` as a closed mesh, faces counter-clockwise seen from
    outside (shared vertices, so every edge has its twin)."""
    hull = ConvexHull(points)
    faces = hull.simplices.copy()
    centre = points.mean(axis=0)
    for face in faces:
        a, b, c = points[face]
        if np.dot(np.cross(b - a, c - a), a - centre) < 0:
            face[[1, 2]] = face[[2, 1]]
    return make_mesh(points, points - centre, faces, closed=closed)


def _sphere_points(count: int = 400, seed: int = 0) -> np.ndarray:
    p = np.random.default_rng(seed).normal(size=(count, 3))
    return p / np.linalg.norm(p, axis=1, keepdims=True)


def test_a_hull_is_convex_and_a_dent_is_not():
    """Any convex hull is convex; pushing one vertex inwards past its neighbours'
    plane makes a reflex edge, which the test finds."""
    points = _sphere_points()
    assert is_convex(_hull_mesh(points))
    dented = points.copy()
    dented[0] *= 0.5
    mesh = _hull_mesh(points)
    assert not is_convex(make_mesh(dented, mesh.normals, mesh.faces, closed=True))


def test_open_disjoint_or_unmatched_meshes_are_not_convex():
    """Only a connected closed manifold can be called convex: an open mesh, two
    separate hulls (each convex, the pair not) and a mesh whose faces do not share
    their vertices are not."""
    points = _sphere_points()
    assert not is_convex(_hull_mesh(points, closed=False))
    one = _hull_mesh(points)
    two = make_mesh(np.vstack([one.positions, one.positions + np.array([5.0, 0.0, 0.0])]),
                    np.vstack([one.normals, one.normals]),
                    np.vstack([one.faces, one.faces + len(points)]), closed=True)
    assert not is_convex(two)
    split = one.positions[one.faces.ravel()]
    unshared = make_mesh(split, one.normals[one.faces.ravel()],
                         np.arange(len(split)).reshape(-1, 3), closed=True)
    assert not is_convex(unshared)


def test_bundled_objects():
    """The bundled spheres are convex; the bunny and the torus are not."""
    expected = {"glass_sphere": True, "spot_sphere": True, "bunny": False,
                "spot_torus": False}
    for name, convex in expected.items():
        geometry = build_geometry(load_scene(SCENES / f"{name}.toml"))
        assert [is_convex(o.mesh) for o in geometry.objects] == [convex], name
