"""Scene files the harness never wrote, made here for the import tests: a glTF written
with trimesh and pygltflib (no extras), a Mitsuba XML written by hand (an include and a
``<default>``); each holds a glass sphere, a diffuse floor, a point light and a camera."""

from __future__ import annotations

import pygltflib as gl
import trimesh

__all__ = ["AREA_XML", "plain_gltf", "plain_xml"]


def plain_gltf(path, *, emissive_light: bool = False):
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


XML_TEXT = """<scene version="3.0.0">
  <default name="ior" value="1.5"/>
  <include filename="floor.xml"/>
  <shape type="sphere" id="glass"><point name="center" x="0" y="0" z="1"/>
    <float name="radius" value="0.5"/>
    <bsdf type="dielectric"><float name="int_ior" value="$ior"/>
      <float name="ext_ior" value="1"/></bsdf></shape>
  <emitter type="point" id="bulb"><point name="position" x="0" y="0" z="5"/>
    <rgb name="intensity" value="10"/></emitter>
  {extra}
  <sensor type="perspective" id="eye"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0,-5,3" target="0,0,0" up="0,0,1"/></transform>
    <film type="hdrfilm"><integer name="width" value="320"/>
      <integer name="height" value="240"/></film></sensor>
</scene>
"""
FLOOR_XML = """<scene version="3.0.0"><shape type="rectangle" id="floor">
  <transform name="to_world"><scale x="3" y="2"/><rotate z="1" angle="30"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.5,0.4,0.3"/></bsdf></shape></scene>
"""
AREA_XML = """<shape type="sphere" id="lamp"><point name="center" x="2" y="0" z="3"/>
    <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"""


def plain_xml(tmp_path, extra: str = ""):
    """``tmp_path/scene.xml`` (and the ``floor.xml`` it includes); ``extra`` is XML added to
    the scene."""
    (tmp_path / "floor.xml").write_text(FLOOR_XML)
    path = tmp_path / "scene.xml"
    path.write_text(XML_TEXT.replace("{extra}", extra))
    return path
