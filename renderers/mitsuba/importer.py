"""Mitsuba 3 XML -> a scene :class:`~scenes.importers.draft.Draft`, read with Mitsuba's
own loader (``mi.load_file``), so includes, ``<default>`` parameters and transforms
resolve as Mitsuba resolves them; the loaded scene is then traversed.

* shapes: meshes (``obj``, ``ply``, ``serialized``: their world-space vertex buffers),
  ``sphere`` (centre and radius from its ``to_world``), ``rectangle`` (a plane, from its
  ``to_world``); an emitting shape is an area light;
* BSDFs (a ``twosided`` wrapper is looked through): ``dielectric`` (IOR = int/ext IOR,
  Fresnel on, as Mitsuba weights it), the harness's ``chain_dielectric`` (exact),
  ``conductor`` (reflectance = specular reflectance times the normal-incidence Fresnel
  factor of its eta, k), ``diffuse``; a diffuse rectangle is a plane receiver, a diffuse
  mesh facing up everywhere a mesh receiver, other diffuse shapes occluders;
* emitters: ``point``, ``spot``, ``directional`` (Mitsuba's units are the harness's:
  W/sr, W/m²); the ``perspective`` sensor (``--camera``: its id).

A file the harness exported carries the scene's exact tables in a comment
(:mod:`.exact_tables`): each shape, the light and the camera take theirs where the loaded
part still agrees with it, so an export imports back as the same scene (an open water
surface, which the triangles alone cannot be, included); a part edited since is read
from the file.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from renderers.mitsuba import _mi
from renderers.mitsuba.exact_tables import (
    camera_agrees,
    light_agrees,
    material_agrees,
    read_tables,
    shape_table,
)
from scenes.importers.draft import Draft, ImportProblemError, MeshPart, Part, usable
from scenes.importers.shapes import (
    icosphere,
    is_closed,
    is_height_field,
    mesh_problem,
    rectangle,
)

__all__ = ["read_mitsuba"]

_MESHES = {"PLYMesh", "OBJMesh", "SerializedMesh", "Mesh"}


def _kind(obj) -> str:
    """Mitsuba's class name of a loaded plugin (``SmoothDielectric``, ``PLYMesh``...)."""
    name = type(obj).__name__
    if name in {"ChainDielectric"}:
        return name
    return str(obj).split("[", 1)[0].strip()


def _array(value) -> np.ndarray:
    return np.asarray(np.array(value), np.float64)


def _matrix(value) -> np.ndarray:
    return _array(value.matrix).reshape(4, 4)


def _rgb(params, key: str) -> list[float] | None:
    if key not in params:
        return None
    value = _array(params[key]).ravel()
    return [float(v) for v in (value if len(value) == 3 else np.repeat(value[:1], 3))]


def _where(kind: str, obj, index: int) -> str:
    name = obj.id() if hasattr(obj, "id") else ""
    return f"{kind} {name!r}" if name else f"{kind} #{index} ({_kind(obj)})"


def _material(mi, bsdf, where: str, draft: Draft, approx: bool) -> dict | None:
    params = mi.traverse(bsdf)
    kind, prefix = _kind(bsdf), ""
    if kind == "TwoSided":
        inner = str(bsdf).split("brdf[0] = ", 1)[-1]
        kind, prefix = inner.split("[", 1)[0].strip(), "brdf_0."
    where = f"{where}, bsdf {kind}"
    textured = [k for k in params.keys() if k.startswith(prefix) and k.endswith(".data")]
    if textured and not draft.approximate(approx, where, "textured: the scene model's "
                                          "materials are uniform", "its mean is used",
                                          part="shape"):
        return None

    def rgb(name, default):
        value = _rgb(params, prefix + name + ".value")
        if value is None and prefix + name + ".data" in params:
            data = _array(params[prefix + name + ".data"]).reshape(-1, 3)
            value = data.mean(axis=0).tolist()
        return value or default

    if kind == "ChainDielectric":
        sigma = _array(bsdf.sigma).ravel()
        return {"type": "dielectric", "ior": float(bsdf.eta), "fresnel": bool(bsdf.fresnel),
                "absorption": [float(s) for s in np.resize(sigma, 3)]}
    if kind in {"SmoothDielectric", "RoughDielectric", "ThinDielectric"}:
        if kind != "SmoothDielectric" and not draft.approximate(
                approx, where, "the scene model's dielectrics are smooth and closed",
                "read as a smooth dielectric", part="shape"):
            return None
        eta = float(_array(params[prefix + "eta"]).ravel()[0]) if prefix + "eta" in params \
            else 1.5
        return {"type": "dielectric", "ior": eta, "fresnel": True}
    if kind in {"SmoothConductor", "RoughConductor"}:
        if kind != "SmoothConductor" and not draft.approximate(
                approx, where, "a rough conductor: the scene model's conductors are mirrors",
                "read as a mirror", part="shape"):
            return None
        eta = np.asarray(rgb("eta", [0.0] * 3))
        k = np.asarray(rgb("k", [1.0] * 3))
        # Normal-incidence Fresnel reflectance of a conductor: ((n-1)² + k²)/((n+1)² + k²).
        f0 = ((eta - 1) ** 2 + k**2) / ((eta + 1) ** 2 + k**2)
        if np.abs(f0 - 1).max() > 1e-6 and not draft.approximate(
                approx, where, "a conductor with an angle-dependent Fresnel factor: the "
                "scene model's reflectance is constant", "its value at normal incidence",
                part="shape"):
            return None
        reflectance = np.clip(np.asarray(rgb("specular_reflectance", [1.0] * 3)) * f0, 0, 1)
        return {"type": "conductor", "reflectance": reflectance.tolist()}
    if kind == "SmoothDiffuse":
        return {"type": "diffuse",
                "albedo": np.clip(rgb("reflectance", [0.5] * 3), 0, 1).tolist()}
    draft.refuse(where, "a BSDF the scene model does not hold (it holds dielectric, "
                 "thindielectric, conductor and diffuse)", part="shape")
    return None


