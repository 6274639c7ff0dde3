"""An exact camera image of a dielectric sphere over a plane, for the camera checks
of both renderers (the camera requirements and targets of ``compare``, and the
renderers' camera tests).

Everything is closed-form ray geometry, independent of both renderers' code:
primary rays of the scene's pinhole (:mod:`scenes.camera`) through stratified
subpixel positions and, written here, ray–sphere intersection of the *ideal*
sphere (not its icosphere), Snell refraction in at the front and out at the back
(no total internal reflection can occur: a ray that enters a sphere leaves it at
the angle it entered), and the exit ray's hit on the receiver plane. The receiver
is shaded like the radiometric contract's Lambertian receiver::

    L = albedo / pi * (E_direct * V + E_caustic)

with E_direct the light's analytic irradiance (point: I cos(theta) / d^2;
directional: E cos(theta)), V = 0 where the segment to the light meets the sphere
(only with the ``shadows`` effect), and E_caustic read with bilinear filtering in
a given caustic receiver map (for example the reference's own), or 0.

With the ``fresnel`` effect each of the two interfaces transmits 1 - F (Fresnel's
unpolarised reflectance); the ``absorption`` effect multiplies by
exp(-K_a * inside path length) (Beer–Lambert); with dispersion each channel
refracts with its own IOR. Only the chain the photon tracer counts through a
closed dielectric is followed (two transmissions): reflected light is not.

A camera pixel whose refracted ray misses the receiver sees the empty sky and is
black. For the paper's glass sphere about 44 % of the sphere's pixels are black,
which a single refraction to a plane does not reproduce.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from renderers.results import ReceiverMap
from scenes import effects_of
from scenes.camera import pinhole_directions
from scenes.colour import luminance
from scenes.model import (
    DielectricMaterial,
    DirectionalLight,
    PlaneReceiver,
    PointLight,
    Scene,
    SphereObject,
)

#: ``luminance`` (Rec. 709, :func:`scenes.colour.luminance`) is importable from
#: here beside the black level it is compared with.
__all__ = ["BLACK_LEVEL", "SphereCamera", "analytic_sphere_camera", "black_fraction",
           "luminance"]

#: A pixel is black when its luminance is below this fraction of the image's
#: 99th-percentile luminance: far below any lit pixel (the darkest lit floor pixel of
#: glass_sphere is about 1e-2 of it), far above float noise of a black one.
BLACK_LEVEL = 1e-4


def black_fraction(image: np.ndarray, mask: np.ndarray) -> float:
    """Fraction of the ``mask`` pixels of ``image`` (H, W, 3) that are black (see
    :data:`BLACK_LEVEL`); NaN for an empty mask."""
    lum = luminance(np.asarray(image, np.float64))
    if not mask.any():
        return float("nan")
    top = float(np.percentile(lum, 99))
    return float(np.mean(lum[mask] <= BLACK_LEVEL * top))


@dataclass(frozen=True)
class SphereCamera:
    """The exact camera image and its masks.

    Attributes
    ----------
    image : ndarray, (H, W, 3), float64
        Radiance, W m^-2 sr^-1, row 0 at the top; the mean of the subpixel samples.
    sphere : ndarray, (H, W), bool
        Pixels whose centre ray hits the ideal sphere.
    interior : ndarray, (H, W), bool
        ``sphere`` shrunk by one pixel: pixels every renderer's tessellation and
        rasterisation agree are inside.
    floor : ndarray, (H, W), bool
        Pixels whose every subpixel ray sees the receiver plane directly.
    black_fraction : float
        :func:`black_fraction` of ``image`` over ``interior``.
    """

    image: np.ndarray
    sphere: np.ndarray
    interior: np.ndarray
    floor: np.ndarray
    black_fraction: float


def _refract(d: np.ndarray, n: np.ndarray, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """Snell refraction of unit ``d`` at unit ``n`` (facing against ``d``) with
    eta = n_from / n_to; returns (direction, cos of the incident angle)."""
    cos_i = -np.sum(d * n, axis=-1)
    k = 1 - eta**2 * (1 - cos_i**2)
    t = eta * d + (eta * cos_i - np.sqrt(np.maximum(k, 0)))[..., None] * n
    return t / np.linalg.norm(t, axis=-1, keepdims=True), cos_i


def _fresnel(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance for incidence cosine ``cos_i``, eta = n1/n2."""
    sin_t2 = eta**2 * (1 - cos_i**2)
    cos_t = np.sqrt(np.maximum(1 - sin_t2, 0))
    rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return np.where(sin_t2 >= 1, 1.0, 0.5 * (rs**2 + rp**2))


