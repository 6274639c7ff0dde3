"""drei's ``Caustics`` options from a scene, and the scenes it cannot represent.

The component (``@pmndrs/vanilla`` ``Caustics``, the algorithm of ``@react-three/drei``'s
``<Caustics>``) models one thing: parallel light refracted once at the front faces of
the objects in its group, landing on a horizontal ground plane at the group's y = 0.
What a scene must be for it, each refused with one :class:`DreiSceneError` line that
names the file and field:

* ``light.type``: directional (the component takes a direction, ``lightSource``);
* ``light.direction``: travelling down onto the ground (z < 0);
* ``receivers``: one receiver, ``receivers[0].type`` a plane, ``receivers[0].normal``
  along +z (the ground plane);
* ``objects[i].material.type``: dielectric (the component only refracts);
* ``objects[i].material.ior``: one IOR, or one per channel, shared by every object
  (the component has one ``ior``; per-channel IORs are one render per distinct IOR);
* ``objects[i].material.absorption``: zero (the component has no absorption).

What it assumes that a scene does not say (recorded in every result's metadata,
:data:`ASSUMPTIONS`): no Fresnel (every photon is transmitted: a scene with
``fresnel = true`` is rendered, and the comparison measures what that costs); one
refraction (the front faces; a closed object's exit is not traced); the beam's area
measured on the light camera's far plane (perpendicular to the light), not on the
receiver.

Frames and units
----------------
The **drei frame** is the exported glTF's (``docs/export.md``: (x, y, z)_scene ->
(x, z, -y)) shifted by (0, -h, 0), h the receiver's height, so the receiver is the
component's y = 0 plane. ``lightSource`` is the unit vector towards the light in it:
-M d / |d| for the scene's travel direction d.

The component writes ``intensity * A_near / A_far`` per light-camera texel: the area
ratio of a small beam before and after refraction. With no refraction the ratio is 1,
and the ground then receives the unrefracted irradiance E0 cos(theta), theta the angle
between the light and the ground's normal; so ``intensity = max_c(E0_c) cos(theta)``
(W/m²) and each channel is scaled by ``E0_c / max(E0)`` (:attr:`DreiParams.channel_scale`).
The component's ``color`` (what its projection plane adds to the camera image) is
that scale times albedo / pi: the caustic's radiance off the Lambertian receiver.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scenes import Scene
from scenes.errors import HarnessError
from scenes.export import to_gltf
from scenes.model import DielectricMaterial, DirectionalLight, PlaneReceiver

__all__ = ["ASSUMPTIONS", "DEFAULT_WORLD_RADIUS", "NEAR_FRACTION", "DreiParams",
           "DreiSceneError", "drei_params", "refuse_unrepresentable"]

#: drei's default ``worldRadius`` (scene units, here m): the side of the small square
#: beam whose area the component compares before and after refraction.
DEFAULT_WORLD_RADIUS = 0.3125
#: The light camera's near plane sits this fraction of the objects' bounding radius
#: *behind* the camera (an orthographic camera allows it). drei's default near of
#: 0.1 scene units clips the part of an object nearest the light whenever the light is
#: along one of the bounding box's axes (the camera sits on the box's corner plane).
NEAR_FRACTION = 0.01
#: What the method assumes that a scene does not say.
ASSUMPTIONS = (
    "directional light only",
    "one horizontal ground plane (the receiver) at the component's y = 0",
    "no Fresnel: every photon is transmitted (the scene's fresnel flag is ignored)",
    "one refraction at the objects' front faces (a closed object's exit is not traced; "
    "backside off, drei's default)",
    "the beam's area ratio is measured on the light camera's far plane, perpendicular "
    "to the light, and drawn where the unrefracted ray meets the ground",
    "front-face normals stored in 8 bits per component (drei's normal targets)",
)


class DreiSceneError(HarnessError, ValueError):
    """A scene the component cannot represent; the message names the file and field.

    Attributes
    ----------
    file, field : str
        The scene file and the field path (``light.type``, ``receivers[0].normal``).
    """

    def __init__(self, file: str, field: str, reason: str):
        self.file, self.field = file, field
        super().__init__(f"{file or '<scene>'}: {field}: drei-caustics cannot represent "
                         f"this: {reason}")


@dataclass(frozen=True)
class DreiParams:
    """The component's options and the frame they live in.

    Attributes
    ----------
    light_source : tuple of float
        Unit vector towards the light, drei frame (glTF axes).
    cos_theta : float
        Cosine between the light's travel direction and the ground's downward normal.
    intensity : float
        The component's ``intensity``: max_c E0_c cos(theta), W/m².
    channel_scale : tuple of float
        E0_c / max(E0) per RGB channel.
    color : tuple of float
        The component's ``color``: channel_scale x albedo / pi (its plane adds
        ``caustic * color`` to the camera image: radiance, W m^-2 sr^-1).
    passes : tuple of float
        The distinct IORs, one component render each.
    channel_pass : tuple of int
        Which pass each RGB channel's caustic comes from.
    height : float
        The receiver's height h (scene z, m); drei frame = glTF - (0, h, 0).
    near : float
        The light camera's near plane (m; negative: behind the camera).
    world_radius : float
        The component's ``worldRadius``, m.
    resolution : int
        The component's ``resolution`` (its square caustic texture), texels.
    """

    light_source: tuple[float, float, float]
    cos_theta: float
    intensity: float
    channel_scale: tuple[float, float, float]
    color: tuple[float, float, float]
    passes: tuple[float, ...]
    channel_pass: tuple[int, int, int]
    height: float
    near: float
    world_radius: float
    resolution: int

    def component_options(self) -> dict:
        """The options passed to ``Caustics(renderer, options)`` (JSON)."""
        return {"lightSource": list(self.light_source), "intensity": self.intensity,
                "color": list(self.color), "resolution": self.resolution,
                "worldRadius": self.world_radius, "near": self.near,
                "backside": False, "backsideIOR": self.passes[0]}


def refuse_unrepresentable(scene: Scene) -> None:
    """Raise :class:`DreiSceneError` for the first field the component cannot represent
    (module docstring); return None for a scene it can render."""
    file = scene.source

    def refuse(field: str, reason: str):
        raise DreiSceneError(file, field, reason)

    light = scene.light
    if not isinstance(light, DirectionalLight):
        refuse("light.type", f"{light.kind} light; the component takes a directional "
               "light only (its lightSource is a direction)")
    if light.direction[2] >= 0:
        refuse("light.direction", "the light must travel down onto the ground plane "
               f"(z < 0), got {list(light.direction)}")
    if len(scene.receivers) != 1:
        refuse("receivers[1]", f"{len(scene.receivers)} receivers; the component "
               "projects onto one ground plane")
    receiver = scene.receivers[0]
    if not isinstance(receiver, PlaneReceiver):
        refuse("receivers[0].type", f"a {receiver.kind} receiver; the component projects "
               "onto a plane")
    normal = np.asarray(receiver.normal, float)
    if normal[2] / np.linalg.norm(normal) < 1 - 1e-9:
        refuse("receivers[0].normal", f"{list(receiver.normal)}; the component's ground "
               "plane is horizontal (normal +z)")
    iors = None
    for i, obj in enumerate(scene.objects):
        material = obj.material
        if not isinstance(material, DielectricMaterial):
            refuse(f"objects[{i}].material.type", f"a {material.kind} object; the "
                   "component only refracts")
        if any(k > 0 for k in material.absorption):
            refuse(f"objects[{i}].material.absorption", "the component has no absorption")
        if iors is not None and material.iors != iors:
            refuse(f"objects[{i}].material.ior", f"{material.iors} differs from "
                   f"objects[0]'s {iors}; the component has one ior for all its objects")
        iors = material.iors


def drei_params(scene: Scene, *, objects_radius: float, resolution: int,
                world_radius: float = DEFAULT_WORLD_RADIUS) -> DreiParams:
    """The component's options for ``scene`` (module docstring).

    Parameters
    ----------
    scene : Scene
        A scene :func:`refuse_unrepresentable` accepts.
    objects_radius : float
        Radius of the caustic objects' bounding sphere, m (sets the near plane).
    resolution : int
        The component's caustic texture side, texels.
    world_radius : float
        The component's ``worldRadius``, m.

    Raises
    ------
    DreiSceneError
        The scene is not one the component can represent.
    """
    refuse_unrepresentable(scene)
    light, receiver = scene.light, scene.receivers[0]
    d = np.asarray(light.direction, float)
    d /= np.linalg.norm(d)
    cos_theta = float(-d[2])
    e0 = np.asarray(light.irradiance, float)
    peak = float(e0.max())
    scale = e0 / peak
    albedo = np.asarray(receiver.albedo, float)
    iors = scene.objects[0].material.iors
    passes = tuple(sorted(set(iors)))
    return DreiParams(
        light_source=tuple(float(x) for x in to_gltf(-d)),
        cos_theta=cos_theta, intensity=peak * cos_theta,
        channel_scale=tuple(float(x) for x in scale),
        color=tuple(float(x) for x in scale * albedo / math.pi),
        passes=passes, channel_pass=tuple(passes.index(n) for n in iors),
        height=float(receiver.center[2]), near=-NEAR_FRACTION * objects_radius,
        world_radius=float(world_radius), resolution=int(resolution),
    )
