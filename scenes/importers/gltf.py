"""glTF 2.0 (``.gltf``, ``.glb``) -> a scene :class:`~scenes.importers.draft.Draft`.

The mapping is ``docs/export.md`` read backwards, and ``docs/bring-your-scene.md`` for
files the harness did not write:

* axes: glTF +y up -> scene +z up, p_scene = Mᵀ p_glTF (:data:`GLTF_FROM_SCENE` = M);
* meshes with their nodes' world transforms; a material with
  ``KHR_materials_transmission`` is a dielectric (``KHR_materials_ior``, default 1.5;
  absorption σ_c = −ln(attenuationColor_c) / attenuationDistance from
  ``KHR_materials_volume``), metallic ≥ 0.9 with roughness ≤ 0.05 a conductor
  (reflectance = base colour), anything else diffuse: a rectangle is a plane receiver, a
  mesh facing up everywhere a mesh receiver, the rest occluders (diffuse objects);
* ``KHR_lights_punctual`` in the export's units (intensity read as W/sr, a directional
  light's as W/m²: 1 lm = 1 W), the camera named by ``camera``, else the first
  perspective camera.

Where the harness wrote the file, every node carries its scene table in
``extras.harness.table``; that table is taken as it is (the exact scene), unless the
node was moved since (its position or its triangles' bounding box disagree).
"""

from __future__ import annotations

import base64
import math
import re
from pathlib import Path

import numpy as np
import pygltflib as gl
from scipy.spatial.transform import Rotation

from scenes.export.frames import GLTF_FROM_SCENE
from scenes.importers.draft import Draft, ImportProblemError, MeshPart, Part
from scenes.importers.shapes import is_closed, is_height_field, mesh_problem, rectangle

__all__ = ["read_gltf"]

