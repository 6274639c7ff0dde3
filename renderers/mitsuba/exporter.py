"""Scene -> Mitsuba: the same triangles and normals the GPU renderer gets.

Every receiver and caustic object becomes an ``mi.Mesh`` built from
:func:`scenes.geometry.build_geometry` (positions, vertex normals, faces, and the
receiver's (u, v) as texture coordinates), so both renderers intersect identical
triangles and shade with identical normals. Units stay SI: point and spot lights
carry intensity in W/sr, directional lights irradiance in W/m², area lights
radiance intensity / area in W m^-2 sr^-1.

Materials
---------
* diffuse -> ``diffuse`` (albedo);
* dielectric -> ``chain_dielectric`` (see :mod:`.bsdf`: Fresnel only when the
  scene asks for it, absorption on exit);
* conductor -> two-sided ``conductor`` with ``material = "none"`` (a perfect
  mirror, F = 1) times the constant reflectance (the scene's model).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from renderers.mitsuba import _mi
from renderers.mitsuba.bsdf import BSDF_NAME
from scenes.geometry import SceneGeometry, TriangleMesh, build_geometry
from scenes.model import (
    AreaLight,
    Camera,
    ConductorMaterial,
    DielectricMaterial,
    DiffuseMaterial,
    DirectionalLight,
    PointLight,
    Scene,
    SpotLight,
)

__all__ = [
    "ExportedScene",
    "area_light_frame",
    "bsdf_dict",
    "channel_mask",
    "emitter_dicts",
    "export_scene",
    "exported",
    "mitsuba_mesh",
    "scene_dict",
    "sensor_dict",
]


@dataclass(frozen=True, eq=False)
class ExportedScene:
    """A loaded Mitsuba scene and the registry ids of its shapes.

    Attributes
    ----------
    scene : mi.Scene
    receiver_ids, object_ids : tuple of int
        Dr.Jit registry id of each receiver / caustic object's shape (compare with
        ``dr.reinterpret_array(UInt32, si.shape)``), indexed like the Scene's lists.
    """

    scene: object
    receiver_ids: tuple[int, ...]
    object_ids: tuple[int, ...]


def channel_mask(channel: int | None) -> np.ndarray:
    """RGB mask: all ones, or one-hot on ``channel`` (dispersion passes)."""
    if channel is None:
        return np.ones(3)
    mask = np.zeros(3)
    mask[channel] = 1.0
    return mask


def _rgb(values, channel: int | None) -> dict:
    value = np.asarray(values, float) * channel_mask(channel)
    return {"type": "rgb", "value": value.tolist()}


def bsdf_dict(material, *, channel: int | None = None, tir_reflects: bool = False) -> dict:
    """Mitsuba BSDF description of a scene material (``channel``: dispersion pass)."""
    if isinstance(material, DiffuseMaterial):
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(material.albedo)}}
    if isinstance(material, DielectricMaterial):
        sigma = material.absorption
        return {
            "type": BSDF_NAME,
            "eta": float(material.iors[0 if channel is None else channel]),
            "fresnel": bool(material.fresnel),
            "tir_reflects": bool(tir_reflects),
            "sigma_r": float(sigma[0]), "sigma_g": float(sigma[1]), "sigma_b": float(sigma[2]),
        }
    if isinstance(material, ConductorMaterial):
        return {
            "type": "twosided",
            "bsdf": {
                "type": "conductor",
                "material": "none",
                "specular_reflectance": {"type": "rgb", "value": list(material.reflectance)},
            },
        }
    raise TypeError(f"unknown material {material!r}")


def area_light_frame(light: AreaLight) -> np.ndarray:
    """4x4 to_world of the unit rectangle [-1, 1]^2 (normal +z) onto the light.

    The rectangle's first side runs along ``normal x helper`` (helper = +x, or +y
    when the normal is close to x); both renderers must use this frame.
    """
    n = np.asarray(light.normal, float)
    n /= np.linalg.norm(n)
    helper = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = np.cross(n, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    m = np.eye(4)
    m[:3, 0] = e1 * light.size[0] / 2
    m[:3, 1] = e2 * light.size[1] / 2
    m[:3, 2] = n
    m[:3, 3] = light.center
    return m


def emitter_dicts(light, *, channel: int | None = None) -> dict[str, dict]:
    """Mitsuba emitters (area lights become an emitting rectangle shape)."""
    mi, _, _ = _mi.load()
    if isinstance(light, PointLight):
        return {"light": {"type": "point", "position": list(light.position),
                          "intensity": _rgb(light.intensity, channel)}}
    if isinstance(light, SpotLight):
        pos = np.asarray(light.position, float)
        d = np.asarray(light.direction, float)
        up = [0, 0, 1] if abs(d[2]) < 0.99 * np.linalg.norm(d) else [0, 1, 0]
        beam = light.cutoff_angle if light.beam_width is None else light.beam_width
        return {"light": {
            "type": "spot",
            "to_world": mi.ScalarTransform4f().look_at(origin=pos, target=pos + d, up=up),
            "intensity": _rgb(light.intensity, channel),
            "cutoff_angle": float(light.cutoff_angle),
            "beam_width": float(beam),
        }}
    if isinstance(light, DirectionalLight):
        return {"light": {"type": "directional", "direction": list(light.direction),
                          "irradiance": _rgb(light.irradiance, channel)}}
    if isinstance(light, AreaLight):
        area = light.size[0] * light.size[1]
        return {"light": {
            "type": "rectangle",
            "to_world": mi.ScalarTransform4f(area_light_frame(light).tolist()),
            "emitter": {"type": "area",
                        "radiance": _rgb(np.asarray(light.intensity) / area, channel)},
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}},
        }}
    raise TypeError(f"unknown light {light!r}")


def sensor_dict(camera: Camera, *, spp: int = 1, sample_count_film: bool = False) -> dict:
    """Perspective sensor of the scene camera; box-filtered HDR film (linear radiance)."""
    mi, _, _ = _mi.load()
    w, h = camera.resolution
    return {
        "type": "perspective",
        "fov": float(camera.fov),
        "fov_axis": camera.fov_axis,
        "to_world": mi.ScalarTransform4f().look_at(
            origin=list(camera.position), target=list(camera.look_at), up=list(camera.up)
        ),
        "sampler": {"type": "independent", "sample_count": int(spp)},
        "film": {"type": "hdrfilm", "width": int(w), "height": int(h),
                 "rfilter": {"type": "box"}, "pixel_format": "rgb",
                 "sample_border": False},
    }


def mitsuba_mesh(mi, name: str, mesh: TriangleMesh, bsdf: dict, *, texcoords: bool):
    """A ``mi.Mesh`` named ``name`` holding ``mesh``'s positions (m), normals and
    faces (and its (u, v) where ``texcoords``), with the BSDF ``bsdf`` (a Mitsuba dict)."""
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf)
    out = mi.Mesh(name, len(mesh.positions), len(mesh.faces), props=props,
                  has_vertex_normals=True, has_vertex_texcoords=texcoords)
    params = mi.traverse(out)
    params["vertex_positions"] = np.ravel(mesh.positions).astype(np.float32)
    params["vertex_normals"] = np.ravel(mesh.normals).astype(np.float32)
    params["faces"] = np.ravel(mesh.faces).astype(np.uint32)
    if texcoords:
        params["vertex_texcoords"] = np.ravel(mesh.uvs).astype(np.float32)
    params.update()
    return out


def scene_dict(
    scene: Scene,
    *,
    geometry: SceneGeometry | None = None,
    channel: int | None = None,
    tir_reflects: bool = False,
    include_objects: bool = True,
    sensor: dict | None = None,
    integrator: dict | None = None,
    shape: Callable[[str, TriangleMesh, dict, bool], object] | None = None,
) -> dict:
    """The Mitsuba scene description of ``scene`` (what :func:`export_scene` loads).

    Shapes are the dict's ``receiver_<i>`` and ``object_<i>`` entries, each made by
    ``shape(name, mesh, bsdf, texcoords)`` (default: an ``mi.Mesh`` of the triangles);
    the other parameters are :func:`export_scene`'s.
    """
    mi, _, _ = _mi.load()
    if shape is None:
        def shape(name, mesh, bsdf, texcoords):
            return mitsuba_mesh(mi, name, mesh, bsdf, texcoords=texcoords)
    geometry = geometry or build_geometry(scene)
    desc: dict = {"type": "scene"}
    desc["integrator"] = integrator or {"type": "ptracer"}
    desc["sensor"] = sensor or sensor_dict(scene.camera)
    desc.update(emitter_dicts(scene.light, channel=channel))
    for i, rec in enumerate(geometry.receivers):
        desc[f"receiver_{i}"] = shape(
            f"receiver_{i}", rec.mesh,
            {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(rec.albedo)}},
            True,
        )
    if include_objects:
        for i, obj in enumerate(geometry.objects):
            desc[f"object_{i}"] = shape(
                f"object_{i}", obj.mesh,
                bsdf_dict(obj.material, channel=channel, tir_reflects=tir_reflects), False,
            )
    return desc


def exported(loaded, *, receivers: int, objects: int) -> ExportedScene:
    """An ``mi.Scene`` whose shapes have the ids ``receiver_<i>`` and ``object_<i>``
    (:func:`scene_dict`'s), with their registry ids.

    Raises
    ------
    KeyError
        A receiver or object the counts name is not among the scene's shapes.
    """
    mi, dr, _ = _mi.load()
    ids = {}
    for item in loaded.shapes():
        ids[item.id()] = int(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(item))[0])
    return ExportedScene(loaded, tuple(ids[f"receiver_{i}"] for i in range(receivers)),
                         tuple(ids[f"object_{i}"] for i in range(objects)))


def export_scene(
    scene: Scene,
    *,
    geometry: SceneGeometry | None = None,
    channel: int | None = None,
    tir_reflects: bool = False,
    include_objects: bool = True,
    sensor: dict | None = None,
    integrator: dict | None = None,
) -> ExportedScene:
    """Load ``scene`` into Mitsuba.

    Parameters
    ----------
    channel
        Dispersion pass: dielectrics take this channel's IOR and the light only
        this channel's power. ``None``: one IOR (the first) and full RGB.
    tir_reflects
        See :mod:`.bsdf` (True only when all L S+ D paths are counted).
    include_objects
        False gives the receivers alone (unshadowed direct light).
    sensor, integrator
        Mitsuba dicts; default the scene camera and a plain ``ptracer``.
    """
    mi, _, _ = _mi.load()
    geometry = geometry or build_geometry(scene)
    desc = scene_dict(scene, geometry=geometry, channel=channel, tir_reflects=tir_reflects,
                      include_objects=include_objects, sensor=sensor, integrator=integrator)
    return exported(mi.load_dict(desc), receivers=len(geometry.receivers),
                    objects=len(geometry.objects) if include_objects else 0)
