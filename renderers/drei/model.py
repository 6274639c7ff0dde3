"""A NumPy model of drei's caustic pass on analytic spheres, and what changing one of
its choices at a time does: the tool that measures what a single refraction, the
far-plane area and the placement cost (``docs/drei-caustics.md``).

The component's pass, as its shader (``@pmndrs/vanilla`` ``core/Caustics.js``) computes
it, written out:

1. **Light camera.** Orthographic, looking along the light's travel direction -l at
   the centre f of the objects' bounding box, from f + l D with
   D = max over the box's corners of (corner - f) . l; it sees ``radius`` either side,
   the largest distance of the box's corners from their centroid on the plane normal
   to l. Its far distance is the one at which its top edge reaches the ground:
   ``far = (eye_y + radius y_y) / l_y`` (y its up axis).
2. **Per texel** (centre (s, t)), four rays along -l from the corners of a square of
   side ``worldRadius`` around it, each from its point on the camera's plane. If the
   centre's or any corner's ray misses every object, the texel is 0. Otherwise each
   refracts once at its front hit (normal N from an 8-bit texture;
   ``refract(-l, N, 1 / ior)``), steps 0.1 along the new direction, and meets the
   **far plane** (normal to l). With A_near and A_far the areas of the quadrilateral
   (two triangles (1, 2, 3) and (1, 3, 4), their cross products' lengths), the texel
   holds ``intensity * A_near / A_far``.
3. **Placement.** The texture is drawn on the ground through the light camera: where
   the *unrefracted* ray through the texel meets it (:mod:`renderers.drei.mapping`).

The model's switches, each one of the component's choices replaced by the physics:

* ``refractions = 2``: the rays also refract out of the sphere at their exit point
  (the closed object's second interface), then meet the far plane;
* ``placement = "landing"``: every texel's beam, flux E0 x (its area normal to the
  light), is carried along its refracted path (two refractions) to the ground and
  deposited where it lands: a photon map on the texture's grid, ``points`` x
  ``points`` rays per texel, no area ratio and no far plane;
* ``fresnel = True``: each interface passes only the unpolarised Fresnel
  transmittance;
* ``quantised_normals = False``: exact normals instead of 8-bit ones.

Only spheres are modelled (their hits and normals are exact, where the component
reads a tessellation's depth and interpolated normals); the texture's sampling
(nearest depth, bilinear normals) is not.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Literal

import numpy as np

from renderers.drei.mapping import LightCamera, light_affine, receiver_map
from renderers.drei.params import (
    DEFAULT_WORLD_RADIUS,
    DreiParams,
    DreiSceneError,
    drei_params,
    refuse_unrepresentable,
)
from renderers.results import ReceiverMap, RenderResult
from scenes import Scene
from scenes.export import GLTF_FROM_SCENE, receiver_frame, to_gltf
from scenes.geometry import build_geometry
from scenes.model import SphereObject

__all__ = ["DreiModel", "Spheres", "fresnel_transmittance", "light_camera", "refract",
           "trace_texture"]

#: How far the component steps along the refracted ray before meeting the far plane, m.
STEP = 0.1


@dataclass(frozen=True)
class Spheres:
    """Analytic spheres in the drei frame: centres (k, 3) and radii (k,), m."""

    centers: np.ndarray
    radii: np.ndarray

    def hit(self, origins: np.ndarray, direction: np.ndarray, *, far: bool = False
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Nearest front (or, with ``far``, the same sphere's exit) hit of rays
        ``origins + t direction`` (one unit direction, or one per ray): (t, point,
        outward normal); t is inf where a ray misses."""
        d = np.broadcast_to(direction, origins.shape)
        best = np.full(origins.shape[:-1], np.inf)
        normal = np.zeros_like(origins)
        for center, radius in zip(self.centers, self.radii, strict=True):
            oc = origins - center
            b = np.einsum("...i,...i", oc, d)
            disc = b * b - (np.einsum("...i,...i", oc, oc) - radius * radius)
            root = np.sqrt(np.maximum(disc, 0.0))
            t = -b + root if far else -b - root
            ok = (disc >= 0) & (t > (-1e-9 if far else 0.0)) & (t < best)
            best = np.where(ok, t, best)
            hit = origins + t[..., None] * d
            normal = np.where(ok[..., None], (hit - center) / radius, normal)
        points = origins + np.where(np.isfinite(best), best, 0.0)[..., None] * d
        return best, points, normal


