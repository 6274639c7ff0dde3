"""The caustic of an ideal glass sphere, by ray optics in NumPy: an answer that owes
nothing to either renderer, for the physical requirements on the reference.

Scene: one dielectric sphere (centre C, radius R, IOR n per channel, absorption σ per
channel, Fresnel on or off), a point light (intensity I, W/sr) or a directional light
(irradiance E0 on a plane facing it, W/m²), plane receivers. The light paths counted
are the reference's: light → refraction into the sphere → refraction out → the first
receiver plane (L T T D).

Sampling. Point light: directions in the cone the sphere subtends, uniform in solid
angle (Ω = 2π (1 − cos α), sin α = R / |C − L|), stratified on an n × n grid of
(cos θ, φ); each ray carries I Ω / n². Directional light: the sphere's shadow disk
(area π R²), uniform in area (stratified in b² and φ); each ray carries E0 π R² / n².

Per ray, with d the unit direction and m the unit outward normal at the hit:

    refraction (η = n_i / n_t, cos_i = −d·m):  t = η d + (η cos_i − √(1 − η² (1 − cos_i²))) m
    chord inside the sphere:                   s = −2 t·(P₁ − C)
    Fresnel (unpolarised), when enabled:       weight (1 − F(entry)) (1 − F(exit))
    absorption (Beer–Lambert):                 weight exp(−σ s)

A sphere cannot trap light (the exit angle equals the entry's refraction angle, always
below the critical angle), so no path is lost to total internal reflection; the rays
that leave are those deflected past the receivers' edges or upward. Irradiance per
texel = landing flux / texel area.

The mesh both renderers see is an icosphere whose flat faces lie inside the ideal
sphere: :func:`tessellation_deficit` bounds the flux it misses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scenes import Scene
from scenes.model import (
    DielectricMaterial,
    DirectionalLight,
    PlaneReceiver,
    PointLight,
    SphereObject,
)

__all__ = ["IdealSphereCaustic", "ideal_sphere_caustic", "not_applicable",
           "tessellation_deficit"]


@dataclass(frozen=True, eq=False)
class IdealSphereCaustic:
    """The ideal sphere's caustic on each receiver.

    Attributes
    ----------
    maps : list of ndarray (H, W, 3)
        Irradiance (W/m²) per receiver, over the extents asked for.
    flux : ndarray (R, 3)
        Flux landing on each receiver inside its extent (W).
    entering : ndarray (3,)
        Flux the light sends into the sphere (W).
    focus : list of (float, float)
        (u, v) where the light's axis through the sphere's centre meets each receiver
        plane (the caustic's axis of symmetry; nan where it does not meet it).
    rays : int
        Rays traced per channel.
    """

    maps: list
    flux: np.ndarray
    entering: np.ndarray
    focus: list
    rays: int


def not_applicable(scene: Scene) -> str | None:
    """Why the ideal-sphere answer does not describe ``scene`` (None when it does)."""
    if len(scene.objects) != 1 or not isinstance(scene.objects[0], SphereObject):
        return "not a single sphere"
    if not isinstance(scene.objects[0].material, DielectricMaterial):
        return "the sphere is not a dielectric"
    if not isinstance(scene.light, PointLight | DirectionalLight):
        return "not a point or directional light"
    if not all(isinstance(r, PlaneReceiver) for r in scene.receivers):
        return "a receiver is not a plane"
    if scene.settings.all_specular_paths:
        return "all specular paths are counted, not only the two refractions"
    if isinstance(scene.light, PointLight):
        centre = np.asarray(scene.objects[0].center, float)
        if np.linalg.norm(centre - np.asarray(scene.light.position, float)) <= \
                scene.objects[0].radius:
            return "the light is inside the sphere"
    return None


def _basis(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.array([1.0, 0.0, 0.0]) if abs(w[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(w, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(w, e1)


def _refract(d: np.ndarray, m: np.ndarray, eta: float):
    """Refract unit ``d`` at unit normal ``m`` facing against it; (t, cos_i, ok)."""
    cos_i = -np.einsum("ij,ij->i", d, m)
    sin2_t = eta * eta * np.maximum(0.0, 1.0 - cos_i * cos_i)
    ok = sin2_t <= 1.0
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    t = eta * d + (eta * cos_i - cos_t)[:, None] * m
    return t, cos_i, cos_t, ok


def _fresnel(cos_i: np.ndarray, cos_t: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance; eta = n_i / n_t."""
    rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return 0.5 * (rs * rs + rp * rp)


def _plane_frame(receiver: PlaneReceiver):
    n = np.asarray(receiver.normal, float)
    n /= np.linalg.norm(n)
    u = np.asarray(receiver.u_axis, float)
    u = u - (u @ n) * n
    u /= np.linalg.norm(u)
    return np.asarray(receiver.center, float), n, u, np.cross(n, u)


def _rays(scene: Scene, n: int):
    """Origins, unit directions, flux per ray (3,), entering flux (3,), axis point/dir."""
    sphere = scene.objects[0]
    centre, radius = np.asarray(sphere.center, float), float(sphere.radius)
    a = (np.arange(n) + 0.5) / n
    u1, u2 = (x.ravel() for x in np.meshgrid(a, a, indexing="ij"))
    phi = 2 * np.pi * u2
    light = scene.light
    if isinstance(light, PointLight):
        origin = np.asarray(light.position, float)
        axis = centre - origin
        dist = float(np.linalg.norm(axis))
        axis /= dist
        cos_max = np.sqrt(1.0 - (radius / dist) ** 2)
        cos_t = 1.0 - u1 * (1.0 - cos_max)
        sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
        e1, e2 = _basis(axis)
        d = (cos_t[:, None] * axis + (sin_t * np.cos(phi))[:, None] * e1
             + (sin_t * np.sin(phi))[:, None] * e2)
        solid_angle = 2 * np.pi * (1.0 - cos_max)
        entering = np.asarray(light.intensity, float) * solid_angle
        origins = np.broadcast_to(origin, d.shape)
        return origins, d, entering / (n * n), entering, origin, axis
    axis = np.asarray(light.direction, float)
    axis /= np.linalg.norm(axis)
    e1, e2 = _basis(axis)
    b = radius * np.sqrt(u1)
    origins = (centre - 4 * radius * axis + (b * np.cos(phi))[:, None] * e1
               + (b * np.sin(phi))[:, None] * e2)
    d = np.broadcast_to(axis, origins.shape)
    entering = np.asarray(light.irradiance, float) * np.pi * radius**2
    return origins, d, entering / (n * n), entering, centre, axis


#: The last few answers, by what they depend on (a comparison of several methods asks
#: for the same one once per method; each costs about 1.7 s on one core at n = 1536).
_ANSWERS: dict[str, IdealSphereCaustic] = {}
_KEPT = 4


def ideal_sphere_caustic(scene: Scene, extents, resolutions, *, n: int = 2048,
                         chunk: int = 1 << 20) -> IdealSphereCaustic:
    """Trace ``n²`` rays per distinct IOR through the ideal sphere of ``scene`` (see
    the module docstring) and bin them on each receiver; an answer already computed for
    the same sphere, light, receivers, extents, sizes and ``n`` is returned again (its
    arrays read-only).

    Parameters
    ----------
    extents : list of (umin, umax, vmin, vmax)
        Each receiver's map extent (metres along its u and v axes).
    resolutions : list of (H, W)
        Each receiver's map size.
    """
    reason = not_applicable(scene)
    if reason is not None:
        raise ValueError(f"{scene.name}: no ideal-sphere answer ({reason})")
    key = repr((scene.objects[0], scene.light, scene.receivers,
                [tuple(map(float, e)) for e in extents],
                [tuple(map(int, r)) for r in resolutions], n))
    if key not in _ANSWERS:
        answer = _trace_ideal_sphere(scene, extents, resolutions, n=n, chunk=chunk)
        for array in (*answer.maps, answer.flux, answer.entering):
            array.setflags(write=False)
        while len(_ANSWERS) >= _KEPT:
            _ANSWERS.pop(next(iter(_ANSWERS)))
        _ANSWERS[key] = answer
    return _ANSWERS[key]


def _trace_ideal_sphere(scene: Scene, extents, resolutions, *, n: int,
                        chunk: int) -> IdealSphereCaustic:
    sphere = scene.objects[0]
    material = sphere.material
    centre, radius = np.asarray(sphere.center, float), float(sphere.radius)
    ior = np.broadcast_to(np.asarray(material.ior, float), (3,))
    sigma = np.asarray(material.absorption, float)
    frames = [_plane_frame(r) for r in scene.receivers]
    origins, dirs, per_ray, entering, axis_point, axis = _rays(scene, n)
    maps = [np.zeros((h, w, 3)) for h, w in resolutions]
    flux = np.zeros((len(frames), 3))
    for value in np.unique(ior):
        channels = np.flatnonzero(ior == value)
        for start in range(0, len(dirs), chunk):
            o, d = origins[start:start + chunk], dirs[start:start + chunk]
            # Entry: the nearer root of |o + t d − C| = R.
            oc = o - centre
            b = np.einsum("ij,ij->i", oc, d)
            disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius * radius)
            hit = disc > 0
            t_in = -b - np.sqrt(np.maximum(disc, 0.0))
            p1 = o + t_in[:, None] * d
            m1 = (p1 - centre) / radius
            t, cos_i1, cos_t1, _ = _refract(d, m1, 1.0 / value)
            chord = -2.0 * np.einsum("ij,ij->i", t, p1 - centre)
            p2 = p1 + chord[:, None] * t
            m2 = (p2 - centre) / radius
            out, cos_i2, cos_t2, ok = _refract(t, -m2, value)
            weight = np.ones((len(d), 3))
            if material.fresnel:
                keep = (1 - _fresnel(cos_i1, cos_t1, 1.0 / value)) * \
                    (1 - _fresnel(cos_i2, cos_t2, value))
                weight *= keep[:, None]
            weight *= np.exp(-np.outer(chord, sigma))
            alive = hit & ok
            # First receiver plane hit from its front side.
            best = np.full(len(d), np.inf)
            which = np.full(len(d), -1)
            coords = np.zeros((len(d), 2))
            for k, (c, nrm, u, v) in enumerate(frames):
                denom = out @ nrm
                with np.errstate(divide="ignore", invalid="ignore"):
                    tk = ((c - p2) @ nrm) / denom
                x = p2 + np.where(np.isfinite(tk), tk, 0)[:, None] * out
                uu, vv = (x - c) @ u, (x - c) @ v
                umin, umax, vmin, vmax = extents[k]
                inside = (denom < 0) & (tk > 0) & (uu >= umin) & (uu < umax) & \
                    (vv >= vmin) & (vv < vmax)
                closer = inside & (tk < best)
                best = np.where(closer, tk, best)
                which = np.where(closer, k, which)
                coords[closer] = np.stack([uu, vv], axis=1)[closer]
            for k in range(len(frames)):
                sel = alive & (which == k)
                if not sel.any():
                    continue
                h, w = resolutions[k]
                umin, umax, vmin, vmax = extents[k]
                for ch in channels:
                    wts = per_ray[ch] * weight[sel, ch]
                    hist, _, _ = np.histogram2d(coords[sel, 1], coords[sel, 0], bins=(h, w),
                                                range=((vmin, vmax), (umin, umax)),
                                                weights=wts)
                    maps[k][..., ch] += hist
                    flux[k, ch] += wts.sum()
    for k, (h, w) in enumerate(resolutions):
        umin, umax, vmin, vmax = extents[k]
        maps[k] /= (umax - umin) * (vmax - vmin) / (h * w)
    focus = []
    for c, nrm, u, v in frames:
        denom = axis @ nrm
        if abs(denom) < 1e-12:
            focus.append((float("nan"), float("nan")))
            continue
        x = axis_point + ((c - axis_point) @ nrm) / denom * axis
        focus.append((float((x - c) @ u), float((x - c) @ v)))
    return IdealSphereCaustic(maps, flux, entering, focus, n * n)


