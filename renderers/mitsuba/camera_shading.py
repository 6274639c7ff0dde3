"""What a camera ray does at a specular surface and at the first diffuse one.

The two halves of the camera tracer's arithmetic (:mod:`.camera_trace` is the
loop that calls them), on Mitsuba's surface interactions and Dr.Jit arrays.

Specular event (:func:`camera_event`)
-------------------------------------
The same geometry as the photon tracer's event (:mod:`.specular`): refraction at
the shading normal n, oriented against the arriving direction d, with
eta = n1 / n2 (n1 the side the ray comes from, decided by the geometric normal),

    t = eta d + (eta cos_i - sqrt(k)) n,   k = 1 - eta^2 (1 - cos_i^2),

k < 0 being total internal reflection (TIR); r = d + 2 cos_i n. A camera ray
carries a *radiance weight* W: the radiance found at its end times W is what
the pixel sees. For an ideal specular chain the factors are those of light
travelling the chain backwards:

* conductor: W *= reflectance (constant, as the scene model states);
* dielectric transmission: W *= eta^2 (n1 / n2 along the camera ray). Radiance
  divided by the squared refractive index is invariant along a ray (Veach 1997,
  §5.2), so light that reaches the camera in air from a pool floor in water has
  1 / 1.33^2 of the floor's radiance, with or without Fresnel. Through a closed
  dielectric the two factors cancel (eta and 1 / eta). The photon tracer
  carries flux, where no such factor exists (Mitsuba's own ``dielectric`` and
  ``chain_dielectric`` apply it in radiance mode only: :mod:`.bsdf`);
* Fresnel (only with the ``fresnel`` effect): transmission 1 - F, reflection F,
  F the exact unpolarised dielectric Fresnel factor (``mi.fresnel``). In chain
  mode a reflection at a dielectric breaks the counted chain (the photon tracer
  drops such a photon), so the camera ray follows the transmitted branch
  deterministically with W *= 1 - F: the photon tracer's expectation, without
  its sampling noise. In all-paths mode both branches count and a path may
  branch at every event, so one branch is sampled, reflection with probability F
  (weight one), as the photon tracer does;
* TIR without Fresnel: no transmitted branch. Chain mode drops the ray (black, as
  the photon tracer drops the photon); all-paths mode reflects with weight one;
* no shading-normal factor: the adjoint correction of Veach §5.3 belongs to the
  light-tracing side (:mod:`.photons` applies it), where it makes light tracing
  agree with this, the camera-side (radiance) evaluation.

After a transmission the ray travels in the object's medium (absorption
coefficient sigma, 1/m) or, leaving it, in vacuum; objects do not nest.

Shading (:func:`receiver_radiance`)
-----------------------------------
A Lambertian surface is one-sided (as in the photon tracer's deposit and
Mitsuba's ``diffuse``): seen from behind its shading normal it is black. Seen
from the front, the radiance it sends back along the ray is

    L = albedo / pi * (E_direct * V + E_caustic)                         (W m^-2 sr^-1)

* E_direct (W/m²): only when ``scene.info.direct_lighting``; the light's own
  Mitsuba emitter, exported in the contract's units, evaluated towards the point
  (``scene.sample_emitter_direction``): point light I / d^2, spot light the same
  times its linear falloff between beam width and cutoff, directional light E0,
  area light one sample of its rectangle, L cos_l / (d^2 pdf), unbiased), times
  max(0, cos) at the shading normal, as the method's ``direct_irradiance``
  (``common.glsl``) does;
* V: a Mitsuba shadow ray. With the ``shadows`` effect every shape occludes;
  without it only the receivers do (the caustic objects cast no shadow), as the
  photon tracer traces the unshadowed direct term past the objects;
* E_caustic (W/m², receivers only): the photon tracer's caustic irradiance map of
  that receiver, looked up bilinearly at the hit's (u, v)
  (:func:`.camera_lookup.bilinear`). Diffuse *objects* have no caustic map: they
  get E_direct alone (the photon tracer deposits nothing on them).
"""

from __future__ import annotations

import dataclasses
import math

from renderers.mitsuba import _mi
from renderers.mitsuba.camera_lookup import bilinear
from renderers.mitsuba.specular import CONDUCTOR, DIELECTRIC, interface
from scenes.model import DiffuseMaterial

__all__ = ["CameraEvent", "camera_event", "receiver_radiance"]


@dataclasses.dataclass(frozen=True)
class CameraEvent:
    """One specular event of a batch of camera rays (Dr.Jit arrays, per lane).

    Attributes
    ----------
    ray : mi.Ray3f
        The ray leaving the surface.
    weight : mi.Color3f
        Radiance weight after the event (dimensionless).
    sigma : mi.Color3f
        Absorption coefficient (1/m) of the medium the ray travels next.
    reflected : mi.Bool
        The event was a reflection (else a transmission).
    going_on : mi.Bool
        The ray goes on (it hit a specular object and was not dropped).
    """

    ray: object
    weight: object
    sigma: object
    reflected: object
    going_on: object


