"""glTF export round trip (``scenes/export``): the file read back with pygltflib, converted
back to scene axes, against the scene: geometry within the chord tolerance of the
analytic surface, materials, the light, the scene camera and each receiver's
orthographic camera and frame.

Kind: physical requirements of the mapping (exact geometry; tolerances are float32
rounding, 1e-6 relative, or the stated chord tolerance)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pygltflib as gl
import pytest
from scipy.spatial.transform import Rotation

from scenes import load_scene, resolve_scene
from scenes.camera import pinhole_directions
from scenes.export import GLTF_FROM_SCENE, UNITS, export_gltf
from scenes.export.tessellation import sphere_chord_error
from scenes.geometry import build_geometry
from tests.scenes.export.scenes import area_light_scene

_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


class Read:
    """An exported file, read back: arrays in scene axes, nodes by name."""

    def __init__(self, path):
        self.gltf = gl.GLTF2().load(str(path))
        self.blob = self.gltf.binary_blob() if str(path).endswith(".glb") else (
            path.with_suffix(".bin").read_bytes())
        self.nodes = {n.name: n for n in self.gltf.nodes}

    def array(self, index: int) -> np.ndarray:
        accessor = self.gltf.accessors[index]
        view = self.gltf.bufferViews[accessor.bufferView]
        dtype = np.uint32 if accessor.componentType == gl.UNSIGNED_INT else np.float32
        data = np.frombuffer(self.blob, dtype, count=accessor.count
                             * _COMPONENTS[accessor.type], offset=view.byteOffset)
        return data.reshape(accessor.count, -1)

    def mesh(self, name: str) -> dict:
        primitive = self.gltf.meshes[self.nodes[name].mesh].primitives[0]
        attributes = primitive.attributes
        out = {"positions": self.array(attributes.POSITION) @ GLTF_FROM_SCENE,
               "normals": self.array(attributes.NORMAL) @ GLTF_FROM_SCENE,
               "faces": self.array(primitive.indices).reshape(-1, 3),
               "material": self.gltf.materials[primitive.material]}
        if attributes.TEXCOORD_0 is not None:
            out["uv"] = self.array(attributes.TEXCOORD_0)
        return out

    def placement(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(position, 3x3 rotation of the node's local axes), in scene axes."""
        node = self.nodes[name]
        rotation = Rotation.from_quat(node.rotation or [0, 0, 0, 1]).as_matrix()
        return (np.asarray(node.translation or [0, 0, 0]) @ GLTF_FROM_SCENE,
                GLTF_FROM_SCENE.T @ rotation)

    def light(self) -> dict:
        index = self.nodes["light"].extensions["KHR_lights_punctual"]["light"]
        return self.gltf.extensions["KHR_lights_punctual"]["lights"][index]


def _export(tmp_path, name: str, *, suffix: str = ".glb", tolerance=None, scene=None):
    scene = scene or load_scene(resolve_scene(name))
    done = export_gltf(scene, tmp_path / f"{scene.name}{suffix}", tolerance=tolerance)
    return scene, done, Read(done.path)


def _face_samples(positions, faces, n: int = 6) -> np.ndarray:
    """Points of a barycentric grid on every face (vertices, edges and interior)."""
    a, b, c = (positions[faces[:, k]].astype(np.float64) for k in range(3))
    points = [a * (i / n) + b * (j / n) + c * ((n - i - j) / n)
              for i in range(n + 1) for j in range(n + 1 - i)]
    return np.concatenate(points)


@pytest.mark.parametrize("tolerance", [None, 1e-4])
def test_sphere_triangles_lie_within_the_tolerance_of_the_sphere(tmp_path, tolerance):
    """glass_sphere: every vertex on the sphere (float32 rounding), every point of every
    face within the stated tolerance inside it; the stated chord error is the measured
    one, and 1e-4 m refines the scene's 5 levels to 6 (7.1e-5 m)."""
    scene, done, read = _export(tmp_path, "glass_sphere", tolerance=tolerance)
    sphere = scene.objects[0]
    mesh = read.mesh("object_0")
    centre, r = np.asarray(sphere.center), sphere.radius
    radii = np.linalg.norm(mesh["positions"] - centre, axis=1)
    np.testing.assert_allclose(radii, r, atol=4e-7 * (r + np.abs(centre).max()))
    depth = r - np.linalg.norm(_face_samples(mesh["positions"], mesh["faces"]) - centre, axis=1)
    assert depth.max() <= done.tolerance + 1e-6
    stated = read.gltf.asset.extras["harness"]["tessellation"]["objects"][0]
    assert depth.max() == pytest.approx(stated["chord_error"], rel=0.02)
    assert stated["level"]["subdivisions"] == (5 if tolerance is None else 6)
    assert read.gltf.asset.extras["harness"]["tessellation"]["tolerance_m"] == done.tolerance


