"""Scene -> LuxCore scene, from the same triangles as :func:`scenes.geometry.build_geometry`.

Only what LuxCore renders exactly as the scene describes it is translated:

=========================  ==================================================
scene                      LuxCore
=========================  ==================================================
point light, I [W/sr]      ``point`` light, ``gain = 4 pi I`` (LuxCore's point
                           light emits ``gain`` watts per unit ``color``)
dielectric, one IOR,       ``glass``, ``kr = kt = 1``, ``interiorior = ior``,
no absorption, Fresnel on  ``exteriorior = 1``, ``cauchyb = 0``: exact
                           unpolarised dielectric Fresnel, specular events
plane receiver             ``matte`` triangles (albedo chosen by the caller)
=========================  ==================================================

Everything else raises :class:`UnsupportedScene` naming the scene file and the
field path, never an approximation: spot lights (LuxCore's smoothstep falloff is
not ours), directional and area lights (not verified against an analytic answer),
conductors, absorption (LuxCore volumes are not checked against Beer-Lambert on
our paths), dispersion (per-channel IOR), dielectrics with ``fresnel = false``
(LuxCore's glass always weights by Fresnel), heightfield and mesh receivers (the
receiver map is read through an orthographic camera along a plane's normal), and
``settings.all_specular_paths = false`` (LuxCore follows every light path, the
event-filtered chains cannot be selected).

Caustic objects are camera-invisible: a light vertex on a receiver connects to the
orthographic camera straight along the normal, through the objects, so the camera
measures the receiver's radiance everywhere, also under the objects.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from scenes.errors import HarnessError
from scenes.geometry import SceneGeometry, TriangleMesh, build_geometry
from scenes.model import DielectricMaterial, PlaneReceiver, PointLight, Scene

__all__ = [
    "CAMERA_DISTANCE",
    "LuxScene",
    "OrthoView",
    "UnsupportedScene",
    "check_supported",
    "receiver_view",
    "translate_scene",
]

#: Distance of the orthographic camera from the receiver plane, in metres. The light
#: tracer weights a receiver vertex by the cosine toward the camera's origin, not along
#: its axis; at this distance that cosine is 1 - 1e-5 at worst on a 10 m receiver, and
#: :mod:`.render` divides it out exactly anyway.
CAMERA_DISTANCE = 1000.0

Variant = Literal["glass", "black", "bare"]


class UnsupportedScene(HarnessError, ValueError):
    """The scene holds something LuxCore cannot render faithfully.

    The message names the scene file and the field path, e.g.
    ``scenes/metal_ring.toml: objects[0].material: conductor has no faithful
    LuxCore equivalent``.
    """


def _problems(scene: Scene) -> list[tuple[str, str]]:
    found = []
    if not isinstance(scene.light, PointLight):
        found.append(("light.type", f"{scene.light.kind} light has no verified LuxCore "
                      "equivalent (only point lights are checked against analytic "
                      "irradiance)"))
    for i, rec in enumerate(scene.receivers):
        if not isinstance(rec, PlaneReceiver):
            found.append((f"receivers[{i}].type", f"{rec.kind} receiver: the receiver map "
                          "is read through an orthographic camera, planes only"))
    for i, obj in enumerate(scene.objects):
        mat, path = obj.material, f"objects[{i}].material"
        if not isinstance(mat, DielectricMaterial):
            found.append((path, f"{mat.kind} has no faithful LuxCore equivalent"))
            continue
        if len(set(mat.iors)) > 1:
            found.append((f"{path}.ior", "dispersion (per-channel IOR) is not translated"))
        if any(a > 0 for a in mat.absorption):
            found.append((f"{path}.absorption", "LuxCore volumes are not verified "
                          "against Beer-Lambert on these paths"))
        if not mat.fresnel:
            found.append((f"{path}.fresnel", "LuxCore's glass always weights by the "
                          "Fresnel factor; set fresnel = true"))
    if scene.objects and not scene.settings.all_specular_paths:
        found.append(("settings.all_specular_paths", "LuxCore follows every light path; "
                      "set all_specular_paths = true"))
    return found


def check_supported(scene: Scene) -> None:
    """Raise :class:`UnsupportedScene` unless LuxCore renders ``scene`` faithfully.

    All problems are listed, one per line, each as ``file: field path: reason``.
    """
    problems = _problems(scene)
    if problems:
        file = scene.source or "<scene>"
        raise UnsupportedScene("\n".join(f"{file}: {path}: {why}" for path, why in problems))


@dataclass(frozen=True)
class OrthoView:
    """An orthographic camera over one plane receiver's (u, v) extent.

    LuxCore's light tracer puts a hit at raster row k into film row ``H' - 2 - k`` (one
    row off, and the hits of the last raster row are dropped), so the film is one row
    taller than the map and its window reaches one texel below ``vmin``: film row j
    then holds exactly map row j (row 0 at vmin) and film row H stays empty.

    Attributes
    ----------
    origin, target, up : tuple of float
        Camera placement in world metres (``up`` is the receiver's +v axis).
    window : tuple of float
        LuxCore ``screenwindow`` (u0, u1, v0, v1) in metres.
    film : tuple of int
        Film (width, height) in pixels: (W, H + 1).
    resolution : tuple of int
        Map (W, H).
    extent : tuple of float
        (umin, umax, vmin, vmax) of the map, metres.
    distance : float
        Camera distance from the plane, metres.
    """

    origin: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float]
    window: tuple[float, float, float, float]
    film: tuple[int, int]
    resolution: tuple[int, int]
    extent: tuple[float, float, float, float]
    distance: float

    def cos_to_origin(self) -> np.ndarray:
        """(H, W) cosine between the plane normal and the direction from each texel
        centre to the camera origin (LuxCore weights a light vertex by it)."""
        umin, umax, vmin, vmax = self.extent
        w, h = self.resolution
        u = umin + (np.arange(w) + 0.5) * (umax - umin) / w
        v = vmin + (np.arange(h) + 0.5) * (vmax - vmin) / h
        # The camera sits over the plane's (u, v) = (0, 0), the receiver's centre.
        rho2 = u[None, :] ** 2 + v[:, None] ** 2
        return self.distance / np.sqrt(self.distance**2 + rho2)


def receiver_view(scene: Scene, index: int, *, resolution: tuple[int, int] | None = None,
                  geometry: SceneGeometry | None = None) -> OrthoView:
    """The orthographic view of ``scene.receivers[index]`` (a plane)."""
    geometry = geometry or build_geometry(scene)
    rec = scene.receivers[index]
    extent = tuple(float(x) for x in geometry.receivers[index].extent)
    w, h = tuple(resolution or scene.settings.receiver_map)
    n = np.asarray(rec.normal, float) / np.linalg.norm(rec.normal)
    u = np.asarray(rec.u_axis, float)
    u = u - n * (u @ n)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    center = np.asarray(rec.center, float)
    umin, umax, vmin, vmax = extent
    dv = (vmax - vmin) / h
    return OrthoView(
        origin=tuple((center + CAMERA_DISTANCE * n).tolist()),
        target=tuple(center.tolist()),
        up=tuple(v.tolist()),
        window=(umin, umax, vmin - dv, vmax),
        film=(int(w), int(h) + 1),
        resolution=(int(w), int(h)),
        extent=extent,
        distance=CAMERA_DISTANCE,
    )


@dataclass(frozen=True, eq=False)
class LuxScene:
    """A LuxCore scene as plain data, built into pyluxcore objects by the render worker.

    Attributes
    ----------
    meshes : tuple of (str, TriangleMesh)
        Shape name and its world-space triangles (defined with ``Scene.DefineMesh``).
    properties : str
        LuxCore scene properties (``Properties.SetFromString`` syntax).
    """

    meshes: tuple[tuple[str, TriangleMesh], ...]
    properties: str


def _rgb(values) -> str:
    return " ".join(repr(float(x)) for x in values)


def translate_scene(scene: Scene, *, variant: Variant, receiver_albedo: float,
                    view: OrthoView, geometry: SceneGeometry | None = None):
    """Describe the LuxCore scene of one render (meshes and scene properties).

    Parameters
    ----------
    variant
        ``"glass"``: the objects as dielectrics; ``"black"``: the same triangles with a
        black Lambertian material (they absorb every photon); ``"bare"``: no objects.
    receiver_albedo
        Albedo given to every receiver (dimensionless, in (0, 1]); the caller divides
        the measured radiance by it.
    view
        The camera (:func:`receiver_view`).

    Raises
    ------
    UnsupportedScene
        See :func:`check_supported`.
    """
    check_supported(scene)
    geometry = geometry or build_geometry(scene)
    meshes, lines = [], []
    for i, rec in enumerate(geometry.receivers):
        meshes.append((f"receiver{i}", rec.mesh))
        lines += [f"scene.materials.receiver{i}.type = matte",
                  f"scene.materials.receiver{i}.kd = {_rgb([receiver_albedo] * 3)}",
                  f"scene.objects.receiver{i}.shape = receiver{i}",
                  f"scene.objects.receiver{i}.material = receiver{i}"]
    if variant != "bare":
        for i, obj in enumerate(geometry.objects):
            meshes.append((f"object{i}", obj.mesh))
            mat = f"scene.materials.object{i}"
            if variant == "glass":
                lines += [f"{mat}.type = glass", f"{mat}.kr = 1 1 1", f"{mat}.kt = 1 1 1",
                          f"{mat}.interiorior = {float(obj.material.iors[0])!r}",
                          f"{mat}.exteriorior = 1.0", f"{mat}.cauchyb = 0.0"]
            else:
                lines += [f"{mat}.type = matte", f"{mat}.kd = 0 0 0"]
            lines += [f"scene.objects.object{i}.shape = object{i}",
                      f"scene.objects.object{i}.material = object{i}",
                      f"scene.objects.object{i}.camerainvisible = 1"]
    light = scene.light
    lines += ["scene.lights.light.type = point",
              f"scene.lights.light.position = {_rgb(light.position)}",
              "scene.lights.light.color = 1 1 1",
              f"scene.lights.light.gain = {_rgb(4 * np.pi * np.asarray(light.intensity))}",
              "scene.camera.type = orthographic",
              f"scene.camera.lookat.orig = {_rgb(view.origin)}",
              f"scene.camera.lookat.target = {_rgb(view.target)}",
              f"scene.camera.up = {_rgb(view.up)}",
              f"scene.camera.screenwindow = {_rgb(view.window)}",
              "scene.camera.cliphither = 0", "scene.camera.clipyon = 1e30"]
    return LuxScene(tuple(meshes), "\n".join(lines) + "\n")
