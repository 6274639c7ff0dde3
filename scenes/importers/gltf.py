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
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pygltflib as gl
from scipy.spatial.transform import Rotation

from scenes.export.frames import GLTF_FROM_SCENE
from scenes.importers.draft import Draft, ImportProblemError, MeshPart, Part, usable
from scenes.importers.shapes import (
    icosphere,
    is_closed,
    is_height_field,
    mesh_problem,
    rectangle,
)

__all__ = ["read_gltf"]

_COMPONENTS = {gl.BYTE: np.int8, gl.UNSIGNED_BYTE: np.uint8, gl.SHORT: np.int16,
               gl.UNSIGNED_SHORT: np.uint16, gl.UNSIGNED_INT: np.uint32, gl.FLOAT: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
#: Thresholds of the material classification (glTF's metallic-roughness model).
CONDUCTOR_METALLIC, SMOOTH_ROUGHNESS = 0.9, 0.05
#: Image height (px) of a camera that states only its aspect ratio.
DEFAULT_HEIGHT = 512


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
        seen: set[int] = set()
        while stack:
            index, parent = stack.pop()
            if index in seen:
                raise ImportProblemError([f"{self.path}: nodes[{index}] is reached twice "
                                          "(the node hierarchy is not a tree)"])
            seen.add(index)
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


def _label(item, plural: str, index: int) -> str:
    """``'name'`` of a named glTF item, else ``plural[index]``."""
    name = getattr(item, "name", None)
    return repr(name) if name else f"{plural}[{index}]"


def _rgb(values) -> list[float]:
    return [float(v) for v in list(values)[:3]]


def _vector(world: np.ndarray, column: int, sign: float = 1.0) -> list[float]:
    direction = sign * world[:3, column]
    return _to_scene(direction / np.linalg.norm(direction)).tolist()


def _position(world: np.ndarray) -> np.ndarray:
    return _to_scene(world[:3, 3])


def _agrees(table_point, node_point) -> bool:
    a, b = np.asarray(table_point, float), np.asarray(node_point, float)
    return bool(np.linalg.norm(a - b) <= 1e-6 * max(1.0, np.linalg.norm(a)))


@dataclass(frozen=True)
class _Triangles:
    """A mesh node's primitives joined, in scene coordinates: positions (n, 3) m, faces
    (m, 3), normals (n, 3) where every primitive has them, each primitive's material."""

    positions: np.ndarray
    faces: np.ndarray
    normals: np.ndarray | None
    materials: tuple[int | None, ...]


class _Reader:
    """Reads one file's nodes into a draft; ``approximate`` as :func:`read_gltf`'s."""

    def __init__(self, file: _File, draft: Draft, *, approximate: bool):
        self.file, self.draft, self.approx = file, draft, approximate

    # ------------------------------------------------------------------ geometry

    def triangles(self, mesh_index: int, world: np.ndarray, where: str) -> _Triangles:
        file = self.file
        linear = world[:3, :3]
        flip = np.linalg.det(linear) < 0  # a mirroring transform turns the winding over
        positions, faces, normals, materials, count = [], [], [], [], 0
        for k, primitive in enumerate(file.gltf.meshes[mesh_index].primitives):
            at = f"{file.path}: {where}, primitive {k}"
            if primitive.mode not in (None, gl.TRIANGLES):
                raise ImportProblemError([f"{at}: mode {primitive.mode} is not triangles"])
            if primitive.attributes.POSITION is None:
                raise ImportProblemError([f"{at}: no POSITION"])
            local = file.accessor(primitive.attributes.POSITION).astype(np.float64)
            index = (file.accessor(primitive.indices).reshape(-1)
                     if primitive.indices is not None else np.arange(len(local)))
            if len(index) % 3:
                raise ImportProblemError([f"{at}: {len(index)} indices is not a whole "
                                          "number of triangles"])
            index = index.astype(np.int64).reshape(-1, 3)
            positions.append(_to_scene(local @ linear.T + world[:3, 3]))
            faces.append((index[:, ::-1] if flip else index) + count)
            count += len(local)
            if primitive.attributes.NORMAL is not None:
                # Normals transform by the inverse transpose of the node's linear part.
                n = file.accessor(primitive.attributes.NORMAL).astype(np.float64)
                n = _to_scene(n @ np.linalg.inv(linear))
                normals.append(n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True),
                                              1e-300))
            materials.append(primitive.material)
        every = len(normals) == len(positions) and all(
            len(n) == len(p) for n, p in zip(normals, positions, strict=True))
        return _Triangles(np.concatenate(positions), np.concatenate(faces),
                          np.concatenate(normals) if every else None, tuple(materials))

    def emissive(self, materials) -> bool:
        return any(m is not None and any(v > 0 for v in
                                         (self.file.gltf.materials[m].emissiveFactor or ()))
                   for m in materials)

    def mesh_node(self, label: str, node: gl.Node, world: np.ndarray) -> None:
        """One mesh node: the harness's exact table from extras where it still describes
        the triangles, else a shape classified by its material and triangles."""
        draft, harness, where = self.draft, _harness(node), f"node {label}"
        tri = self.triangles(node.mesh, world, where)
        if harness.get("type") == "area" or (not harness and self.emissive(tri.materials)):
            self.area(where, harness, tri)
            return
        problem = mesh_problem(tri.positions, tri.faces)
        if problem:
            draft.refuse(where, f"the mesh {problem}", part="shape")
            return
        role, table = harness.get("role"), harness.get("table")
        if role in {"receiver", "object"} and isinstance(table, dict) and usable(table):
            # The triangles' reading is kept in reserve (and its problems forgotten): it
            # is written only if the table does not reproduce the triangles.
            marks = len(draft.problems), len(draft.approximations)
            fallback = self.shape(label, tri)
            refused = tuple(draft.problems[marks[0]:])
            del draft.problems[marks[0]:], draft.approximations[marks[1]:]
            part = Part(table, f"glTF node {label} (exact {harness.get('kind')} from extras)",
                        fallback=fallback, refused=refused,
                        bounds=np.stack([tri.positions.min(axis=0), tri.positions.max(axis=0)]))
            (draft.receivers if role == "receiver" else draft.objects).append(part)
            return
        if role in {"receiver", "object"} and isinstance(table, dict):
            # The harness's own mesh, whose file the export could not name: its triangles,
            # placed, in the role and with the material the table gives.
            self.placed_mesh(label, role, table, tri)
            return
        found = self.shape(label, tri)
        if found is not None:
            getattr(draft, found[0]).append(found[1])

    def placed_mesh(self, label: str, role: str, table: dict, tri: _Triangles) -> None:
        draft = self.draft
        slug = re.sub(r"[^A-Za-z0-9_-]+", "_", label.strip("'")).strip("_") or "mesh"
        mesh = MeshPart(f"{len(draft.receivers) + len(draft.objects)}_{slug}", tri.positions,
                        tri.faces, tri.normals)
        origin = f"glTF node {label} (the harness's {table.get('type')} {role}, its triangles)"
        if role == "receiver":
            draft.receivers.append(Part({"type": "mesh", "albedo": table["albedo"]}, origin,
                                        mesh))
        else:
            draft.objects.append(Part({"type": "mesh", "material": table["material"]}, origin,
                                      mesh))

    def shape(self, label: str, tri: _Triangles) -> tuple[str, Part] | None:
        """("receivers" | "objects", Part) from the triangles and the material alone."""
        draft, where = self.draft, f"node {label}"
        if len(set(tri.materials)) > 1:
            draft.approximate(self.approx, where, "primitives with different materials: one "
                              "material per shape", "the first primitive's material is used")
        material = self.material(tri.materials[0], where)
        slug = re.sub(r"[^A-Za-z0-9_-]+", "_", label.strip("'")).strip("_") or "mesh"
        mesh = MeshPart(f"{len(draft.receivers) + len(draft.objects)}_{slug}", tri.positions,
                        tri.faces, tri.normals)
        origin = f"glTF node {label} (mesh, material {material['type']})"
        if material["type"] == "diffuse":
            plane = rectangle(tri.positions, tri.faces)
            if plane is not None:
                return "receivers", Part({**plane, "albedo": material["albedo"]},
                                         f"glTF node {label} (rectangle, diffuse)")
            if is_height_field(tri.positions, tri.faces):
                return "receivers", Part({"type": "mesh", "albedo": material["albedo"]},
                                         origin + " as a height-field receiver", mesh)
            return "objects", Part({"type": "mesh", "material": material},
                                   origin + " as an occluder", mesh)
        sphere = icosphere(tri.positions, tri.faces)
        if sphere is not None:
            return "objects", Part({**sphere, "material": material}, f"glTF node {label} "
                                   f"(the harness's icosphere, level {sphere['subdivisions']}: "
                                   f"a sphere, material {material['type']})")
        if material["type"] == "dielectric" and not is_closed(tri.positions, tri.faces):
            draft.refuse(where, "an open (non-manifold or not watertight) dielectric mesh: a "
                         "dielectric must close a volume", part="shape")
            return None
        return "objects", Part({"type": "mesh", "material": material}, origin, mesh)

    def area(self, where: str, harness: dict, tri: _Triangles) -> None:
        exact = harness.get("table")
        if isinstance(exact, dict) and exact.get("type") == "area":
            self.draft.lights.append(Part(exact, f"glTF {where} (the harness's area light, "
                                          "exact from extras)"))
            return
        p, f = tri.positions, tri.faces
        area = float(np.linalg.norm(np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]]),
                                    axis=1).sum() / 2)
        material = self.file.gltf.materials[next(m for m in tri.materials if m is not None)]
        strength = (material.extensions or {}).get("KHR_materials_emissive_strength", {}).get(
            "emissiveStrength", 1.0)
        radiance = [float(v) * strength for v in material.emissiveFactor]
        self.draft.area_light(self.approx, where, p.mean(axis=0), radiance, area)

    # ----------------------------------------------------------------- materials

    def material(self, index: int | None, where: str) -> dict:
        """The material's table (dielectric, conductor or diffuse), from extras where
        the harness wrote them."""
        if index is None:  # glTF's default material: white, rough, dielectric-free
            return {"type": "diffuse", "albedo": [1.0, 1.0, 1.0]}
        material = self.file.gltf.materials[index]
        where = f"{where}, material {_label(material, 'materials', index)}"
        exact = _harness(material)
        if exact.get("type") in {"dielectric", "conductor", "diffuse"}:
            keys = {"type", "albedo", "reflectance", "ior", "absorption", "fresnel"}
            table = {k: v for k, v in exact.items() if k in keys}
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
            self.draft.approximate(self.approx, where, f"textured ({', '.join(textures)}): "
                                   "the scene model's materials are uniform",
                                   "its factors are used")
        transmission = ext.get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0)
        if transmission > 0:
            return self.dielectric(ext, roughness, where)
        if metallic >= CONDUCTOR_METALLIC:
            if roughness > SMOOTH_ROUGHNESS:
                self.draft.approximate(self.approx, where, f"a rough conductor (roughness "
                                       f"{roughness:g}): the scene model's conductors are "
                                       "mirrors", "read as a mirror")
            return {"type": "conductor", "reflectance": base}
        return {"type": "diffuse", "albedo": [min(1.0, max(0.0, v)) for v in base]}

    def dielectric(self, ext: dict, roughness: float, where: str) -> dict:
        if roughness > SMOOTH_ROUGHNESS:
            self.draft.approximate(self.approx, where, f"a rough dielectric (roughness "
                                   f"{roughness:g}): the scene model's dielectrics are smooth",
                                   "read as smooth")
        ior = float(ext.get("KHR_materials_ior", {}).get("ior", 1.5))
        # glTF's transmission weights by Fresnel, as the harness does with fresnel = true.
        table = {"type": "dielectric", "ior": ior, "fresnel": True}
        volume = ext.get("KHR_materials_volume", {})
        distance = volume.get("attenuationDistance")
        if distance is not None and math.isfinite(distance) and distance > 0:
            # attenuationColor is the transmitted fraction after attenuationDistance:
            # exp(-sigma d) = colour, so sigma = -ln(colour) / d per channel.
            colour = np.clip(np.asarray(volume.get("attenuationColor", [1, 1, 1]), float),
                             1e-30, 1.0)
            table["absorption"] = (-np.log(colour) / distance).tolist()
        if "KHR_materials_dispersion" in ext:
            self.draft.approximate(self.approx, where, "KHR_materials_dispersion without the "
                                   "harness's per-channel IORs",
                                   f"one IOR {ior:g} for all channels")
        return table

    # ------------------------------------------------------------ light, camera

    def light(self, label: str, light: dict, world: np.ndarray, node: gl.Node) -> None:
        draft, where = self.draft, f"node {label}"
        exact = _harness(node).get("table")
        position = _position(world)
        if isinstance(exact, dict) and ("position" not in exact
                                        or _agrees(exact["position"], position)):
            draft.lights.append(Part(exact, f"glTF node {label} (exact values from extras)"))
            return
        kind = light.get("type")
        power = (np.asarray(light.get("color", [1, 1, 1]), float)
                 * float(light.get("intensity", 1.0))).tolist()
        if light.get("range") is not None and not draft.approximate(
                self.approx, where, "a light with a range: the harness's lights reach "
                "everywhere", "the range is ignored", part="light"):
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
                if not draft.approximate(self.approx, where, f"a cone of {outer:g}°: the "
                                         "harness's spot lights are narrower than 90°",
                                         "cut to 89.9°", part="light"):
                    return
                outer = 89.9
            # glTF blends between the cones in a renderer's own way; the harness's beam is
            # full within beam_width and falls linearly to the cutoff (beam_width > 0).
            table = {"type": "spot", "position": position.tolist(),
                     "direction": _vector(world, 2, -1.0), "intensity": power,
                     "cutoff_angle": outer,
                     "beam_width": max(min(inner, outer), 1e-3 * outer)}
        else:
            draft.refuse(where, f"light type {kind!r} is not point, spot or directional",
                         part="light")
            return
        draft.lights.append(Part(table, f"glTF node {label} (KHR_lights_punctual {kind}; "
                                 "intensity read as W/sr, directional as W/m²)"))

    def camera(self, cameras: list, wanted: str | None, centre: np.ndarray) -> None:
        """The camera node named ``wanted``, else the first perspective one; its look-at
        point is where its axis passes closest to ``centre`` (the meshes' centre)."""
        draft, gltf = self.draft, self.file.gltf
        if wanted is not None:
            cameras = [c for c in cameras if c[3].name == wanted]
            if not cameras:
                draft.refuse("camera", f"no camera node named {wanted!r}", part="camera")
                return
        perspective = [c for c in cameras if gltf.cameras[c[1]].type == "perspective"]
        if not perspective:
            if cameras:
                draft.refuse(f"node {cameras[0][0]}", "an orthographic camera: the scene "
                             "model's camera is a pinhole", part="camera")
            return
        label, index, world, node = perspective[0]
        position = _position(world)
        exact = _harness(node).get("table")
        if isinstance(exact, dict) and _agrees(exact.get("position", []), position):
            draft.camera = Part(exact, f"glTF node {label} (exact values from extras)")
            return
        camera = gltf.cameras[index].perspective
        forward = np.asarray(_vector(world, 2, -1.0))
        distance = float(np.dot(centre - position, forward))
        look_at = position + forward * (distance if distance > 0 else 1.0)
        height = DEFAULT_HEIGHT
        width = max(1, round(height * camera.aspectRatio)) if camera.aspectRatio else height
        table = {"position": position.tolist(), "look_at": look_at.tolist(),
                 "up": _vector(world, 1), "fov": math.degrees(camera.yfov), "fov_axis": "y",
                 "resolution": [width, height]}
        draft.camera = Part(table, f"glTF node {label} (perspective camera; {width} x "
                            f"{height} pixels from its aspect ratio)")


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
    reader = _Reader(file, draft, approximate=approximate)
    try:
        cameras, points = _walk(file, reader)
    except (IndexError, KeyError, TypeError, ValueError, AttributeError) as error:
        # A reference to an item the file does not have, or a field of the wrong type.
        raise ImportProblemError([f"{path}: malformed glTF ({type(error).__name__}: "
                                  f"{error})"]) from None
    centre = _to_scene(np.mean(points, axis=0)) if points else np.zeros(3)
    reader.camera(cameras, camera, centre)
    draft.choose_light(approximate)
    return draft


def _walk(file: _File, reader: _Reader) -> tuple[list, list]:
    """Every node of the scene: meshes, lights; the cameras and mesh origins found."""
    punctual = (file.gltf.extensions or {}).get("KHR_lights_punctual", {}).get("lights", [])
    cameras, points = [], []
    for index, world in file.world_nodes():
        node = file.gltf.nodes[index]
        label = _label(node, "nodes", index)
        if node.mesh is not None:
            reader.mesh_node(label, node, world)
            points.append(world[:3, 3])
        light = (node.extensions or {}).get("KHR_lights_punctual", {}).get("light")
        if light is not None:
            if not 0 <= light < len(punctual):
                reader.draft.refuse(f"node {label}", f"names light {light}, the file has "
                                    f"{len(punctual)}", part="light")
            else:
                reader.light(label, punctual[light], world, node)
        if node.camera is not None:
            cameras.append((label, node.camera, world, node))
    return cameras, points