def _sphere_hits(o, d, center, radius):
    """Near and far distances along unit ``d`` to the sphere (NaN where missed)."""
    oc = o - center
    b = np.sum(oc * d, axis=-1)
    disc = b * b - (np.sum(oc * oc, axis=-1) - radius * radius)
    root = np.sqrt(np.where(disc >= 0, disc, np.nan))
    return -b - root, -b + root


def _plane_hit(o, d, receiver: PlaneReceiver):
    """Hit point and (u, v) on the receiver rectangle; NaN rows where missed."""
    n = np.asarray(receiver.normal, float)
    n /= np.linalg.norm(n)
    u_axis = np.asarray(receiver.u_axis, float)
    u_axis = u_axis - n * (u_axis @ n)
    u_axis /= np.linalg.norm(u_axis)
    v_axis = np.cross(n, u_axis)
    c = np.asarray(receiver.center, float)
    den = d @ n
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((c - o) @ n) / den
    t = np.where(t > 1e-9, t, np.nan)
    x = o + t[..., None] * d
    u, v = (x - c) @ u_axis, (x - c) @ v_axis
    half = np.asarray(receiver.size, float) / 2
    inside = (np.abs(u) <= half[0]) & (np.abs(v) <= half[1])
    x[~inside] = np.nan
    return x, np.where(inside, u, np.nan), np.where(inside, v, np.nan), n