def test_ring_band_lies_within_the_tolerance_of_its_cylinder(tmp_path):
    """metal_ring at 1e-5 m: the band's vertices at the ring's radius from its axis, its
    facets' middles within the tolerance inside (703 segments: pi / acos(1 - 1e-5 / r))."""
    scene, done, read = _export(tmp_path, "metal_ring", tolerance=1e-5)
    ring = scene.objects[0]
    mesh = read.mesh("object_0")
    axis = np.asarray(ring.axis, float) / np.linalg.norm(ring.axis)

    def radial(points):
        d = points - np.asarray(ring.center)
        return np.linalg.norm(d - np.outer(d @ axis, axis), axis=1)

    np.testing.assert_allclose(radial(mesh["positions"]), ring.radius, rtol=1e-6)
    depth = ring.radius - radial(_face_samples(mesh["positions"], mesh["faces"]))
    assert 0.5e-5 < depth.max() <= 1e-5 + 1e-7
    assert done.objects[0].level["segments"] == math.ceil(
        math.pi / math.acos(1 - 1e-5 / ring.radius))


def test_meshes_and_grids_are_the_triangles_both_renderers_get(tmp_path):
    """A mesh file (spot_torus) and a heightfield with a water surface (seabed) read back
    as the very triangles and normals of build_geometry (float32 exact after the axes)."""
    for name in ("spot_torus", "seabed"):
        scene, _, read = _export(tmp_path, name)
        geometry = build_geometry(scene)
        for label, built in [*(("receiver", g) for g in geometry.receivers[:1]),
                             *(("object", g) for g in geometry.objects[:1])]:
            mesh = read.mesh(f"{label}_0")
            np.testing.assert_allclose(mesh["positions"], built.mesh.positions, atol=1e-6)
            np.testing.assert_allclose(mesh["normals"], built.mesh.normals, atol=1e-6)
            np.testing.assert_array_equal(mesh["faces"], built.mesh.faces)


def test_gltf_with_its_buffer_reads_back_as_the_glb(tmp_path):
    """``.gltf`` + ``.bin`` holds the same arrays and JSON as ``.glb``."""
    _, _, glb = _export(tmp_path, "glass_sphere")
    _, _, text = _export(tmp_path, "glass_sphere", suffix=".gltf")
    for name in ("receiver_0", "object_0"):
        for key in ("positions", "normals", "faces"):
            np.testing.assert_array_equal(glb.mesh(name)[key], text.mesh(name)[key])
    assert glb.gltf.asset.extras == text.gltf.asset.extras


def test_materials(tmp_path):
    """Receivers and diffuse: base colour = albedo; dielectric: transmission 1, ior (the
    green channel's), volume with Beer-Lambert attenuation that gives back the absorption
    (colored_bunny), dispersion 20 (n_F - n_C) / (n_d - 1) (dispersion_sphere);
    conductor: metallic, base colour = reflectance, two-sided (metal_ring); exact values
    in extras."""
    scene, _, read = _export(tmp_path, "dispersion_sphere")
    receiver = read.mesh("receiver_0")["material"]
    assert receiver.pbrMetallicRoughness.baseColorFactor[:3] == list(scene.receivers[0].albedo)
    assert receiver.pbrMetallicRoughness.metallicFactor == 0 and not receiver.doubleSided
    glass = read.mesh("object_0")["material"]
    assert glass.extensions["KHR_materials_transmission"]["transmissionFactor"] == 1.0
    assert glass.extensions["KHR_materials_ior"]["ior"] == 1.52
    assert glass.extensions["KHR_materials_dispersion"]["dispersion"] == pytest.approx(
        20 * (1.62 - 1.45) / 0.52)
    assert glass.extras["harness"]["ior"] == [1.45, 1.52, 1.62]
    assert glass.extensions["KHR_materials_volume"]["thicknessFactor"] == pytest.approx(2.0,
                                                                                       rel=1e-6)
    assert not glass.doubleSided

    scene, _, read = _export(tmp_path, "colored_bunny")
    volume = read.mesh("object_0")["material"].extensions["KHR_materials_volume"]
    sigma = -np.log(volume["attenuationColor"]) / volume["attenuationDistance"]
    np.testing.assert_allclose(sigma, scene.objects[0].material.absorption, rtol=1e-12)

    scene, _, read = _export(tmp_path, "metal_ring")
    metal = read.mesh("object_0")["material"]
    assert metal.pbrMetallicRoughness.metallicFactor == 1.0
    assert metal.pbrMetallicRoughness.roughnessFactor == 0.0
    assert metal.pbrMetallicRoughness.baseColorFactor[:3] == list(
        scene.objects[0].material.reflectance)
    assert metal.doubleSided and "KHR_materials_transmission" not in (metal.extensions or {})


