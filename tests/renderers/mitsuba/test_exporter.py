"""The exporter hands Mitsuba the same triangles, normals and (u, v) the GPU
renderer gets, and the depth/chains follow the effects."""

from __future__ import annotations

import numpy as np
import pytest

from renderers.mitsuba import load_mitsuba
from renderers.mitsuba.camera import camera_max_depth
from renderers.mitsuba.exporter import export_scene
from renderers.mitsuba.photons import event_chains_counted
from scenes import load_scene
from scenes.geometry import build_geometry


@pytest.mark.parametrize("name", ["glass_sphere", "water_pool", "metal_ring"])
def test_meshes_are_bit_identical(name, request):
    mi, _, _ = load_mitsuba()
    scene = load_scene(request.config.rootpath / "scenes" / f"{name}.toml")
    geometry = build_geometry(scene)
    exported = export_scene(scene, geometry=geometry)
    shapes = {s.id(): mi.traverse(s) for s in exported.scene.shapes()}
    pairs = [(f"receiver_{i}", r.mesh) for i, r in enumerate(geometry.receivers)]
    pairs += [(f"object_{i}", o.mesh) for i, o in enumerate(geometry.objects)]
    for key, mesh in pairs:
        params = shapes[key]
        np.testing.assert_array_equal(np.asarray(params["vertex_positions"]),
                                      mesh.positions.ravel())
        np.testing.assert_array_equal(np.asarray(params["vertex_normals"]), mesh.normals.ravel())
        np.testing.assert_array_equal(np.asarray(params["faces"]), mesh.faces.ravel())
        if key.startswith("receiver"):
            np.testing.assert_array_equal(np.asarray(params["vertex_texcoords"]),
                                          mesh.uvs.ravel())


@pytest.mark.parametrize(("name", "depth", "chains"), [
    ("glass_sphere", 4, ["L D", "L T T D (objects[0])"]),
    ("water_pool", 3, ["L T D (objects[0])"]),
    ("metal_ring", 3, ["L D", "L R D (objects[0])"]),
])
def test_depth_and_chains_follow_effects(name, depth, chains, request):
    """ptracer max_depth = longest chain + 2 (L D E is 2); the chains recorded."""
    scene = load_scene(request.config.rootpath / "scenes" / f"{name}.toml")
    assert camera_max_depth(scene) == depth
    assert event_chains_counted(scene) == chains