def refract(incident: np.ndarray, normal: np.ndarray, eta: float) -> np.ndarray:
    """GLSL's ``refract(I, N, eta)`` (zero where light is totally reflected)."""
    incident = np.broadcast_to(incident, normal.shape)
    cos = np.einsum("...i,...i", normal, incident)
    k = 1.0 - eta * eta * (1.0 - cos * cos)
    out = eta * incident - (eta * cos + np.sqrt(np.maximum(k, 0.0)))[..., None] * normal
    return np.where((k >= 0)[..., None], out, 0.0)


def fresnel_transmittance(cos_in: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel transmittance 1 - (R_s + R_p) / 2 for light arriving at
    cos_in (> 0) from a medium of index n1 into n2, eta = n1 / n2."""
    sin_t2 = eta * eta * (1.0 - cos_in * cos_in)
    cos_t = np.sqrt(np.maximum(1.0 - sin_t2, 0.0))
    rs = ((eta * cos_in - cos_t) / (eta * cos_in + cos_t)) ** 2
    rp = ((eta * cos_t - cos_in) / (eta * cos_t + cos_in)) ** 2
    return np.where(sin_t2 < 1.0, 1.0 - 0.5 * (rs + rp), 0.0)


def light_camera(spheres: Spheres, towards_light, *, near: float
                 ) -> tuple[LightCamera, float, np.ndarray]:
    """The component's light camera for ``spheres`` (module docstring, step 1):
    (camera, far, eye). The bounding box is the analytic spheres'."""
    lo = (spheres.centers - spheres.radii[:, None]).min(axis=0)
    hi = (spheres.centers + spheres.radii[:, None]).max(axis=0)
    focus = (lo + hi) / 2
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])]) - focus
    light = np.asarray(towards_light, float) / np.linalg.norm(towards_light)
    projected = corners - np.outer(corners @ light, light)
    radius = float(np.linalg.norm(projected - projected.mean(axis=0), axis=1).max())
    eye = focus + light * float((corners @ light).max())
    x = np.cross([0.0, 1.0, 0.0], light)
    x /= np.linalg.norm(x)
    y = np.cross(light, x)
    far = float((eye[1] + radius * y[1]) / light[1])
    world = np.eye(4)
    world[:3, 0], world[:3, 1], world[:3, 2], world[:3, 3] = x, y, light, eye
    projection = np.array([[1 / radius, 0, 0, 0], [0, 1 / radius, 0, 0],
                           [0, 0, -2 / (far - near), -(far + near) / (far - near)],
                           [0, 0, 0, 1]])
    return (LightCamera(projection, np.linalg.inv(world), -radius, radius, -radius, radius),
            far, eye)


def _plane_points(camera: LightCamera, eye, resolution: int, offsets) -> np.ndarray:
    """Points on the camera's plane of every texel centre plus ``offsets`` (m along
    the camera's x and y): (res, res, len(offsets), 3), row 0 at t = 0."""
    world = np.linalg.inv(camera.view)
    x, y = world[:3, 0], world[:3, 1]
    centres = camera.left + (np.arange(resolution) + 0.5) * (camera.right - camera.left
                                                            ) / resolution
    cx = centres[None, :, None] + np.asarray(offsets)[None, None, :, 0]
    cy = centres[:, None, None] + np.asarray(offsets)[None, None, :, 1]
    return eye + cx[..., None] * x + cy[..., None] * y


def _exit(spheres: Spheres, points, inside, ior: float):
    """Second refraction: from ``points`` inside along ``inside``, out through the
    sphere's far side: (exit points, outgoing direction, cos at the exit)."""
    length = np.linalg.norm(inside, axis=-1, keepdims=True)
    inside = inside / np.where(length > 0, length, 1.0)
    _, exits, normal = spheres.hit(points, inside, far=True)
    cos = np.einsum("...i,...i", inside, normal)
    return exits, refract(inside, -normal, ior), cos