def _local_minus_z(rotation: np.ndarray) -> np.ndarray:
    return -rotation[:, 2]


def test_lights(tmp_path):
    """Point: position and RGB intensity (colour x intensity, W/sr); spot: its -z along the
    scene's direction, outer cone = cutoff, inner = beam width (rad); directional: its -z
    along the direction, colour x intensity = irradiance (W/m^2); the units stated."""
    scene, _, read = _export(tmp_path, "glass_sphere")
    light = read.light()
    position, _ = read.placement("light")
    assert light["type"] == "point"
    np.testing.assert_allclose(position, scene.light.position, atol=1e-12)
    np.testing.assert_allclose(np.multiply(light["color"], light["intensity"]),
                               scene.light.intensity)
    assert read.gltf.asset.extras["harness"]["units"] == UNITS
    assert "W/sr" in UNITS["point_spot_intensity"]

    scene, _, read = _export(tmp_path, "spot_sphere")
    light = read.light()
    position, rotation = read.placement("light")
    direction = np.asarray(scene.light.direction) / np.linalg.norm(scene.light.direction)
    np.testing.assert_allclose(_local_minus_z(rotation), direction, atol=1e-12)
    np.testing.assert_allclose(position, scene.light.position, atol=1e-12)
    assert light["spot"]["outerConeAngle"] == pytest.approx(math.radians(
        scene.light.cutoff_angle))
    assert light["spot"]["innerConeAngle"] == pytest.approx(math.radians(
        scene.light.beam_width))

    scene, _, read = _export(tmp_path, "water_pool")
    light = read.light()
    _, rotation = read.placement("light")
    direction = np.asarray(scene.light.direction) / np.linalg.norm(scene.light.direction)
    assert light["type"] == "directional"
    np.testing.assert_allclose(_local_minus_z(rotation), direction, atol=1e-12)
    np.testing.assert_allclose(np.multiply(light["color"], light["intensity"]),
                               scene.light.irradiance)


def test_scene_camera_sees_every_pixel_along_the_scenes_ray(tmp_path):
    """A 640 x 480 camera (fov along x): the glTF perspective camera (yfov, aspect ratio,
    the node's -z forward and +y up) sends each image corner's and the centre's ray along
    the scene camera's pinhole direction (scenes.camera)."""
    scene = load_scene(resolve_scene("glass_sphere"))
    scene = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                  resolution=(640, 480)))
    _, _, read = _export(tmp_path, "glass_sphere", scene=scene)
    node = read.nodes["camera"]
    perspective = read.gltf.cameras[node.camera].perspective
    position, rotation = read.placement("camera")
    np.testing.assert_allclose(position, scene.camera.position, atol=1e-12)
    fx = np.array([0.0, 640.0, 0.0, 640.0, 320.0, 17.5])
    fy = np.array([0.0, 0.0, 480.0, 480.0, 240.0, 401.5])
    tan_y = math.tan(perspective.yfov / 2)
    local = np.stack([(2 * fx / 640 - 1) * tan_y * perspective.aspectRatio,
                      (1 - 2 * fy / 480) * tan_y, -np.ones_like(fx)], axis=1)
    seen = local @ rotation.T
    seen /= np.linalg.norm(seen, axis=1, keepdims=True)
    np.testing.assert_allclose(seen, pinhole_directions(scene.camera, fx, fy), atol=1e-12)


def _orthographic_pixels(read: Read, index: int, points: np.ndarray):
    """(column, row, depth) of scene points in receiver ``index``'s camera image of the
    frame's resolution (glTF's orthographic projection: x / xmag, y / ymag in [-1, 1])."""
    name = f"receiver_{index}_camera"
    node = read.nodes[name]
    ortho = read.gltf.cameras[node.camera].orthographic
    width, height = node.extras["harness"]["resolution"]
    position, rotation = read.placement(name)
    local = (points - position) @ rotation
    column = (local[:, 0] / ortho.xmag + 1) / 2 * width
    row = (1 - local[:, 1] / ortho.ymag) / 2 * height
    return column, row, -local[:, 2], ortho