def _bilinear(caustic: ReceiverMap, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Bilinear lookup of (N,) (u, v) in the map (texel centres, clamped edges)."""
    h, w = caustic.irradiance.shape[:2]
    umin, umax, vmin, vmax = caustic.extent
    fx = np.clip((u - umin) / (umax - umin) * w - 0.5, 0, w - 1)
    fy = np.clip((v - vmin) / (vmax - vmin) * h - 0.5, 0, h - 1)
    x0, y0 = np.floor(fx).astype(int), np.floor(fy).astype(int)
    x1, y1 = np.minimum(x0 + 1, w - 1), np.minimum(y0 + 1, h - 1)
    ax, ay = (fx - x0)[:, None], (fy - y0)[:, None]
    e = caustic.irradiance.astype(np.float64)
    return ((1 - ay) * ((1 - ax) * e[y0, x0] + ax * e[y0, x1])
            + ay * ((1 - ax) * e[y1, x0] + ax * e[y1, x1]))


def _direct(scene: Scene, x, n, center, radius, *, shadows: bool) -> np.ndarray:
    """Direct irradiance (N, 3), W/m², at receiver points ``x`` with normal ``n``."""
    light = scene.light
    if isinstance(light, PointLight):
        to_light = np.asarray(light.position, float) - x
        dist = np.linalg.norm(to_light, axis=-1)
        l_dir = to_light / dist[:, None]
        e = np.asarray(light.intensity, float) * (np.clip(l_dir @ n, 0, None) / dist**2)[:, None]
    elif isinstance(light, DirectionalLight):
        l_dir = -np.asarray(light.direction, float) / np.linalg.norm(light.direction)
        l_dir = np.broadcast_to(l_dir, x.shape)
        dist = np.full(len(x), np.inf)
        e = np.asarray(light.irradiance, float) * np.clip(l_dir @ n, 0, None)[:, None]
    else:
        raise ValueError(f"analytic sphere camera: unsupported light {light.kind!r}")
    if shadows:
        near, far = _sphere_hits(x, l_dir, center, radius)
        blocked = np.isfinite(near) & (far > 0) & (near < dist)
        e[blocked] = 0
    return e


def analytic_sphere_camera(scene: Scene, caustic: ReceiverMap | None = None, *,
                           supersample: int = 2) -> SphereCamera:
    """The exact camera image of ``scene``: one dielectric sphere over one plane.

    Parameters
    ----------
    scene : Scene
        A scene with one ``sphere`` object of a dielectric material and a ``plane``
        receiver (receiver 0), lit by a point or directional light.
    caustic : ReceiverMap, optional
        Caustic irradiance of receiver 0 (W/m²), added to the direct light; none
        when omitted.
    supersample : int
        Stratified subpixel samples per axis (stratum centres).

    Returns
    -------
    SphereCamera
    """
    (sphere,) = scene.objects
    receiver = scene.receivers[0]
    if not isinstance(sphere, SphereObject) or not isinstance(sphere.material,
                                                               DielectricMaterial):
        raise ValueError("analytic sphere camera: needs one dielectric sphere object")
    if not isinstance(receiver, PlaneReceiver):
        raise ValueError("analytic sphere camera: receiver 0 must be a plane")
    effects = effects_of(scene)
    material = sphere.material
    center, radius = np.asarray(sphere.center, float), float(sphere.radius)
    cam = scene.camera
    width, height = cam.resolution
    s = int(supersample)

    # Film positions (pixels from the left / top edge) of the stratum centres.
    sub = (np.arange(s) + 0.5) / s
    px = (np.arange(width)[:, None] + sub[None, :]).ravel()      # (W*s,)
    py = (np.arange(height)[:, None] + sub[None, :]).ravel()     # (H*s,)
    d = pinhole_directions(cam, *np.meshgrid(px, py)).reshape(-1, 3)
    o = np.broadcast_to(np.asarray(cam.position, float), d.shape)

    near, _ = _sphere_hits(o, d, center, radius)
    on_sphere = np.isfinite(near) & (near > 0)
    x_floor, u_floor, v_floor, n_plane = _plane_hit(o, d, receiver)
    sees_floor = ~on_sphere & np.isfinite(u_floor)
    albedo = np.asarray(receiver.albedo, float)
    shadows = "shadows" in effects
    direct = scene.info.direct_lighting

    def shade(x, u, v):
        e = np.zeros((len(x), 3))
        if direct:
            e += _direct(scene, x, n_plane, center, radius, shadows=shadows)
        if caustic is not None:
            e += _bilinear(caustic, u, v)
        return albedo / np.pi * e

    radiance = np.zeros((len(d), 3))
    radiance[sees_floor] = shade(x_floor[sees_floor], u_floor[sees_floor], v_floor[sees_floor])

    # Through the sphere: in at the near hit, out at the far hit, then to the plane.
    idx = np.flatnonzero(on_sphere)
    p1 = o[idx] + near[idx, None] * d[idx]
    n1 = (p1 - center) / radius
    channels = [0, 1, 2] if "dispersion" in effects else [None]
    for c in channels:
        ior = material.iors[0 if c is None else c]
        t1, cos1 = _refract(d[idx], n1, 1 / ior)
        # From inside, the second hit along t1 is 2 * (-(p1 - c) . t1) away.
        length = -2 * np.sum((p1 - center) * t1, axis=-1)
        p2 = p1 + length[:, None] * t1
        n2 = -(p2 - center) / radius                      # faces against t1
        t2, cos2 = _refract(t1, n2, ior)
        weight = np.ones((len(idx), 3))
        if "fresnel" in effects:
            weight *= ((1 - _fresnel(cos1, 1 / ior)) * (1 - _fresnel(cos2, ior)))[:, None]
        if "absorption" in effects:
            weight *= np.exp(-np.outer(length, np.asarray(material.absorption, float)))
        x, u, v, _ = _plane_hit(p2, t2, receiver)
        hit = np.isfinite(u)
        lit = np.zeros((len(idx), 3))
        lit[hit] = shade(x[hit], u[hit], v[hit]) * weight[hit]
        if c is None:
            radiance[idx] = lit
        else:
            radiance[idx, c] = lit[:, c]

    image = radiance.reshape(height, s, width, s, 3).mean(axis=(1, 3))
    centre = (s - 1) // 2 if s % 2 else None
    hits = on_sphere.reshape(height, s, width, s)
    sphere_mask = (hits[:, centre, :, centre] if centre is not None
                   else hits.mean(axis=(1, 3)) >= 0.5)
    interior = sphere_mask.copy()
    interior[1:] &= sphere_mask[:-1]
    interior[:-1] &= sphere_mask[1:]
    interior[:, 1:] &= sphere_mask[:, :-1]
    interior[:, :-1] &= sphere_mask[:, 1:]
    floor = sees_floor.reshape(height, s, width, s).all(axis=(1, 3))
    return SphereCamera(image=image, sphere=sphere_mask, interior=interior, floor=floor,
                        black_fraction=black_fraction(image, interior))