def _shape(mi, draft: Draft, approx: bool, shape, index: int) -> None:
    where = _where("shape", shape, index)
    kind = _kind(shape)
    params = mi.traverse(shape)
    if shape.emitter() is not None:
        eparams = mi.traverse(shape.emitter())
        radiance = _rgb(eparams, "radiance.value") or [1.0, 1.0, 1.0]
        box = shape.bbox()
        centre = (_array(box.min).ravel() + _array(box.max).ravel()) / 2
        draft.area_light(approx, f"Mitsuba {where}", centre, radiance,
                         float(np.array(shape.surface_area()).ravel()[0]))
        return
    material = _material(mi, shape.bsdf(), where, draft, approx)
    if material is None:
        return
    origin = f"Mitsuba {where} ({kind}, {material['type']})"
    if kind == "Sphere":
        matrix = _matrix(params["to_world"])
        scales = np.linalg.norm(matrix[:3, :3], axis=0)
        if np.ptp(scales) > 1e-6 * scales.max():
            draft.refuse(where, "an ellipsoid (a sphere scaled unevenly)", part="shape")
            return
        table = {"type": "sphere", "center": matrix[:3, 3].tolist(),
                 "radius": float(scales.mean()), "material": material}
        draft.objects.append(Part(table, origin + "; tessellated as an icosphere"))
        return
    if kind == "Rectangle":
        matrix = _matrix(params["to_world"])
        corners = np.array([[-1, -1, 0, 1], [1, -1, 0, 1], [1, 1, 0, 1], [-1, 1, 0, 1]])
        positions = (corners @ matrix.T)[:, :3]
        faces = np.array([[0, 1, 2], [0, 2, 3]])
    elif kind in _MESHES or shape.is_mesh():
        positions, faces = _triangles(params)
    else:
        draft.refuse(where, f"a {kind} shape: the importer reads meshes (obj, ply, "
                     "serialized), sphere and rectangle", part="shape")
        return
    problem = mesh_problem(positions, faces)
    if problem:
        draft.refuse(where, f"the mesh {problem}", part="shape")
        return
    mesh = _mesh_part(draft, shape, params, positions, faces, normals=kind != "Rectangle")
    if material["type"] == "diffuse":
        plane = rectangle(positions, faces)
        if plane is not None:
            draft.receivers.append(Part({**plane, "albedo": material["albedo"]}, origin))
        elif is_height_field(positions, faces):
            draft.receivers.append(Part({"type": "mesh", "albedo": material["albedo"]},
                                        origin + " as a height-field receiver", mesh))
        else:
            draft.objects.append(Part({"type": "mesh", "material": material},
                                      origin + " as an occluder", mesh))
        return
    sphere = icosphere(positions, faces)
    if sphere is not None:
        draft.objects.append(Part({**sphere, "material": material}, f"Mitsuba {where} (the "
                                  f"harness's icosphere, level {sphere['subdivisions']}: a "
                                  f"sphere, {material['type']})"))
        return
    if material["type"] == "dielectric" and not is_closed(positions, faces):
        draft.refuse(where, "an open (non-manifold or not watertight) dielectric mesh: a "
                     "dielectric must close a volume", part="shape")
        return
    draft.objects.append(Part({"type": "mesh", "material": material}, origin, mesh))