def _quantise(normal: np.ndarray) -> np.ndarray:
    """8 bits per component, as the component's normal render target stores them."""
    return np.round((normal * 0.5 + 0.5) * 255.0) / 255.0 * 2.0 - 1.0


def trace_texture(spheres: Spheres, params: DreiParams, ior: float, *,
                  refractions: int = 1, fresnel: bool = False,
                  quantised_normals: bool = True) -> tuple[np.ndarray, LightCamera]:
    """The caustic texture (res, res), W/m², and the light camera (module docstring,
    steps 1 and 2)."""
    camera, far, eye = light_camera(spheres, params.light_source, near=params.near)
    light = np.asarray(params.light_source)
    half = params.world_radius / 2
    corners = [(-half, -half), (-half, half), (half, half), (half, -half)]
    origins = _plane_points(camera, eye, params.resolution, [(0.0, 0.0), *corners])
    t, points, normal = spheres.hit(origins, -light)
    lit = np.isfinite(t).all(axis=-1)
    points, normal = points[..., 1:, :], normal[..., 1:, :]
    if quantised_normals:
        normal = _quantise(normal)
    direction = refract(-light, normal, 1.0 / ior)
    weight = np.ones(points.shape[:-1])
    if fresnel:
        weight *= fresnel_transmittance(-np.einsum("...i,...i", normal, -light), 1.0 / ior)
    start = points + STEP * direction
    if refractions == 2:
        start, direction, cos = _exit(spheres, points, direction, ior)
        if fresnel:
            weight *= fresnel_transmittance(cos, ior)
    # The far plane: normal l, at distance `far` from the eye along -l.
    plane_point = eye - far * light
    denominator = direction @ light
    safe = np.where(np.abs(denominator) > 1e-12, denominator, np.nan)
    final = start + ((plane_point - start) @ light / safe)[..., None] * direction
    o = origins[..., 1:, :]

    def area(p):
        return (np.linalg.norm(np.cross(p[..., 1, :] - p[..., 0, :], p[..., 2, :] - p[..., 0, :]),
                               axis=-1)
                + np.linalg.norm(np.cross(p[..., 2, :] - p[..., 0, :],
                                          p[..., 3, :] - p[..., 0, :]), axis=-1))

    ratio = area(o) / area(final)
    # The shader weights nothing; with Fresnel the beam keeps its corners' mean share.
    value = params.intensity * ratio * weight.mean(axis=-1)
    texture = np.where(lit & np.isfinite(value), np.maximum(value, 0.0), 0.0)
    return texture, camera


def land(spheres: Spheres, params: DreiParams, ior: float, frame, *, points: int = 2,
         fresnel: bool = False) -> tuple[np.ndarray, float]:
    """Photon map on the texture's grid (``placement = "landing"``): irradiance (H, W)
    of the brightest channel, W/m², row 0 at vmin; and the flux that does not land on
    the receiver (leaving upwards, or off its extent), W."""
    camera, _, eye = light_camera(spheres, params.light_source, near=params.near)
    light = np.asarray(params.light_source)
    texel = (camera.right - camera.left) / params.resolution
    offsets = [((i + 0.5) / points - 0.5) * texel for i in range(points)]
    origins = _plane_points(camera, eye, params.resolution,
                            [(a, b) for a in offsets for b in offsets]).reshape(-1, 3)
    t, hits, normal = spheres.hit(origins, -light)
    ok = np.isfinite(t)
    hits, normal = hits[ok], normal[ok]
    inside = refract(-light, normal, 1.0 / ior)
    weight = np.ones(len(hits))
    if fresnel:
        weight *= fresnel_transmittance(normal @ light, 1.0 / ior)
    exits, out, cos = _exit(spheres, hits, inside, ior)
    if fresnel:
        weight *= fresnel_transmittance(cos, ior)
    down = out[:, 1] < 0
    ground = exits - (exits[:, 1] / np.where(down, out[:, 1], -1.0))[:, None] * out
    scene_points = (ground + np.array([0.0, params.height, 0.0])) @ GLTF_FROM_SCENE
    u = (scene_points - frame.origin) @ np.asarray(frame.u_axis)
    v = (scene_points - frame.origin) @ np.asarray(frame.v_axis)
    umin, umax, vmin, vmax = frame.extent
    width, height = frame.resolution
    column = np.floor((u - umin) / (umax - umin) * width).astype(np.int64)
    row = np.floor((v - vmin) / (vmax - vmin) * height).astype(np.int64)
    inside_map = down & (column >= 0) & (column < width) & (row >= 0) & (row < height)
    flux = (params.intensity / params.cos_theta) * (texel / points) ** 2 * weight
    cell = (umax - umin) * (vmax - vmin) / (width * height)
    counts = np.bincount(row[inside_map] * width + column[inside_map],
                         weights=flux[inside_map], minlength=width * height)
    return (counts / cell).reshape(height, width), float(flux[~inside_map].sum())


