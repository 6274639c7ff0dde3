"""glTF files the harness never wrote: a plain file (no extras) imports; an area light is
refused with one line and approximated on request; bad files give one line each."""

from __future__ import annotations

import json

import pygltflib as gl
import pytest
import trimesh

from scenes.importers import ImportProblemError, read_gltf, write_draft
from scenes.model import DielectricMaterial, PlaneReceiver, PointLight


def _plain_gltf(path, *, emissive_light: bool = False):
    """An icosphere with KHR transmission + IOR, a quad floor, a KHR point light and a
    camera, glTF axes (+y up), no extras: written with trimesh and pygltflib."""
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.5)
    sphere.apply_translation([0, 1.0, 0])
    floor = trimesh.Trimesh([[-2, 0, 2], [2, 0, 2], [2, 0, -2], [-2, 0, -2]],
                            [[0, 1, 2], [0, 2, 3]], process=False)
    scene = trimesh.Scene()
    scene.add_geometry(sphere, node_name="glass", geom_name="glass")
    scene.add_geometry(floor, node_name="floor", geom_name="floor")
    gltf = gl.GLTF2().load_from_bytes(scene.export(file_type="glb"))
    names = [n.name for n in gltf.nodes]
    glass = names.index("glass")
    materials = [gl.Material(name="glass", pbrMetallicRoughness=gl.PbrMetallicRoughness(
        metallicFactor=0.0, roughnessFactor=0.0),
        extensions={"KHR_materials_transmission": {"transmissionFactor": 1.0},
                    "KHR_materials_ior": {"ior": 1.45}}),
        gl.Material(name="floor", pbrMetallicRoughness=gl.PbrMetallicRoughness(
            baseColorFactor=[0.7, 0.7, 0.7, 1], metallicFactor=0.0, roughnessFactor=1.0))]
    gltf.materials = materials
    for node in gltf.nodes:
        if node.mesh is not None:
            for primitive in gltf.meshes[node.mesh].primitives:
                primitive.material = 0 if node.name == "glass" else 1
    if emissive_light:  # a copy of the floor 4 m up, emitting: an area light
        gltf.materials.append(gl.Material(name="panel", emissiveFactor=[1.0, 1.0, 1.0]))
        floor = next(n for n in gltf.nodes if n.name == "floor")
        (primitive,) = gltf.meshes[floor.mesh].primitives
        panel = gl.Primitive(attributes=primitive.attributes, indices=primitive.indices,
                             material=2)
        gltf.meshes.append(gl.Mesh(name="panel", primitives=[panel]))
        gltf.nodes.append(gl.Node(name="panel", mesh=len(gltf.meshes) - 1,
                                  translation=[0, 4, 0]))
        gltf.scenes[0].nodes.append(len(gltf.nodes) - 1)
    gltf.extensions = {"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1, 1, 1], "intensity": 20.0}]}}
    gltf.extensionsUsed = ["KHR_lights_punctual", "KHR_materials_transmission",
                           "KHR_materials_ior"]
    gltf.cameras = [gl.Camera(type="perspective", perspective=gl.Perspective(
        yfov=0.7, aspectRatio=1.5, znear=0.01))]
    gltf.nodes.append(gl.Node(name="sun", translation=[0, 5, 0],
                              extensions={"KHR_lights_punctual": {"light": 0}}))
    # The camera at (0, 2, 6) glTF, looking along -z (its default).
    gltf.nodes.append(gl.Node(name="eye", camera=0, translation=[0, 2, 6]))
    gltf.scenes[0].nodes += [len(gltf.nodes) - 2, len(gltf.nodes) - 1]
    assert glass >= 0
    gltf.save(str(path))
    return path


def test_plain_gltf_imports(tmp_path):
    """Physical requirement: a file without extras reads as a glass sphere over a plane,
    lit by a point light, axes converted (+y up to +z up)."""
    scene = write_draft(read_gltf(_plain_gltf(tmp_path / "plain.glb")), tmp_path / "s.toml")
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
    path = _plain_gltf(tmp_path / "area.glb", emissive_light=True)
    with pytest.raises(ImportProblemError) as caught:
        write_draft(read_gltf(path), tmp_path / "s.toml")
    area = [p for p in caught.value.problems if "area light" in p]
    assert len(area) == 1 and "'panel'" in area[0]
    scene = write_draft(read_gltf(path, approximate=True), tmp_path / "s.toml")
    assert "area light" in scene.info.description


def test_truncated_glb_is_one_line(tmp_path):
    path = _plain_gltf(tmp_path / "plain.glb")
    truncated = tmp_path / "cut.glb"
    truncated.write_bytes(path.read_bytes()[:600])
    with pytest.raises(ImportProblemError) as caught:
        read_gltf(truncated)
    assert len(caught.value.problems) == 1 and "cut.glb" in caught.value.problems[0]


def test_missing_buffer_names_it(tmp_path):
    gltf = gl.GLTF2().load(str(_plain_gltf(tmp_path / "plain.glb")))
    gltf.convert_buffers(gl.BufferFormat.BINFILE)
    gltf.save(str(tmp_path / "plain.gltf"))
    (uri,) = [b.uri for b in gltf.buffers]
    (tmp_path / uri).unlink()
    with pytest.raises(ImportProblemError, match=f"buffers\\[0\\]: cannot read '{uri}'"):
        read_gltf(tmp_path / "plain.gltf")


def test_degenerate_and_absurd_meshes_are_named(tmp_path):
    path = _plain_gltf(tmp_path / "plain.glb")
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