@pytest.mark.parametrize(("name", "clear"), [("glass_sphere", True), ("seabed", True),
                                             ("bowl_sun", False)])
def test_receiver_camera_maps_receiver_uv_onto_its_map(tmp_path, name, clear):
    """Each receiver vertex, seen by its orthographic camera, lands at the image position
    the frame states for its (u, v) (column (u - umin) / du, row (vmax - v) / dv, from
    TEXCOORD_0 back to metres), inside the camera's depth slab. Where no object touches
    the receiver (``clear``), every caustic object's vertex lies outside the slab (nearer
    than znear), so it does not hide the receiver; bowl_sun's bowl rests on its floor,
    and only its lowest vertices (3 %, within 1.2 mm of the floor) reach into the slab."""
    scene, _, read = _export(tmp_path, name)
    extras = read.nodes["receiver_0_camera"].extras["harness"]
    umin, umax, vmin, vmax = extras["extent"]
    width, height = extras["resolution"]
    mesh = read.mesh("receiver_0")
    u = umin + mesh["uv"][:, 0] * (umax - umin)
    v = vmin + mesh["uv"][:, 1] * (vmax - vmin)
    np.testing.assert_allclose(np.stack([u, v], 1), build_geometry(scene).receivers[0].mesh.uvs,
                               atol=1e-5 * (umax - umin))
    column, row, depth, ortho = _orthographic_pixels(read, 0, mesh["positions"])
    scale = max(width, height) * 1e-5
    np.testing.assert_allclose(column, (u - umin) / (umax - umin) * width, atol=scale)
    np.testing.assert_allclose(row, (vmax - v) / (vmax - vmin) * height, atol=scale)
    assert depth.min() > ortho.znear and depth.max() < ortho.zfar
    for i in range(len(scene.objects)):
        points = read.mesh(f"object_{i}")["positions"]
        _, _, object_depth, _ = _orthographic_pixels(read, 0, points)
        inside = object_depth >= ortho.znear
        if clear:
            assert not inside.any()
        else:
            assert 0 < inside.mean() < 0.05
    assert "pi * L / albedo" in extras["radiance_to_irradiance"]
    assert extras["albedo"] == list(scene.receivers[0].albedo)


def test_axes_are_stated_and_y_is_up(tmp_path):
    """asset.extras states the conversion; the receiver floor (scene z = 0, normal +z)
    lies at glTF y = 0 with its POSITION bounds spanning x and z."""
    _, _, read = _export(tmp_path, "glass_sphere")
    axes = read.gltf.asset.extras["harness"]["axes"]
    np.testing.assert_array_equal(axes["gltf_from_scene"], GLTF_FROM_SCENE)
    accessor = read.gltf.accessors[read.gltf.meshes[read.nodes["receiver_0"].mesh]
                                   .primitives[0].attributes.POSITION]
    assert accessor.min == [-4.0, 0.0, -4.0] and accessor.max == [4.0, 0.0, 4.0]
    assert sphere_chord_error(1.0, 5) < read.gltf.asset.extras["harness"]["tessellation"][
        "tolerance_m"]


def test_area_light_is_an_emissive_rectangle(tmp_path):
    """The rectangle's corners at centre +- half its sides, facing the normal (its faces
    wound counter-clockwise seen from below), radiance = intensity / area as emissive
    colour x strength (W m^-2 sr^-1)."""
    scene = area_light_scene()
    _, _, read = _export(tmp_path, "glass_sphere", scene=scene)
    mesh = read.mesh("light")
    p = mesh["positions"].astype(np.float64)
    np.testing.assert_allclose(p.mean(axis=0), scene.light.center, atol=1e-6)
    assert sorted(np.ptp(p, axis=0)) == pytest.approx([0.0, 0.25, 0.5], abs=1e-6)
    a, b, c = (p[mesh["faces"][:, k]] for k in range(3))
    facing = np.cross(b - a, c - a) @ np.asarray(scene.light.normal)
    assert np.all(facing > 0)
    material = mesh["material"]
    radiance = np.multiply(material.emissiveFactor, material.extensions[
        "KHR_materials_emissive_strength"]["emissiveStrength"])
    np.testing.assert_allclose(radiance, np.array([30.0, 20.0, 10.0]) / 0.125, rtol=1e-12)
    assert "KHR_lights_punctual" not in (read.gltf.extensions or {})
