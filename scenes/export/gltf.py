"""Scene -> glTF 2.0 (``.glb``, or ``.gltf`` with a ``.bin`` beside it), for renderers
outside the process (a browser, a game engine).

The mapping, both ways, with its units and its gaps, is the table of ``docs/export.md``;
in short:

* every receiver and caustic object is one node with one mesh (POSITION, NORMAL: the
  shading normals both renderers use; receivers also TEXCOORD_0, their (u, v) scaled to
  [0, 1] over the map's extent, t = 0 at vmin = the map's row 0), in glTF coordinates
  (:mod:`scenes.export.frames`), analytic shapes within the chord tolerance
  (:mod:`scenes.export.tessellation`); receivers are one-sided (the harness counts
  light on their front side only), open objects two-sided;
* diffuse (receivers, diffuse objects): base colour = albedo, metallic 0, roughness 1;
  dielectric: ``KHR_materials_transmission`` (1), ``KHR_materials_ior`` (the IOR, the
  green channel's when it has one per channel), ``KHR_materials_volume`` on closed
  objects (thickness: the smallest side of the object's bounding box; attenuation from
  the absorption), ``KHR_materials_dispersion`` for per-channel IORs; conductor:
  metallic 1, roughness 0, base colour = reflectance;
* point, spot and directional lights: ``KHR_lights_punctual`` in the harness's
  radiometric units (W/sr, W/m^2; see :data:`UNITS`); an area light, which has no
  punctual equivalent, is an emissive rectangle (``KHR_materials_emissive_strength``);
* the scene camera: a perspective camera; each receiver: an orthographic camera whose
  image maps onto its irradiance map (:class:`~scenes.export.frames.ReceiverFrame`).

Every node, material and light carries ``extras.harness``: the scene's exact values
(frame-free numbers such as IORs per channel, absorption, the Fresnel switch, a spot's
falloff; vectors in glTF coordinates) where an extension holds only an approximation,
so that a scene read back from the file keeps the values the harness renders with (the
exceptions, such as the renderer settings, are listed in ``docs/export.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import numpy as np
import pygltflib as gl

from scenes.camera import half_fov_tangents
from scenes.export.frames import (
    GLTF_FROM_SCENE,
    ReceiverFrame,
    any_up,
    look_rotation,
    quaternion,
    receiver_frame,
    to_gltf,
)
from scenes.export.tessellation import DEFAULT_RELATIVE_TOLERANCE, Tessellation, tessellate
from scenes.files import atomic_write_bytes
from scenes.geometry import TriangleMesh
from scenes.geometry.mesh import make_mesh
from scenes.model import (
    AreaLight,
    ConductorMaterial,
    DielectricMaterial,
    DiffuseMaterial,
    DirectionalLight,
    PointLight,
    Scene,
    SpotLight,
)
from scenes.tables import portable_table, to_table

__all__ = ["HARD_EDGE", "UNITS", "GltfExport", "export_gltf"]

#: The unit convention, written into ``asset.extras.units``. glTF's punctual lights are
#: photometric (cd, lx); the harness is radiometric, and its numbers go into the same
#: fields unconverted: read 1 lm as 1 W.
UNITS = {
    "length": "m",
    "point_spot_intensity": "W/sr (written where KHR_lights_punctual expects cd)",
    "directional_intensity": "W/m^2 irradiance perpendicular to the rays (where "
                             "KHR_lights_punctual expects lx)",
    "emissive_strength": "W m^-2 sr^-1 radiance (area lights)",
    "radiance": "W m^-2 sr^-1: a renderer's linear output, no tone mapping, no exposure",
    "irradiance": "W/m^2",
    "absorption": "1/m (Beer-Lambert exp(-sigma d))",
    "angles": "rad in glTF fields, deg where extras say _deg",
    "photometric_reading": "1 W = 1 lm: a renderer that takes cd and lx renders radiance in "
                           "W m^-2 sr^-1 when it takes these numbers as they are",
}
#: A spot light with a hard edge (beam width = cutoff) gets innerConeAngle = outer -
#: HARD_EDGE rad: glTF requires inner < outer.
HARD_EDGE = 1e-6

_FLOAT, _UINT = gl.FLOAT, gl.UNSIGNED_INT


@dataclass(frozen=True)
class GltfExport:
    """What :func:`export_gltf` wrote.

    Attributes
    ----------
    path : Path
        The ``.glb`` or ``.gltf`` file (a ``.gltf``'s buffer is ``<stem>.bin`` beside it).
    tolerance : float
        The chord tolerance used, m.
    receivers, objects : tuple of Tessellation
        How each receiver's and object's triangles were made.
    frames : tuple of ReceiverFrame
        Each receiver's orthographic frame (scene coordinates).
    """

    path: Path
    tolerance: float
    receivers: tuple[Tessellation, ...]
    objects: tuple[Tessellation, ...]
    frames: tuple[ReceiverFrame, ...]


class _Buffer:
    """One binary buffer and the accessors into it (float32 and uint32 only, so every
    view starts 4-byte aligned)."""

    def __init__(self, gltf: gl.GLTF2):
        self.gltf = gltf
        self.blob = bytearray()

    def add(self, array: np.ndarray, kind: str, *, target: int | None,
            bounds: bool = False) -> int:
        data = np.ascontiguousarray(array, np.uint32 if kind == "SCALAR" else np.float32)
        view = gl.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=data.nbytes,
                             target=target)
        self.blob += data.tobytes()
        self.gltf.bufferViews.append(view)
        flat = data.reshape(len(data), -1)
        accessor = gl.Accessor(
            bufferView=len(self.gltf.bufferViews) - 1, count=len(data),
            componentType=_UINT if kind == "SCALAR" else _FLOAT, type=kind,
            min=flat.min(axis=0).tolist() if bounds else None,
            max=flat.max(axis=0).tolist() if bounds else None,
        )
        self.gltf.accessors.append(accessor)
        return len(self.gltf.accessors) - 1


def _vec(v) -> list[float]:
    return [float(x) for x in np.asarray(v, np.float64).ravel()]


def _color_and_strength(rgb) -> tuple[list[float], float]:
    """(colour with its largest channel 1, that channel's value): rgb = strength x colour."""
    rgb = np.asarray(rgb, np.float64)
    strength = float(rgb.max())
    return _vec(rgb / strength if strength > 0 else rgb), strength


def _dispersion(iors) -> float:
    """glTF's dispersion 20 / V of per-channel IORs, reading the channels as the Fraunhofer
    lines C (red), d (green) and F (blue): V = (n_d - 1) / (n_F - n_C); 0 where blue
    does not exceed red (the exact IORs stay in extras)."""
    red, green, blue = iors
    return max(0.0, 20.0 * (blue - red) / (green - 1.0)) if green > 1 else 0.0


def _material(material, *, name: str, closed: bool, thickness: float,
              double_sided: bool) -> gl.Material:
    harness: dict = {"type": material.kind}
    extensions: dict = {}
    pbr = gl.PbrMetallicRoughness(baseColorFactor=[1.0, 1.0, 1.0, 1.0], metallicFactor=0.0,
                                  roughnessFactor=1.0)
    if isinstance(material, DiffuseMaterial):
        pbr.baseColorFactor = [*_vec(material.albedo), 1.0]
        harness["albedo"] = _vec(material.albedo)
    elif isinstance(material, ConductorMaterial):
        pbr.baseColorFactor = [*_vec(material.reflectance), 1.0]
        pbr.metallicFactor, pbr.roughnessFactor = 1.0, 0.0
        harness["reflectance"] = _vec(material.reflectance)
    elif isinstance(material, DielectricMaterial):
        pbr.roughnessFactor = 0.0
        iors = material.iors
        harness.update(ior=_vec(iors), absorption=_vec(material.absorption),
                       fresnel=bool(material.fresnel))
        extensions["KHR_materials_transmission"] = {"transmissionFactor": 1.0}
        extensions["KHR_materials_ior"] = {"ior": float(iors[1])}
        sigma = np.asarray(material.absorption, np.float64)
        if closed:
            volume: dict = {"thicknessFactor": float(thickness)}
            if sigma.max() > 0:
                # attenuationColor^(d / distance) = exp(-sigma d) per channel, with the
                # distance 1 / max(sigma): colour = exp(-sigma / max(sigma)).
                volume["attenuationDistance"] = float(1.0 / sigma.max())
                volume["attenuationColor"] = _vec(np.exp(-sigma / sigma.max()))
            extensions["KHR_materials_volume"] = volume
            if len(set(iors)) > 1:
                extensions["KHR_materials_dispersion"] = {"dispersion": _dispersion(iors)}
    else:
        raise TypeError(f"unknown material {material!r}")
    return gl.Material(name=name, pbrMetallicRoughness=pbr, doubleSided=double_sided,
                       extensions=extensions, extras={"harness": harness})


def _mesh_node(gltf, buffer: _Buffer, mesh: TriangleMesh, *, name: str, material: int,
               uvs: np.ndarray | None, extras: dict) -> int:
    attributes = gl.Attributes(
        POSITION=buffer.add(to_gltf(mesh.positions), "VEC3", target=gl.ARRAY_BUFFER,
                            bounds=True),
        NORMAL=buffer.add(to_gltf(mesh.normals), "VEC3", target=gl.ARRAY_BUFFER),
    )
    if uvs is not None:
        attributes.TEXCOORD_0 = buffer.add(uvs, "VEC2", target=gl.ARRAY_BUFFER)
    indices = buffer.add(np.asarray(mesh.faces).ravel(), "SCALAR",
                         target=gl.ELEMENT_ARRAY_BUFFER)
    primitive = gl.Primitive(attributes=attributes, indices=indices, material=material,
                             mode=gl.TRIANGLES)
    gltf.meshes.append(gl.Mesh(name=name, primitives=[primitive]))
    gltf.nodes.append(gl.Node(name=name, mesh=len(gltf.meshes) - 1, extras=extras))
    return len(gltf.nodes) - 1


def _add(items: list, item) -> int:
    items.append(item)
    return len(items) - 1


def _light(gltf, buffer: _Buffer, light) -> int:
    """The light's node (a punctual light, or an area light's emissive rectangle)."""
    if isinstance(light, AreaLight):
        return _area_light(gltf, buffer, light)
    harness: dict = {"type": light.kind}
    node = gl.Node(name="light")
    if isinstance(light, DirectionalLight):
        color, strength = _color_and_strength(light.irradiance)
        punctual = {"type": "directional", "color": color, "intensity": strength}
        harness["irradiance"] = _vec(light.irradiance)
    else:
        color, strength = _color_and_strength(light.intensity)
        punctual = {"type": light.kind, "color": color, "intensity": strength}
        harness["intensity"] = _vec(light.intensity)
        node.translation = _vec(to_gltf(light.position))
    if isinstance(light, SpotLight):
        beam = light.cutoff_angle if light.beam_width is None else light.beam_width
        outer = math.radians(light.cutoff_angle)
        punctual["spot"] = {"innerConeAngle": min(math.radians(beam), outer - HARD_EDGE),
                            "outerConeAngle": outer}
        harness.update(cutoff_angle_deg=float(light.cutoff_angle), beam_width_deg=float(beam),
                       falloff="full intensity within beam_width, then linear in the angle "
                       "to 0 at cutoff_angle")
    if isinstance(light, SpotLight | DirectionalLight):
        direction = to_gltf(light.direction)
        harness["direction"] = _vec(direction / np.linalg.norm(direction))
        node.rotation = quaternion(look_rotation(direction, any_up(direction)))
    elif not isinstance(light, PointLight):
        raise TypeError(f"unknown light {light!r}")
    lights = gltf.extensions.setdefault("KHR_lights_punctual", {"lights": []})["lights"]
    index = _add(lights, {"name": "light", **punctual})
    node.extensions = {"KHR_lights_punctual": {"light": index}}
    node.extras = {"harness": {**harness, "table": to_table(light)}}
    return _add(gltf.nodes, node)


def _area_light(gltf, buffer: _Buffer, light: AreaLight) -> int:
    """An emitting rectangle, one-sided along its normal; radiance = intensity / area.
    Its first side runs along normal x helper (helper +x, or +y when the normal is near
    x): the frame both renderers give an area light."""
    n = np.asarray(light.normal, np.float64) / np.linalg.norm(light.normal)
    helper = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = np.cross(n, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * np.asarray(light.size) / 2
    positions = np.asarray(light.center) + corners[:, :1] * e1 + corners[:, 1:] * e2
    mesh = make_mesh(positions, np.tile(n, (4, 1)), [[0, 1, 2], [0, 2, 3]])
    radiance = np.asarray(light.intensity, np.float64) / (light.size[0] * light.size[1])
    color, strength = _color_and_strength(radiance)
    material = gl.Material(
        name="light", emissiveFactor=color, doubleSided=False,
        pbrMetallicRoughness=gl.PbrMetallicRoughness(baseColorFactor=[0.0, 0.0, 0.0, 1.0],
                                                     metallicFactor=0.0),
        extensions={"KHR_materials_emissive_strength": {"emissiveStrength": strength}})
    extras = {"harness": {"type": "area", "intensity": _vec(light.intensity),
                          "radiance": _vec(radiance), "size": _vec(light.size),
                          "normal": _vec(to_gltf(n)), "samples": int(light.samples),
                          "table": to_table(light)}}
    return _mesh_node(gltf, buffer, mesh, name="light", material=_add(gltf.materials, material),
                      uvs=None, extras=extras)


def _scene_camera(gltf, scene: Scene) -> int:
    camera = scene.camera
    width, height = camera.resolution
    eye, target = to_gltf(camera.position), to_gltf(camera.look_at)
    up = to_gltf(camera.up)
    _, tan_y = half_fov_tangents(camera)
    distance = float(np.linalg.norm(target - eye))
    perspective = gl.Perspective(yfov=2 * math.atan(tan_y), aspectRatio=width / height,
                                 znear=1e-3 * distance)
    index = _add(gltf.cameras, gl.Camera(name="camera", type="perspective",
                                         perspective=perspective))
    extras = {"harness": {"look_at": _vec(target), "up": _vec(up), "fov_deg": camera.fov,
                          "fov_axis": camera.fov_axis, "resolution": [width, height],
                          "table": to_table(camera)}}
    return _add(gltf.nodes, gl.Node(name="camera", camera=index, translation=_vec(eye),
                                    rotation=quaternion(look_rotation(target - eye, up)),
                                    extras=extras))


def _frame_extras(frame: ReceiverFrame, *, index: int, projected: bool, albedo) -> dict:
    umin, umax, vmin, vmax = frame.extent
    width, height = frame.resolution
    return {"harness": {
        "receiver": index,
        "origin": _vec(to_gltf(frame.origin)),
        "u_axis": _vec(to_gltf(frame.u_axis)), "v_axis": _vec(to_gltf(frame.v_axis)),
        "normal": _vec(to_gltf(frame.normal)),
        "extent": list(frame.extent), "resolution": [width, height],
        "uv_is_projection": projected,
        "image_to_map": (
            "render W x H = resolution; pixel (row i from the top, column j) has its centre "
            f"at u = {umin!r} + (j + 0.5) * {(umax - umin) / width!r}, "
            f"v = {vmax!r} - (i + 0.5) * {(vmax - vmin) / height!r} and is the map's texel "
            "(row H - 1 - i, column j), the map's row 0 being at vmin: map = image "
            "flipped upside down"),
        "radiance_to_irradiance": (
            "E = pi * L / albedo per channel (Lambertian receiver); the compared map holds "
            "caustic irradiance only (light that reached the receiver through the caustic "
            "objects), so L must exclude the receiver's direct light"),
        "albedo": _vec(albedo),
    }}


def _receiver_camera(gltf, frame: ReceiverFrame, index: int, *, projected: bool,
                     albedo) -> int:
    xmag, ymag = frame.half_size
    camera = gl.Camera(name=f"receiver_{index}_camera", type="orthographic",
                       orthographic=gl.Orthographic(xmag=xmag, ymag=ymag, znear=frame.znear,
                                                    zfar=frame.zfar))
    rotation = np.stack([to_gltf(frame.u_axis), to_gltf(frame.v_axis), to_gltf(frame.normal)],
                        axis=1)
    return _add(gltf.nodes, gl.Node(
        name=f"receiver_{index}_camera", camera=_add(gltf.cameras, camera),
        translation=_vec(to_gltf(frame.eye)), rotation=quaternion(rotation),
        extras=_frame_extras(frame, index=index, projected=projected, albedo=albedo)))


def _normalised_uvs(mesh: TriangleMesh, extent) -> np.ndarray:
    umin, umax, vmin, vmax = extent
    uv = mesh.uvs.astype(np.float64)
    return np.stack([(uv[:, 0] - umin) / (umax - umin), (uv[:, 1] - vmin) / (vmax - vmin)], 1)


def _asset_extras(scene: Scene, tolerance: float, given: bool, receivers, objects) -> dict:
    return {"harness": {
        "scene": scene.name,
        # The scene-wide tables the nodes cannot hold (scene coordinates), so that an
        # import gives back the same scene: [scene] and [settings].
        "tables": {"scene": to_table(scene.info), "settings": to_table(scene.settings)},
        "units": UNITS,
        "axes": {"scene_up": "+z", "gltf_up": "+y", "gltf_from_scene":
                 GLTF_FROM_SCENE.tolist(), "rule": "(x, y, z) scene -> (x, z, -y) glTF"},
        "tessellation": {
            "tolerance_m": tolerance,
            "chosen_by": "given" if given else f"default: {DEFAULT_RELATIVE_TOLERANCE:g} x the "
                         "diagonal of the scene geometry's bounding box",
            "meaning": "largest distance of an analytic shape's triangles from its surface; "
                       "never coarser than the scene's own tessellation",
            "receivers": [vars(t) for t in receivers],
            "objects": [vars(t) for t in objects],
        },
        "effects_note": "KHR extensions approximate the harness's materials (Fresnel always "
                        "on, one IOR plus an Abbe number, Schlick conductors); the exact "
                        "values are in each material's and light's extras.harness",
    }}


def export_gltf(scene: Scene, path: str | Path, *, tolerance: float | None = None
                ) -> GltfExport:
    """Write ``scene`` as glTF 2.0.

    Parameters
    ----------
    scene : Scene
    path : str or Path
        ``.glb`` (one binary file) or ``.gltf`` (JSON, with ``<stem>.bin`` beside it).
    tolerance : float, optional
        Largest chord error of analytic shapes, m; default 1e-4 of the diagonal of the
        scene geometry's bounding box (:func:`~scenes.export.tessellation.tessellate`).

    Raises
    ------
    SceneError
        A shape cannot meet the tolerance, or the geometry cannot be built.
    ValueError
        ``path`` ends in neither ``.glb`` nor ``.gltf``.
    """
    path = Path(path)
    if path.suffix not in (".glb", ".gltf"):
        raise ValueError(f"{path}: a glTF file ends in .glb or .gltf")
    geometry, used, receivers, objects = tessellate(scene, tolerance=tolerance)
    gltf = gl.GLTF2(asset=gl.Asset(version="2.0", generator=_generator()))
    gltf.extensions = {}
    buffer = _Buffer(gltf)
    roots, frames = [], []
    for i, (rec, built) in enumerate(zip(scene.receivers, geometry.receivers, strict=True)):
        material = _add(gltf.materials, _material(DiffuseMaterial(albedo=rec.albedo),
                                                  name=f"receiver_{i}", closed=False,
                                                  thickness=0.0, double_sided=False))
        extras = {"harness": {"role": "receiver", "index": i, "kind": rec.kind,
                              "tessellation": vars(receivers[i]),
                              "table": portable_table(to_table(rec))}}
        roots.append(_mesh_node(gltf, buffer, built.mesh, name=f"receiver_{i}",
                                material=material, uvs=_normalised_uvs(built.mesh, built.extent),
                                extras=extras))
        frame, projected = receiver_frame(rec, built, scene.settings.receiver_map)
        frames.append(frame)
        roots.append(_receiver_camera(gltf, frame, i, projected=projected, albedo=rec.albedo))
    for i, (obj, built) in enumerate(zip(scene.objects, geometry.objects, strict=True)):
        mesh = built.mesh
        thickness = float(np.ptp(mesh.positions.astype(np.float64), axis=0).min())
        material = _add(gltf.materials, _material(obj.material, name=f"object_{i}",
                                                  closed=mesh.closed, thickness=thickness,
                                                  double_sided=not mesh.closed))
        extras = {"harness": {"role": "object", "index": i, "kind": obj.kind,
                              "closed": bool(mesh.closed), "tessellation": vars(objects[i]),
                              "table": portable_table(to_table(obj))}}
        roots.append(_mesh_node(gltf, buffer, mesh, name=f"object_{i}", material=material,
                                uvs=None, extras=extras))
    roots.append(_light(gltf, buffer, scene.light))
    roots.append(_scene_camera(gltf, scene))
    gltf.scenes = [gl.Scene(name=scene.name, nodes=roots)]
    gltf.scene = 0
    gltf.asset.extras = _asset_extras(scene, used, tolerance is not None, receivers, objects)
    gltf.extensionsUsed = sorted({*gltf.extensions,
                                  *(k for m in gltf.materials for k in m.extensions)})
    _write(gltf, bytes(buffer.blob), path)
    return GltfExport(path, used, receivers, objects, tuple(frames))


def _generator() -> str:
    try:
        return f"caustics-harness {metadata.version('caustics-harness')}"
    except metadata.PackageNotFoundError:
        return "caustics-harness"


def _write(gltf: gl.GLTF2, blob: bytes, path: Path) -> None:
    """The file, written atomically (a ``.gltf``'s buffer first)."""
    if path.suffix == ".glb":
        gltf.buffers = [gl.Buffer(byteLength=len(blob))]
        gltf.set_binary_blob(blob)
        atomic_write_bytes(path, b"".join(gltf.save_to_bytes()))
        return
    binary = path.with_suffix(".bin")
    gltf.buffers = [gl.Buffer(byteLength=len(blob), uri=binary.name)]
    atomic_write_bytes(binary, blob)
    atomic_write_bytes(path, gltf.gltf_to_json().encode("utf-8"))
