"""Every bundled scene exported to glTF and imported back is the same scene: the same
reference cache key (the exact tables in the export's extras), with the scene's mesh
files replaced by the file's triangles where the export could not name them."""

from __future__ import annotations

import numpy as np
import pygltflib as gl
import pytest

from renderers.mitsuba.cache import cache_key
from scenes.bundled import resolve_scene
from scenes.export import export_gltf
from scenes.geometry import build_geometry
from scenes.importers import read_gltf, write_draft
from scenes.loader import load_scene
from tests.conftest import BUNDLED_FILES, bundled_id
from tests.scenes.importers.geometry import largest_vertex_gap


def _has_mesh_file(scene) -> bool:
    return any(getattr(part, "file", "builtin:").startswith("builtin:") is False
               for part in (*scene.receivers, *scene.objects))


@pytest.mark.parametrize("file", BUNDLED_FILES, ids=bundled_id)
def test_round_trip_gives_the_same_scene(file, tmp_path):
    """Regression lock: export then import reproduces the scene (the same cache key), or
    where the scene names mesh files, the same triangles to float32 precision."""
    scene = load_scene(file)
    export_gltf(scene, tmp_path / "scene.glb")
    back = write_draft(read_gltf(tmp_path / "scene.glb"), tmp_path / "back.toml")
    if not _has_mesh_file(scene):
        assert cache_key(back, {}) == cache_key(scene, {})
        return
    assert back.light == scene.light
    assert back.camera == scene.camera
    assert back.settings == scene.settings
    # The file holds float32 positions: equal to float32 precision of the scene's size.
    assert largest_vertex_gap(back, scene) <= 1e-6
    ours, theirs = build_geometry(back), build_geometry(scene)
    for a, b in zip(ours.receivers, theirs.receivers, strict=True):
        # The same (u, v) domain: the irradiance maps compare texel for texel.
        assert np.allclose(a.extent, b.extent, rtol=1e-6, atol=1e-6)
    for a, b in zip(ours.objects, theirs.objects, strict=True):
        # The shading normals come back too (the OBJ's vn lines): the same reference.
        assert len(a.mesh.normals) == len(b.mesh.normals)
        assert np.abs(np.sort(a.mesh.normals, axis=0) - np.sort(b.mesh.normals, axis=0)
                      ).max() <= 1e-6


def test_a_moved_node_gives_way_to_its_triangles(tmp_path):
    """An exported node moved in an editor: its exact table no longer describes its
    triangles, so the triangles are imported (the icosphere, recognised, 1 m along x)."""
    scene = load_scene(resolve_scene("glass_sphere"))
    export_gltf(scene, tmp_path / "scene.glb")
    gltf = gl.GLTF2().load(str(tmp_path / "scene.glb"))
    next(n for n in gltf.nodes if n.name == "object_0").translation = [1.0, 0.0, 0.0]
    gltf.save(str(tmp_path / "moved.glb"))
    back = write_draft(read_gltf(tmp_path / "moved.glb"), tmp_path / "back.toml")
    (sphere,) = back.objects
    assert np.allclose(sphere.center, np.add(scene.objects[0].center, (1.0, 0.0, 0.0)))
    assert sphere.material == scene.objects[0].material
    assert "icosphere" in (tmp_path / "back.toml").read_text()