_COMPONENTS = {gl.BYTE: np.int8, gl.UNSIGNED_BYTE: np.uint8, gl.SHORT: np.int16,
               gl.UNSIGNED_SHORT: np.uint16, gl.UNSIGNED_INT: np.uint32, gl.FLOAT: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
#: Thresholds of the material classification (glTF's metallic-roughness model).
CONDUCTOR_METALLIC, SMOOTH_ROUGHNESS = 0.9, 0.05


def _to_scene(vectors) -> np.ndarray:
    return np.asarray(vectors, np.float64) @ GLTF_FROM_SCENE


class _File:
    """A parsed glTF file with its buffers, read accessors and node world matrices."""

    def __init__(self, path: Path):
        self.path = path
        try:
            self.gltf = gl.GLTF2.load(str(path))
        except Exception as error:  # pygltflib raises many types on malformed input
            raise ImportProblemError([f"{path}: not a readable glTF file "
                                      f"({type(error).__name__}: {error})"]) from None
        if self.gltf is None:
            raise ImportProblemError([f"{path}: not a readable glTF file"])
        self.buffers = [self._buffer(i, b) for i, b in enumerate(self.gltf.buffers)]

    def _buffer(self, index: int, buffer: gl.Buffer) -> bytes:
        where = f"{self.path}: buffers[{index}]"
        if buffer.uri is None:
            blob = self.gltf.binary_blob()
            if blob is None:
                raise ImportProblemError([f"{where}: no binary chunk (truncated .glb?)"])
        elif buffer.uri.startswith("data:"):
            blob = base64.b64decode(buffer.uri.partition(",")[2])
        else:
            file = self.path.parent / buffer.uri
            try:
                blob = file.read_bytes()
            except OSError as error:
                raise ImportProblemError([f"{where}: cannot read {buffer.uri!r}: "
                                          f"{error.strerror}"]) from None
        if len(blob) < buffer.byteLength:
            raise ImportProblemError([f"{where}: holds {len(blob)} bytes, the file says "
                                      f"{buffer.byteLength} (truncated?)"])
        return bytes(blob)

    def accessor(self, index: int) -> np.ndarray:
        accessor = self.gltf.accessors[index]
        view = self.gltf.bufferViews[accessor.bufferView]
        dtype = np.dtype(_COMPONENTS[accessor.componentType])
        width = _WIDTH[accessor.type]
        stride = view.byteStride or dtype.itemsize * width
        start = (view.byteOffset or 0) + (accessor.byteOffset or 0)
        blob = self.buffers[view.buffer]
        need = start + stride * (accessor.count - 1) + dtype.itemsize * width
        if need > len(blob):
            raise ImportProblemError([f"{self.path}: accessors[{index}] reaches past its "
                                      "buffer (truncated file?)"])
        rows = np.ndarray((accessor.count, width), dtype, blob, start, (stride, dtype.itemsize))
        return np.array(rows)

    def world_nodes(self):
        """(node index, world matrix in glTF coordinates) of every node of the scene."""
        gltf = self.gltf
        roots = gltf.scenes[gltf.scene or 0].nodes if gltf.scenes else range(len(gltf.nodes))
        stack = [(i, np.eye(4)) for i in reversed(list(roots))]
        while stack:
            index, parent = stack.pop()
            node = gltf.nodes[index]
            world = parent @ _local(node)
            yield index, world
            stack.extend((child, world) for child in reversed(node.children or []))


def _local(node: gl.Node) -> np.ndarray:
    if node.matrix:
        return np.asarray(node.matrix, np.float64).reshape(4, 4).T  # column-major
    matrix = np.eye(4)
    scale = np.asarray(node.scale or [1, 1, 1], np.float64)
    matrix[:3, :3] = Rotation.from_quat(node.rotation or [0, 0, 0, 1]).as_matrix() * scale
    matrix[:3, 3] = node.translation or [0, 0, 0]
    return matrix


def _harness(item) -> dict:
    extras = getattr(item, "extras", None) or {}
    value = extras.get("harness") if isinstance(extras, dict) else None
    return value if isinstance(value, dict) else {}


def _name(kind: str, index: int, item) -> str:
    return f"{kind} {item.name!r}" if getattr(item, "name", None) else f"{kind}s[{index}]"


def _rgb(values) -> list[float]:
    return [float(v) for v in list(values)[:3]]


def _material(file: _File, index: int | None, where: str, draft: Draft, approx: bool) -> dict:
    """The material's table (dielectric, conductor or diffuse), from extras where the
    harness wrote them."""
    if index is None:
        return {"type": "diffuse", "albedo": [1.0, 1.0, 1.0]}
    material = file.gltf.materials[index]
    where = f"{where}, material {_name('material', index, material)[9:]}"
    exact = _harness(material)
    if exact.get("type") in {"dielectric", "conductor", "diffuse"}:
        table = {k: v for k, v in exact.items() if k in {"type", "albedo", "reflectance",
                                                         "ior", "absorption", "fresnel"}}
        if isinstance(table.get("ior"), list) and len(set(table["ior"])) == 1:
            table["ior"] = table["ior"][0]
        return table
    ext = material.extensions or {}
    pbr = material.pbrMetallicRoughness or gl.PbrMetallicRoughness()
    base = _rgb(pbr.baseColorFactor or [1, 1, 1, 1])
    metallic = 1.0 if pbr.metallicFactor is None else pbr.metallicFactor
    roughness = 1.0 if pbr.roughnessFactor is None else pbr.roughnessFactor
    textures = [name for name, value in (("baseColorTexture", pbr.baseColorTexture),
                                         ("metallicRoughnessTexture",
                                          pbr.metallicRoughnessTexture)) if value is not None]
    if textures:
        draft.approximate(approx, where, f"textured ({', '.join(textures)}): the scene "
                          "model's materials are uniform", "its factors are used")
    transmission = ext.get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0)
    if transmission > 0:
        if roughness > SMOOTH_ROUGHNESS:
            draft.approximate(approx, where, f"a rough dielectric (roughness {roughness:g}): "
                              "the scene model's dielectrics are smooth", "read as smooth")
        ior = float(ext.get("KHR_materials_ior", {}).get("ior", 1.5))
        table = {"type": "dielectric", "ior": ior, "fresnel": True}
        volume = ext.get("KHR_materials_volume", {})
        distance = volume.get("attenuationDistance")
        if distance is not None and math.isfinite(distance) and distance > 0:
            colour = np.clip(np.asarray(volume.get("attenuationColor", [1, 1, 1]), float),
                             1e-30, 1.0)
            table["absorption"] = (-np.log(colour) / distance).tolist()
        if "KHR_materials_dispersion" in ext:
            draft.approximate(approx, where, "KHR_materials_dispersion without the "
                              "harness's per-channel IORs", f"one IOR {ior:g} for all channels")
        return table
    if metallic >= CONDUCTOR_METALLIC:
        if roughness > SMOOTH_ROUGHNESS:
            draft.approximate(approx, where, f"a rough conductor (roughness {roughness:g}): "
                              "the scene model's conductors are mirrors", "read as a mirror")
        return {"type": "conductor", "reflectance": base}
    return {"type": "diffuse", "albedo": [min(1.0, max(0.0, v)) for v in base]}