def camera_event(si, ray, weight, sigma, *, hit, object_ids, objects, channel,
                 all_paths: bool, u=None) -> CameraEvent:
    """Scatter the camera rays of ``hit`` at ``si`` (see the module docstring).

    Parameters
    ----------
    si : mi.SurfaceInteraction3f
        Where each ray arrived.
    ray : mi.Ray3f
        The arriving rays (unit directions).
    weight, sigma : mi.Color3f
        Radiance weight, and the absorption coefficient (1/m) of the medium the
        ray came through (kept on reflection).
    hit : mi.Bool
        Lanes that are alive and hit a surface.
    object_ids, objects
        Mitsuba shape ids of the scene's objects and the objects (their
        materials), in the same order.
    channel : int or None
        Colour channel whose IOR applies (dispersion), or None for ``iors[0]``.
    all_paths : bool
        All-paths mode (TIR reflects; Fresnel branches sampled with ``u``).
    u : mi.Float, optional
        One uniform number per lane; needed only in all-paths mode with Fresnel.
    """
    mi, dr, _ = _mi.load()
    face = interface(si, ray, hit=hit, object_ids=object_ids, objects=objects, channel=channel)
    kind, obj_sigma, refl, fres = face.kind, face.sigma, face.reflectance, face.fresnel
    going_on, entering, rel = face.going_on, face.entering, face.relative_eta
    tir, t_dir, r_dir, f = (face.tir, face.transmitted, face.reflected,
                            face.fresnel_reflectance)
    dielectric = kind == DIELECTRIC
    if all_paths:
        # Fresnel: sample the branch (reflect with probability F, weight one);
        # without it, TIR reflects with weight one.
        pick = (u < f) if u is not None else mi.Bool(False)
        reflect = dr.select(fres, pick, tir)
        drop = mi.Bool(False)
        transmit_weight = mi.Float(1.0)
    else:
        # Chain mode: only transmissions through a dielectric are counted, so the
        # transmitted branch is followed with its Fresnel weight 1 - F (0 under
        # TIR); without Fresnel, TIR has no transmitted branch and drops the ray.
        reflect = mi.Bool(False)
        drop = tir
        transmit_weight = dr.select(fres, 1.0 - f, 1.0)
    reflect = dr.select(dielectric, reflect, True)
    drop = dielectric & drop
    factor = dr.select(reflect, 1.0, transmit_weight * rel * rel)  # radiance: eta^2
    weight = dr.select(going_on & dielectric, weight * factor, weight)
    weight = dr.select(going_on & (kind == CONDUCTOR), weight * refl, weight)
    new_d = dr.select(reflect, r_dir, t_dir)
    sigma = dr.select(reflect, sigma, dr.select(entering, obj_sigma, mi.Color3f(0.0)))
    return CameraEvent(ray=si.spawn_ray(new_d), weight=weight, sigma=sigma, reflected=reflect,
                       going_on=going_on & ~drop)


def receiver_radiance(si, d, mask, *, exported, occluders, receivers, objects, lookup,
                      direct: bool, light_sample):
    """Radiance (W m^-2 sr^-1, RGB) leaving the diffuse surfaces hit at ``si``
    towards the ray's origin (see the module docstring); zero off ``mask``.

    Parameters
    ----------
    si : mi.SurfaceInteraction3f
        The first diffuse hit of each lane.
    d : mi.Vector3f
        The unit directions the rays arrived along.
    mask : mi.Bool
        Lanes to shade (alive, on a diffuse surface, counted chain).
    exported : ExportedScene
        The scene traced (its emitter gives E_direct; it is this channel's pass).
    occluders : mi.Scene
        What casts shadows: the full scene with the ``shadows`` effect, else the
        receivers alone.
    receivers : sequence
        The scene's receivers (their albedos), indexed like
        ``exported.receiver_ids``.
    objects : sequence
        The scene's caustic objects (a diffuse one is shaded with E_direct alone).
    lookup : LookupMaps or None
        Caustic irradiance maps, one per receiver; None: no caustic term.
    direct : bool
        The scene has direct lighting.
    light_sample : mi.Point2f
        Uniform numbers for the light's sample (used by area lights only).
    """
    mi, dr, _ = _mi.load()
    sid = dr.reinterpret_array(mi.UInt32, si.shape)
    front = dr.dot(d, si.sh_frame.n) < 0  # Lambertian surfaces are one-sided
    albedo = mi.Color3f(0.0)
    irradiance = mi.Color3f(0.0)
    for r, rid in enumerate(exported.receiver_ids):
        here = sid == rid
        albedo = dr.select(here, mi.Color3f(*map(float, receivers[r].albedo)), albedo)
        if lookup is not None:
            irradiance = dr.select(mask & here, bilinear(lookup, r, si.uv), irradiance)
    for oid, obj in zip(exported.object_ids, objects, strict=True):
        if isinstance(obj.material, DiffuseMaterial):
            albedo = dr.select(sid == oid, mi.Color3f(*map(float, obj.material.albedo)), albedo)
    lit = mask & front
    if direct:
        ds, emitted = exported.scene.sample_emitter_direction(si, light_sample, False, lit)
        cos = dr.maximum(dr.dot(ds.d, si.sh_frame.n), 0.0)
        shadow = si.spawn_ray_to(ds.p)
        visible = ~occluders.ray_test(shadow, lit & (cos > 0))
        irradiance += dr.select(lit & visible, emitted * cos, 0.0)
    return dr.select(lit, albedo * (1.0 / math.pi) * irradiance, 0.0)
