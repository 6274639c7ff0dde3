"""Light views (``lights.py``): the object views are fitted to the points on the
caustic objects' convex hull, which must give the views that every vertex gives."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from renderers.caustics_mapping import lights
from scenes import load_scene
from scenes.geometry import build_geometry
from tests.renderers.caustics_mapping.conftest import SCENES


def _views(setups):
    """Every view of every setup, as (where, name, matrix, perspective, half, rect)."""
    return [(f"setup {k} {kind} {i}", v.name, v.view_proj, v.perspective, v.half_size, v.rect)
            for k, s in enumerate(setups)
            for kind, views in (("map", s.map_views), ("object", s.object_views))
            for i, v in enumerate(views)]


@pytest.mark.regression_lock
@pytest.mark.parametrize("frustum", ["tight", "square"])
@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_views_from_the_hull_are_the_views_from_every_vertex(monkeypatch, path, frustum):
    """Boxes, depths, projected rectangles and the farthest distance from a centre
    are all attained on the hull, so the views are the same bit for bit (0 is what
    "the same extremes" means, not a calibrated bound)."""
    scene = load_scene(path)
    geometry = build_geometry(scene)
    hulled = lights.light_setups(scene, geometry, frustum_fit=frustum)
    monkeypatch.setattr(lights, "_extreme_points", lambda points: points)
    every = lights.light_setups(scene, geometry, frustum_fit=frustum)
    assert len(hulled) == len(every)
    for mine, theirs in zip(_views(hulled), _views(every), strict=True):
        where = mine[0]
        assert mine[1] == theirs[1], where
        np.testing.assert_array_equal(mine[2], theirs[2], err_msg=where)
        assert mine[3:] == theirs[3:], where


def test_the_hull_keeps_far_fewer_of_the_bunnys_points():
    """The point of the hull: the bunny's 28,088 vertices fit its views through a
    few thousand (1,640 measured); a sphere's vertices all lie on its hull."""
    bunny = build_geometry(load_scene(SCENES[0].parent / "bunny.toml"))
    points = np.concatenate([g.mesh.positions for g in bunny.objects]).astype(np.float64)
    kept = lights._extreme_points(points)
    assert len(kept) < 0.1 * len(points)
    assert not kept.flags.writeable          # the remembered points cannot be changed
    sphere = build_geometry(load_scene(SCENES[0].parent / "glass_sphere.toml"))
    ball = np.concatenate([g.mesh.positions for g in sphere.objects]).astype(np.float64)
    assert len(lights._extreme_points(ball)) == len(ball)


def test_a_moved_object_gets_its_own_views():
    """The hulls are remembered by the points' content: the same mesh moved is a new
    set of points, and its views follow it."""
    scene = load_scene(SCENES[0].parent / "bunny.toml")
    geometry = build_geometry(scene)
    before = lights.light_setups(scene, geometry, frustum_fit="tight")
    moved = dataclasses.replace(geometry, objects=tuple(
        dataclasses.replace(g, mesh=dataclasses.replace(
            g.mesh, positions=g.mesh.positions + np.float32(0.25)))
        for g in geometry.objects))
    after = lights.light_setups(scene, moved, frustum_fit="tight")
    assert not np.array_equal(before[0].object_views[0].view_proj,
                              after[0].object_views[0].view_proj)