def _triangles(params) -> tuple[np.ndarray, np.ndarray]:
    """A mesh's world-space positions (n, 3), m, and faces (m, 3)."""
    return (_array(params["vertex_positions"]).reshape(-1, 3),
            np.asarray(np.array(params["faces"]), np.int64).reshape(-1, 3))


def _mesh_part(draft: Draft, shape, params, positions, faces, *, normals: bool) -> MeshPart:
    """The triangles as a mesh file to write, with the file's vertex normals if any."""
    found = None
    if normals and "vertex_normals" in params:
        found = _array(params["vertex_normals"]).reshape(-1, 3)
        found = found if len(found) == len(positions) else None
    name = f"{len(draft.receivers) + len(draft.objects)}_{shape.id() or 'shape'}"
    return MeshPart(name, positions, faces, found)


def _exact_shape(mi, draft: Draft, approx: bool, shape, index: int, *, tables: dict
                 ) -> bool:
    """An exported shape from the comment's table, where its role and material agree
    with what Mitsuba loaded; False where they do not (the caller reads the file)."""
    role, table = shape_table(tables, shape.id()) or (None, None)
    if role is None or shape.emitter() is not None:
        return False
    where = _where("shape", shape, index)
    scratch = Draft(source=draft.source, name=draft.name)
    read = _material(mi, shape.bsdf(), where, scratch, False)
    if not material_agrees(role, table, read, channel=tables.get("channel"),
                           bsdf=tables.get("bsdf", "stock")) or not (
                               usable(table) or shape.is_mesh()):
        return False
    # The file's own reading, kept in reserve for a table that turns out not to
    # reproduce the triangles (its problems with it: an open water surface is refused).
    marks = (len(draft.problems), len(draft.approximations), len(draft.receivers),
             len(draft.objects), set(draft.explained))
    _shape(mi, draft, approx, shape, index)
    refused = tuple(draft.problems[marks[0]:])
    read_parts = ([("receivers", p) for p in draft.receivers[marks[2]:]]
                  + [("objects", p) for p in draft.objects[marks[3]:]])
    del draft.problems[marks[0]:], draft.approximations[marks[1]:]
    del draft.receivers[marks[2]:], draft.objects[marks[3]:]
    draft.explained = marks[4]
    section = f"{role}s"
    box = shape.bbox()
    bounds = np.stack([_array(box.min).ravel(), _array(box.max).ravel()])
    origin = f"Mitsuba {where} (exact {table.get('type')} from the file's harness comment)"
    if usable(table):
        getattr(draft, section).append(Part(table, origin, fallback=(read_parts or [None])[0],
                                            refused=refused, bounds=bounds))
        return True
    # The harness's own mesh, whose file the export could not name: the file's
    # triangles, in the role and with the material the table gives.
    if refused:
        draft.problems.extend(refused)
        return True
    params = mi.traverse(shape)
    positions, faces = _triangles(params)
    mesh = _mesh_part(draft, shape, params, positions, faces, normals=True)
    keys = ("albedo",) if role == "receiver" else ("material",)
    getattr(draft, section).append(Part({"type": "mesh", **{k: table[k] for k in keys}},
                                        f"Mitsuba {where} (the harness's mesh {role}, its "
                                        "triangles)", mesh))
    return True


def _exact_light(draft: Draft, tables: dict, first: int) -> None:
    """The comment's light in place of the one just read, where they agree."""
    exact = tables.get("light")
    for k, part in enumerate(draft.lights[first:], start=first):
        if isinstance(exact, dict) and light_agrees(exact, part.table):
            draft.lights[k] = Part(exact, part.origin + "; exact values from the file's "
                                   "harness comment")


def _emitter(mi, draft: Draft, approx: bool, emitter, index: int) -> None:
    where = _where("emitter", emitter, index)
    kind = _kind(emitter)
    params = mi.traverse(emitter)
    origin = f"Mitsuba {where} ({kind}; W/sr, W/m²)"
    power = "irradiance.value" if kind == "DirectionalEmitter" else "intensity.value"
    if kind in {"PointLight", "SpotLight", "DirectionalEmitter"} and _rgb(params, power) is None:
        draft.refuse(where, f"its {power.removesuffix('.value')} is not an RGB or uniform value "
                     "(a spectrum file or a texture)", part="light")
        return
    if kind == "PointLight":
        draft.lights.append(Part({"type": "point",
                                  "position": _array(params["position"]).ravel().tolist(),
                                  "intensity": _rgb(params, "intensity.value")}, origin))
    elif kind == "SpotLight":
        matrix = _matrix(params["to_world"])
        cutoff = float(_array(params["cutoff_angle"]).ravel()[0])
        beam = float(_array(params["beam_width"]).ravel()[0])
        table = {"type": "spot", "position": matrix[:3, 3].tolist(),
                 "direction": matrix[:3, 2].tolist(), "intensity": _rgb(params, "intensity.value"),
                 "cutoff_angle": cutoff, "beam_width": min(beam, cutoff)}
        draft.lights.append(Part(table, origin))
    elif kind == "DirectionalEmitter":
        matrix = _matrix(params["to_world"])
        draft.lights.append(Part({"type": "directional", "direction": matrix[:3, 2].tolist(),
                                  "irradiance": _rgb(params, "irradiance.value")}, origin))
    elif kind == "AreaLight":
        return  # read with its shape
    else:
        draft.approximate(approx, f"Mitsuba {where}", f"a {kind} emitter (environment or "
                          "other): the scene model holds point, spot and directional lights",
                          "it is left out", part="light")