def _triangles(file: _File, mesh_index: int, world: np.ndarray, where: str
               ) -> list[tuple[np.ndarray, np.ndarray, int | None]]:
    """(positions in scene coordinates, faces, material, normals or None) per primitive."""
    out = []
    linear = world[:3, :3]
    flip = np.linalg.det(linear) < 0  # a mirroring transform turns the winding over
    for k, primitive in enumerate(file.gltf.meshes[mesh_index].primitives):
        if primitive.mode not in (None, gl.TRIANGLES):
            raise ImportProblemError([f"{file.path}: {where}, primitive {k}: mode "
                                      f"{primitive.mode} is not triangles"])
        if primitive.attributes.POSITION is None:
            raise ImportProblemError([f"{file.path}: {where}, primitive {k}: no POSITION"])
        local = file.accessor(primitive.attributes.POSITION).astype(np.float64)
        count = len(local)
        faces = (file.accessor(primitive.indices).reshape(-1) if primitive.indices is not None
                 else np.arange(count)).astype(np.int64)
        if len(faces) % 3:
            raise ImportProblemError([f"{file.path}: {where}, primitive {k}: "
                                      f"{len(faces)} indices is not a whole number of "
                                      "triangles"])
        faces = faces.reshape(-1, 3)
        if flip:
            faces = faces[:, ::-1]
        positions = _to_scene(local @ linear.T + world[:3, 3])
        normals = None
        if primitive.attributes.NORMAL is not None:
            # Normals transform by the inverse transpose of the node's linear part.
            normals = file.accessor(primitive.attributes.NORMAL).astype(np.float64)
            normals = _to_scene(normals @ np.linalg.inv(linear))
            normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
        out.append((positions, faces, primitive.material, normals))
    return out


def _vector(world: np.ndarray, column: int, sign: float = 1.0) -> list[float]:
    direction = sign * world[:3, column]
    return _to_scene(direction / np.linalg.norm(direction)).tolist()


def _position(world: np.ndarray) -> np.ndarray:
    return _to_scene(world[:3, 3])


def _agrees(table_point, node_point) -> bool:
    a, b = np.asarray(table_point, float), np.asarray(node_point, float)
    return bool(np.linalg.norm(a - b) <= 1e-6 * max(1.0, np.linalg.norm(a)))


def _light(file: _File, draft: Draft, approx: bool, name: str, light: dict,  # noqa: PLR0917
           world: np.ndarray, node: gl.Node) -> None:
    exact = _harness(node).get("table")
    position = _position(world)
    if isinstance(exact, dict) and ("position" not in exact or _agrees(exact["position"],
                                                                        position)):
        draft.lights.append(Part(exact, f"glTF node {name} (exact values from extras)"))
        return
    kind = light.get("type")
    power = (np.asarray(light.get("color", [1, 1, 1]), float)
             * float(light.get("intensity", 1.0))).tolist()
    if light.get("range") is not None:
        if not draft.approximate(approx, f"node {name}", "a light with a range: the "
                                 "harness's lights reach everywhere", "the range is ignored"):
            return
    if kind == "point":
        table = {"type": "point", "position": position.tolist(), "intensity": power}
    elif kind == "directional":
        table = {"type": "directional", "direction": _vector(world, 2, -1.0),
                 "irradiance": power}
    elif kind == "spot":
        spot = light.get("spot", {})
        outer = math.degrees(spot.get("outerConeAngle", math.pi / 4))
        inner = math.degrees(spot.get("innerConeAngle", 0.0))
        if outer >= 90:
            if not draft.approximate(approx, f"node {name}", f"a cone of {outer:g}°: the "
                                     "harness's spot lights are narrower than 90°",
                                     "cut to 89.9°"):
                return
            outer = 89.9
        table = {"type": "spot", "position": position.tolist(),
                 "direction": _vector(world, 2, -1.0), "intensity": power,
                 "cutoff_angle": outer, "beam_width": max(min(inner, outer), 1e-3 * outer)}
    else:
        draft.refuse(f"node {name}", f"light type {kind!r} is not point, spot or directional")
        return
    draft.lights.append(Part(table, f"glTF node {name} (KHR_lights_punctual {kind}; "
                             "intensity read as W/sr, directional as W/m²)"))