def tessellation_deficit(scene: Scene, positions: np.ndarray, faces: np.ndarray, *,
                         sphere: SphereObject | None = None) -> float:
    """Upper bound of the share of an ideal sphere's entering flux that its
    tessellation misses (or may trap): its faces lie between the inradius r (the
    smallest distance from the centre to a face plane) and R, so it blocks at least
    the cone (or disk) of radius r. Light at a position, distance D: 1 − Ω(r) / Ω(R)
    with Ω(x) = 2π (1 − √(1 − x²/D²)); directional: 1 − (r/R)². ``sphere`` defaults
    to the scene's first object."""
    sphere = sphere or scene.objects[0]
    centre, radius = np.asarray(sphere.center, float), float(sphere.radius)
    p = np.asarray(positions, float) - centre
    a, b, c = (p[faces[:, i]] for i in range(3))
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    inradius = float(np.abs(np.einsum("ij,ij->i", normal, a)).min())
    position = getattr(scene.light, "position", None)
    if position is not None:
        dist = float(np.linalg.norm(centre - np.asarray(position, float)))
        if dist <= radius:
            return 1.0

        def omega(r):
            return 2 * np.pi * (1 - np.sqrt(1 - (r / dist) ** 2))

        return float(1 - omega(inradius) / omega(radius))
    return float(1 - (inradius / radius) ** 2)
