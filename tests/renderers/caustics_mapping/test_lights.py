"""Light views (``lights.py``): the object views are fitted to the points on the
caustic objects' convex hull, which must give the views that every vertex gives, and
a tight view keeps its outer row of grid vertices off the objects."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from renderers.caustics_mapping import lights, render_frame
from renderers.caustics_mapping.caustic_trace import STATUS
from scenes import load_scene, with_settings
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


@pytest.mark.physical_requirement
@pytest.mark.parametrize("name", ["glass_sphere", "bowl_sun"])
def test_a_tight_views_outer_rows_of_vertices_see_no_object(context_factory, name):
    """Physical requirement: a grid vertex stands for its whole texel, and the outer
    row's texels reach half a texel past the row, into a strip no grid quad (and so
    no rim patch) covers. The tight view keeps a border of half a texel, so that row
    shows nothing and the outline lies inside the quads; without it the outline lies
    in that strip (the rectangle was fitted to it): on the shallow bowl under a 45 deg
    sun, whose floor light comes from a sliver along the outline, 13 vertices of the
    row carried 14 % of the reference's floor flux at the grid's spacing. The count of
    outer-row vertices that show an object is 0 by that border, not a calibrated
    bound (strong, grid 128: glass_sphere, a refractor; bowl_sun, a conductor)."""
    scene = with_settings(load_scene(SCENES[0].parent / f"{name}.toml"),
                          {"preset": "strong", "grid": 128, "caustic_map": 256,
                           "positions_map": 256, "receiver_map": [128, 128]})
    frame = render_frame(scene, ctx=context_factory())
    status = frame.hits["status"].reshape(-1, 128, 128)
    outer = np.concatenate([status[:, 0], status[:, -1], status[:, :, 0], status[:, :, -1]],
                           axis=None)
    assert (status != STATUS["empty"]).sum() > 1000      # the object fills the view
    assert (outer != STATUS["empty"]).sum() == 0