def _camera(file: _File, draft: Draft, approx: bool, cameras, wanted: str | None,  # noqa: PLR0917
            centre: np.ndarray) -> None:
    if wanted is not None:
        cameras = [c for c in cameras if c[0] == repr(wanted)]
        if not cameras:
            draft.refuse("camera", f"no camera node named {wanted!r}")
            return
    perspective = [c for c in cameras if file.gltf.cameras[c[1]].type == "perspective"]
    if not perspective:
        if cameras:
            draft.refuse(f"node {cameras[0][0]}", "an orthographic camera: the scene model's "
                         "camera is a pinhole")
        return
    name, index, world, node = perspective[0]
    position = _position(world)
    exact = _harness(node).get("table")
    if isinstance(exact, dict) and _agrees(exact.get("position", []), position):
        draft.camera = Part(exact, f"glTF node {name} (exact values from extras)")
        return
    camera = file.gltf.cameras[index].perspective
    forward = np.asarray(_vector(world, 2, -1.0))
    distance = float(np.dot(centre - position, forward))
    look_at = position + forward * (distance if distance > 0 else 1.0)
    height = 512
    width = max(1, round(height * camera.aspectRatio)) if camera.aspectRatio else height
    table = {"position": position.tolist(), "look_at": look_at.tolist(),
             "up": _vector(world, 1), "fov": math.degrees(camera.yfov), "fov_axis": "y",
             "resolution": [width, height]}
    draft.camera = Part(table, f"glTF node {name} (perspective camera; {width} x {height} "
                        "pixels from its aspect ratio)")


def _emissive(file: _File, material: int | None) -> bool:
    if material is None:
        return False
    m = file.gltf.materials[material]
    return any(v > 0 for v in (m.emissiveFactor or [0, 0, 0]))


def _shape(file, draft, approx, name, node, world) -> None:  # noqa: PLR0917
    """One mesh node: an exact table from extras, else classified by its material and
    triangles."""
    harness = _harness(node)
    where = f"node {name}"
    parts = _triangles(file, node.mesh, world, where)
    positions = np.concatenate([p for p, *_ in parts])
    offsets = np.cumsum([0] + [len(p) for p, *_ in parts[:-1]])
    faces = np.concatenate([f + o for (_, f, *_), o in zip(parts, offsets, strict=True)])
    problem = mesh_problem(positions, faces)
    if problem:
        draft.refuse(where, f"the mesh {problem}")
        return
    role, table = harness.get("role"), harness.get("table")
    if role in {"receiver", "object"} and isinstance(table, dict) and _usable(table):
        # The triangles' reading is kept in reserve (and its problems forgotten): it is
        # written only if the table does not reproduce the triangles.
        marks = len(draft.problems), len(draft.approximations)
        fallback = _fallback(file, draft, approx, name, parts, positions, faces)
        del draft.problems[marks[0]:], draft.approximations[marks[1]:]
        part = Part(table, f"glTF node {name} (exact {harness.get('kind')} from extras)",
                    fallback=fallback,
                    bounds=np.stack([positions.min(axis=0), positions.max(axis=0)]))
        (draft.receivers if role == "receiver" else draft.objects).append(part)
        return
    draft_part = _fallback(file, draft, approx, name, parts, positions, faces)
    if draft_part is not None:
        section, part = draft_part
        getattr(draft, section).append(part)


def _usable(table: dict) -> bool:
    """A scene table names every file it needs (the export drops a machine's paths)."""
    kind = table.get("type")
    if kind == "mesh" and "file" not in table:
        return False
    height = table.get("height")
    return not (isinstance(height, dict) and height.get("type") == "file"
                and "file" not in height)


