"""glTF files the harness never wrote: a plain file (no extras) imports; an area light is
refused with one line and approximated on request; bad files give one line each."""

from __future__ import annotations

import json

import pygltflib as gl
import pytest

from scenes.importers import ImportProblemError, read_gltf, write_draft
from scenes.model import DielectricMaterial, PlaneReceiver, PointLight
from tests.scenes.importers.files import plain_gltf


def test_plain_gltf_imports(tmp_path):
    """Physical requirement: a file without extras reads as a glass sphere over a plane,
    lit by a point light, axes converted (+y up to +z up)."""
    scene = write_draft(read_gltf(plain_gltf(tmp_path / "plain.glb")), tmp_path / "s.toml")
    assert isinstance(scene.light, PointLight)
    assert scene.light.position == pytest.approx((0, 0, 5))
    assert scene.light.intensity == (20.0, 20.0, 20.0)
    (floor,) = scene.receivers
    assert isinstance(floor, PlaneReceiver)
    assert floor.normal == pytest.approx((0, 0, 1))
    assert sorted(floor.size) == pytest.approx([4, 4])
    (glass,) = scene.objects
    assert isinstance(glass.material, DielectricMaterial)
    assert glass.material.ior == 1.45
    assert scene.camera.position == pytest.approx((0, -6, 2))
    assert scene.camera.resolution == (768, 512)
    text = (tmp_path / "s.toml").read_text()
    assert "# from glTF node 'glass'" in text and "# from glTF node 'floor'" in text


def test_area_light_refused_then_approximated(tmp_path):
    """An emissive surface is refused with one line naming the node, and with
    approximate=True replaced by a point light the description states."""
    path = plain_gltf(tmp_path / "area.glb", emissive_light=True)
    with pytest.raises(ImportProblemError) as caught:
        write_draft(read_gltf(path), tmp_path / "s.toml")
    area = [p for p in caught.value.problems if "area light" in p]
    assert len(area) == 1 and "'panel'" in area[0]
    scene = write_draft(read_gltf(path, approximate=True), tmp_path / "s.toml")
    assert "area light" in scene.info.description


def test_truncated_glb_is_one_line(tmp_path):
    path = plain_gltf(tmp_path / "plain.glb")
    truncated = tmp_path / "cut.glb"
    truncated.write_bytes(path.read_bytes()[:600])
    with pytest.raises(ImportProblemError) as caught:
        read_gltf(truncated)
    assert len(caught.value.problems) == 1 and "cut.glb" in caught.value.problems[0]


def test_missing_buffer_names_it(tmp_path):
    gltf = gl.GLTF2().load(str(plain_gltf(tmp_path / "plain.glb")))
    gltf.convert_buffers(gl.BufferFormat.BINFILE)
    gltf.save(str(tmp_path / "plain.gltf"))
    (uri,) = [b.uri for b in gltf.buffers]
    (tmp_path / uri).unlink()
    with pytest.raises(ImportProblemError, match=f"buffers\\[0\\]: cannot read '{uri}'"):
        read_gltf(tmp_path / "plain.gltf")


def test_degenerate_and_absurd_meshes_are_named(tmp_path):
    path = plain_gltf(tmp_path / "plain.glb")
    gltf = gl.GLTF2().load(str(path))
    floor = next(n for n in gltf.nodes if n.name == "floor")
    floor.scale = [1e6, 1e6, 1e6]
    gltf.save(str(tmp_path / "huge.glb"))
    with pytest.raises(ImportProblemError, match=r"node .floor.: the mesh is .* m across"):
        write_draft(read_gltf(tmp_path / "huge.glb"), tmp_path / "s.toml")
    floor.scale = [1, 1, 0]  # the floor (in x, z) flattened to a line: zero areas
    gltf.save(str(tmp_path / "flat.glb"))
    with pytest.raises(ImportProblemError, match="node 'floor': the mesh is degenerate"):
        write_draft(read_gltf(tmp_path / "flat.glb"), tmp_path / "s.toml")


def test_not_gltf_is_one_line(tmp_path):
    bad = tmp_path / "bad.gltf"
    bad.write_text(json.dumps({"asset": {"version": "2.0"}})[:-3])
    with pytest.raises(ImportProblemError) as caught:
        read_gltf(bad)
    assert len(caught.value.problems) == 1


def test_open_dielectric_is_refused(tmp_path):
    """A glass mesh with a hole (not watertight) is one line naming its node; nothing
    else is reported missing for it."""
    gltf = gl.GLTF2().load(str(plain_gltf(tmp_path / "plain.glb")))
    glass = next(n for n in gltf.nodes if n.name == "glass")
    (primitive,) = gltf.meshes[glass.mesh].primitives
    gltf.accessors[primitive.indices].count -= 3  # drop the last triangle
    gltf.save(str(tmp_path / "open.glb"))
    with pytest.raises(ImportProblemError) as caught:
        write_draft(read_gltf(tmp_path / "open.glb"), tmp_path / "s.toml")
    (line,) = caught.value.problems
    assert "node 'glass'" in line and "not watertight" in line