def _sensor(mi, draft: Draft, sensors, wanted: str | None, centre: np.ndarray) -> None:
    if wanted is not None:
        sensors = [s for s in sensors if s.id() == wanted]
        if not sensors:
            draft.refuse("sensor", f"no sensor with id {wanted!r}", part="camera")
            return
    if not sensors:
        return
    sensor = sensors[0]
    where = _where("sensor", sensor, 0)
    if _kind(sensor) != "PerspectiveCamera":
        draft.refuse(where, f"a {_kind(sensor)} sensor: the scene model's camera is a "
                     "perspective pinhole", part="camera")
        return
    params = mi.traverse(sensor)
    matrix = _matrix(params["to_world"])
    # Mitsuba's camera looks along its local +z, image up +y, image right -x (its
    # to_world is a look-at whose x axis is left).
    position, forward, up = matrix[:3, 3], matrix[:3, 2], matrix[:3, 1]
    forward = forward / np.linalg.norm(forward)
    distance = float(np.dot(centre - position, forward))
    look_at = position + forward * (distance if distance > 0 else 1.0)
    width, height = (int(v) for v in np.array(sensor.film().size()).ravel()[:2])
    table = {"position": position.tolist(), "look_at": look_at.tolist(),
             "up": (up / np.linalg.norm(up)).tolist(),
             "fov": float(_array(params["x_fov"]).ravel()[0]), "fov_axis": "x",
             "resolution": [width, height]}
    draft.camera = Part(table, f"Mitsuba {where} (perspective)")


def _file_order(item) -> tuple:
    """Shapes the harness exported (ids ``receiver_<i>``, ``object_<i>``) in the scene's
    order, the others after them in Mitsuba's (``scene.shapes()`` does not keep the
    file's order)."""
    index, shape = item
    found = re.fullmatch(r"(receiver|object)_(\d+)", shape.id())
    return (0, found[1], int(found[2])) if found else (1, "", index)


def read_mitsuba(path: str | Path, *, approximate: bool = False, camera: str | None = None
                 ) -> Draft:
    """Load a Mitsuba 3 XML scene with ``mi.load_file`` into a :class:`Draft`.

    Raises
    ------
    ImportProblemError
        Mitsuba cannot load the file (one line: its own message's first line).
    """
    path = Path(path)
    mi, _, _ = _mi.load()
    try:
        scene = mi.load_file(str(path))
    except Exception as error:  # Mitsuba raises RuntimeError and others on bad input
        first = (str(error).strip().splitlines() or [type(error).__name__])[0]
        raise ImportProblemError([f"{path}: Mitsuba cannot load it: {first}"]) from None
    tables = read_tables(path)
    draft = Draft(source=str(path), name=str(tables.get("name") or path.stem),
                  info=dict(tables.get("scene") or {}),
                  settings=dict(tables.get("settings") or {}))
    for index, shape in sorted(enumerate(scene.shapes()), key=_file_order):
        if not _exact_shape(mi, draft, approximate, shape, index, tables=tables):
            _shape(mi, draft, approximate, shape, index)
    for index, emitter in enumerate(scene.emitters()):
        first = len(draft.lights)
        _emitter(mi, draft, approximate, emitter, index)
        _exact_light(draft, tables, first)
    box = scene.bbox()
    centre = (_array(box.min).ravel() + _array(box.max).ravel()) / 2
    _sensor(mi, draft, list(scene.sensors()), camera, centre)
    exact = tables.get("camera")
    if draft.camera is not None and isinstance(exact, dict) and camera_agrees(
            exact, draft.camera.table):
        draft.camera = Part(exact, draft.camera.origin + "; exact values from the file's "
                            "harness comment")
    draft.choose_light(approximate)
    return draft