def _fallback(file, draft, approx, name, parts, positions, faces):  # noqa: PLR0917
    """("receivers" | "objects", Part) from the triangles and the material alone."""
    where = f"node {name}"
    materials = {part[2] for part in parts}
    if len(materials) > 1:
        draft.approximate(approx, where, "primitives with different materials: one "
                          "material per shape", "the first primitive's material is used")
    material = _material(file, parts[0][2], where, draft, approx)
    slug = re.sub(r"[^A-Za-z0-9_-]+", "_", name.strip("'")) or "mesh"
    normals = None
    if all(part[3] is not None for part in parts):
        normals = np.concatenate([part[3] for part in parts])
    mesh = MeshPart(f"{len(draft.receivers) + len(draft.objects)}_{slug}", positions, faces,
                    normals)
    origin = f"glTF node {name} (mesh, material {material['type']})"
    closed = is_closed(positions, faces)
    if material["type"] == "diffuse":
        plane = rectangle(positions, faces)
        if plane is not None:
            return "receivers", Part({**plane, "albedo": material["albedo"]},
                                     origin.replace("(mesh", "(rectangle"))
        if is_height_field(positions, faces):
            return "receivers", Part({"type": "mesh", "albedo": material["albedo"]},
                                     origin + " as a height-field receiver", mesh)
        return "objects", Part({"type": "mesh", "material": material},
                               origin + " as an occluder", mesh)
    if material["type"] == "dielectric" and not closed:
        draft.refuse(where, "an open (non-manifold or not watertight) dielectric mesh: a "
                     "dielectric must close a volume")
        return None
    return "objects", Part({"type": "mesh", "material": material}, origin, mesh)


def _area(file, draft, approx, where, harness, positions, faces, material) -> None:  # noqa: PLR0917
    exact = harness.get("table")
    if isinstance(exact, dict) and exact.get("type") == "area":
        draft.lights.append(Part(exact, f"glTF {where} (the harness's area light, exact "
                                 "from extras)"))
        return
    area = float(np.linalg.norm(np.cross(positions[faces[:, 1]] - positions[faces[:, 0]],
                                         positions[faces[:, 2]] - positions[faces[:, 0]]),
                                axis=1).sum() / 2)
    m = file.gltf.materials[material]
    strength = (m.extensions or {}).get("KHR_materials_emissive_strength", {}).get(
        "emissiveStrength", 1.0)
    radiance = [float(v) * strength for v in m.emissiveFactor]
    draft.area_light(approx, where, positions.mean(axis=0), radiance, area)


def read_gltf(path: str | Path, *, approximate: bool = False, camera: str | None = None
              ) -> Draft:
    """Read a ``.gltf`` or ``.glb`` into a :class:`Draft` (not yet checked or written).

    Parameters
    ----------
    approximate
        Replace what the scene model cannot hold by a stated approximation instead of
        refusing it.
    camera
        Name of the camera node to use; default the first perspective camera.

    Raises
    ------
    ImportProblemError
        The file cannot be read (one line naming the file and why).
    """
    path = Path(path)
    file = _File(path)
    asset = _harness(file.gltf.asset)
    tables = asset.get("tables") if isinstance(asset.get("tables"), dict) else {}
    name = re.sub(r"[^A-Za-z0-9_-]+", "_", str(asset.get("scene") or path.stem))
    draft = Draft(source=str(path), name=name, info=dict(tables.get("scene") or {}),
                  settings=dict(tables.get("settings") or {}))
    cameras, points = [], []
    punctual = (file.gltf.extensions or {}).get("KHR_lights_punctual", {}).get("lights", [])
    nodes = list(file.world_nodes())
    for index, world in nodes:
        node = file.gltf.nodes[index]
        name = _name("node", index, node)[5:]
        if node.mesh is not None and _harness(node).get("role") is None and (
                _harness(node).get("type") == "area" or any(
                    _emissive(file, p.material) for p in file.gltf.meshes[node.mesh].primitives)):
            parts = _triangles(file, node.mesh, world, f"node {name}")
            positions = np.concatenate([p for p, *_ in parts])
            offsets = np.cumsum([0] + [len(p) for p, *_ in parts[:-1]])
            faces = np.concatenate([f + o for (_, f, *_), o in zip(parts, offsets, strict=True)])
            _area(file, draft, approximate, f"node {name}", _harness(node), positions, faces,
                  parts[0][2])
        elif node.mesh is not None:
            _shape(file, draft, approximate, name, node, world)
            points.append(world[:3, 3])
        light = (node.extensions or {}).get("KHR_lights_punctual", {}).get("light")
        if light is not None:
            if not 0 <= light < len(punctual):
                draft.refuse(f"node {name}", f"names light {light}, the file has "
                             f"{len(punctual)}")
            else:
                _light(file, draft, approximate, name, punctual[light], world, node)
        if node.camera is not None:
            cameras.append((name, node.camera, world, node))
    centre = _to_scene(np.mean(points, axis=0)) if points else np.zeros(3)
    _camera(file, draft, approximate, cameras, camera, centre)
    draft.choose_light(approximate)
    return draft