@dataclass(frozen=True, eq=False)
class DreiModel:
    """The model as a method (for ``harness.api.compare``): its receiver map only; its
    camera image is black (the model has none).

    Parameters
    ----------
    name : str
    refractions : {1, 2}
    placement : {"entry", "landing"}
    fresnel, quantised_normals : bool
    world_radius : float
        m.
    """

    name: str = "drei-model"
    refractions: int = 1
    placement: Literal["entry", "landing"] = "entry"
    fresnel: bool = False
    quantised_normals: bool = True
    world_radius: float = DEFAULT_WORLD_RADIUS
    description: str = "NumPy model of drei's caustic pass on analytic spheres"

    def configure(self, scene: Scene) -> Scene:
        """``scene`` unchanged; refused unless drei can represent it and every object
        is a sphere."""
        refuse_unrepresentable(scene)
        for i, obj in enumerate(scene.objects):
            if not isinstance(obj, SphereObject):
                raise DreiSceneError(scene.source, f"objects[{i}].type",
                                     f"the model traces spheres only, not {obj.kind}")
        return scene

    def render(self, scene: Scene) -> RenderResult:
        """The model's receiver map (module docstring)."""
        start = time.perf_counter()
        self.configure(scene)
        geometry = build_geometry(scene)
        positions = np.concatenate([o.mesh.positions for o in geometry.objects])
        params = drei_params(scene, objects_radius=float(np.linalg.norm(np.ptp(positions,
                                                                               axis=0)) / 2),
                             resolution=scene.settings.caustic_map,
                             world_radius=self.world_radius)
        offset = np.array([0.0, params.height, 0.0])
        spheres = Spheres(np.array([to_gltf(o.center) - offset for o in scene.objects]),
                          np.array([o.radius for o in scene.objects], float))
        frame = receiver_frame(scene.receivers[0], geometry.receivers[0],
                               scene.settings.receiver_map)[0]
        channels = []
        for n in params.passes:
            if self.placement == "landing":
                channels.append(land(spheres, params, n, frame, fresnel=self.fresnel)[0])
                continue
            texture, camera = trace_texture(spheres, params, n, refractions=self.refractions,
                                            fresnel=self.fresnel,
                                            quantised_normals=self.quantised_normals)
            affine = light_affine(camera, frame, height=params.height)
            mapped = receiver_map(np.stack([texture] * 3), affine, frame)
            channels.append(mapped.irradiance[..., 0])
        irradiance = np.stack([params.channel_scale[c] * channels[params.channel_pass[c]]
                               for c in range(3)], axis=-1)
        width, height = scene.camera.resolution
        seconds = time.perf_counter() - start
        return RenderResult(
            renderer=self.name, camera=np.zeros((height, width, 3), np.float32),
            receivers=(ReceiverMap(irradiance.astype(np.float32), frame.extent),),
            effects=("refraction.double" if self.refractions == 2 else "refraction.single",
                     *(("fresnel",) if self.fresnel else ())),
            timings={"model": seconds}, timer="time.perf_counter around the NumPy model",
            metadata={"refractions": self.refractions, "placement": self.placement,
                      "fresnel": self.fresnel, "quantised_normals": self.quantised_normals,
                      "world_radius": self.world_radius})
