"""One specular event of the photon tracer, on Mitsuba's surface interactions.

Kept apart from the tracer's loop (:mod:`.photons`) so that the same event runs in
the unrolled first events and in the symbolic loop of long paths. The maths is the
one the module docstring of :mod:`.photons` states: refraction at the shading
normal, total internal reflection, Fresnel by sampling, conductor reflectance,
the adjoint shading-normal factor and the medium after the event.
"""

from __future__ import annotations

import dataclasses

from renderers.mitsuba import _mi
from scenes.model import ConductorMaterial, DielectricMaterial

__all__ = ["Event", "Interface", "interface", "specular_event"]

#: Material kinds per lane: a diffuse object absorbs, the others scatter.
ABSORB, DIELECTRIC, CONDUCTOR = 0, 1, 2


@dataclasses.dataclass(frozen=True)
class Event:
    """What one specular event did to a batch of photons (Dr.Jit arrays, per lane).

    Attributes
    ----------
    ray : mi.Ray3f
        The ray leaving the event (spawned off the surface).
    weight : mi.Color3f
        Photon weight after the event (W x photons), conductor reflectance and the
        shading-normal factor applied.
    sigma : mi.Color3f
        Absorption coefficient (1/m) of the medium the photon travels in next.
    reflected : mi.Bool
        The event was a reflection (else a transmission).
    going_on : mi.Bool
        The photon scatters on (it hit a specular object and was not dropped).
    dropped : mi.Bool
        Total internal reflection dropped the photon (chain mode without Fresnel).
    surface_loss : mi.Color3f
        Weight the surface absorbed from a photon that goes on: (1 - R) w at a
        conductor of reflectance R, else 0.
    shading_loss : mi.Color3f
        Weight the adjoint shading-normal factor took from a photon that goes on,
        w (1 - factor): negative where the factor exceeds one (a gain).
    dielectric_reflection : mi.Bool
        The photon goes on after reflecting at a dielectric (Fresnel, or total
        internal reflection in all-paths mode).

    The last four are tallies for the tracer's flux budget (``PhotonTracer(...,
    budget=True)``); the tracer's maps never read them, so a trace without the
    budget compiles the same kernel as before they existed.
    """

    ray: object
    weight: object
    sigma: object
    reflected: object
    going_on: object
    dropped: object = None
    surface_loss: object = None
    shading_loss: object = None
    dielectric_reflection: object = None


@dataclasses.dataclass(frozen=True)
class Interface:
    """What rays meet at a surface: the material per lane and the refraction geometry
    (Dr.Jit arrays; shared by the photon tracer's and the camera tracer's events).

    Attributes
    ----------
    kind : mi.UInt32
        ABSORB, DIELECTRIC or CONDUCTOR.
    eta, sigma, reflectance, fresnel
        The dielectric's IOR (this channel's) and absorption coefficient (1/m), the
        conductor's reflectance, and whether the material asks for Fresnel.
    going_on : mi.Bool
        Lanes that hit a specular object (they scatter on).
    normal, facing : mi.Vector3f
        The shading normal, and it turned to face the ray's origin.
    entering : mi.Bool
        The ray arrives from the geometric normal's side (it enters the object).
    cos_i, relative_eta : mi.Float
        Cosine of incidence at ``facing``, and n1 / n2 along the ray.
    tir : mi.Bool
        Total internal reflection (no transmitted direction).
    transmitted, reflected : mi.Vector3f
        Snell's refracted direction (meaningless under TIR) and the mirror direction.
    fresnel_reflectance : mi.Float
        Unpolarised Fresnel reflectance F.
    """

    kind: object
    eta: object
    sigma: object
    reflectance: object
    fresnel: object
    going_on: object
    normal: object
    facing: object
    entering: object
    cos_i: object
    relative_eta: object
    tir: object
    transmitted: object
    reflected: object
    fresnel_reflectance: object


def interface(si, ray, *, hit, object_ids, objects, channel) -> Interface:
    """The :class:`Interface` of the rays ``ray`` (unit directions) at ``si``; ``hit``,
    ``object_ids``, ``objects`` and ``channel`` as in :func:`specular_event`."""
    mi, dr, _ = _mi.load()
    sid = dr.reinterpret_array(mi.UInt32, si.shape)
    kind = mi.UInt32(ABSORB)
    eta = mi.Float(1.0)
    obj_sigma = mi.Color3f(0.0)
    refl = mi.Color3f(1.0)
    fres = mi.Bool(False)
    for oid, obj in zip(object_ids, objects, strict=True):
        m = obj.material
        here = sid == oid
        if isinstance(m, DielectricMaterial):
            kind = dr.select(here, DIELECTRIC, kind)
            eta = dr.select(here, float(m.iors[0 if channel is None else channel]), eta)
            obj_sigma = dr.select(here, mi.Color3f(*map(float, m.absorption)), obj_sigma)
            fres = dr.select(here, bool(m.fresnel), fres)
        elif isinstance(m, ConductorMaterial):
            kind = dr.select(here, CONDUCTOR, kind)
            refl = dr.select(here, mi.Color3f(*map(float, m.reflectance)), refl)
    d = ray.d
    n = si.sh_frame.n
    entering = dr.dot(d, si.n) < 0  # geometric normal: which side we come from
    nf = dr.select(dr.dot(d, n) < 0, n, -n)  # shading normal facing d's origin
    cos_i = dr.clip(-dr.dot(d, nf), 0.0, 1.0)
    rel = dr.select(entering, dr.rcp(eta), eta)  # n1 / n2
    k = 1.0 - rel * rel * (1.0 - cos_i * cos_i)
    t_dir = dr.normalize(rel * d + (rel * cos_i - dr.sqrt(dr.maximum(k, 0.0))) * nf)
    r_dir = dr.normalize(d + 2.0 * cos_i * nf)
    f, _, _, _ = mi.fresnel(dr.select(entering, cos_i, -cos_i), eta)
    return Interface(kind=kind, eta=eta, sigma=obj_sigma, reflectance=refl, fresnel=fres,
                     going_on=hit & (kind != ABSORB), normal=n, facing=nf, entering=entering,
                     cos_i=cos_i, relative_eta=rel, tir=k < 0, transmitted=t_dir,
                     reflected=r_dir, fresnel_reflectance=f)


def specular_event(si, ray, weight, sigma, rng, *, hit, object_ids, objects, channel,
                   all_paths: bool, shading_correction: bool) -> Event:
    """Scatter the photons of ``hit`` at ``si``; others pass through unchanged.

    Parameters
    ----------
    si : mi.SurfaceInteraction3f
        Where each photon arrived.
    ray : mi.Ray3f
        The ray each photon arrived along (``ray.d`` is its unit direction).
    weight, sigma : mi.Color3f
        Photon weight, and the absorption coefficient (1/m) of the medium it came
        through (kept on reflection).
    rng : mi.PCG32
        Per-lane generator; one float is drawn per event (the Fresnel choice).
    hit : mi.Bool
        Lanes whose photon is alive and hit a surface.
    object_ids, objects
        Mitsuba shape ids of the scene's objects and the objects themselves (their
        materials), in the same order.
    channel : int or None
        Colour channel whose IOR applies (dispersion), or None for ``iors[0]``.
    all_paths : bool
        All-paths mode: total internal reflection reflects with weight one; in
        chain mode without Fresnel it drops the photon.
    shading_correction : bool
        Apply the adjoint shading-normal factor.
    """
    mi, dr, _ = _mi.load()
    face = interface(si, ray, hit=hit, object_ids=object_ids, objects=objects, channel=channel)
    kind, obj_sigma, refl, fres = face.kind, face.sigma, face.reflectance, face.fresnel
    going_on, d, n, entering = face.going_on, ray.d, face.normal, face.entering
    tir, t_dir, r_dir, f = (face.tir, face.transmitted, face.reflected,
                            face.fresnel_reflectance)
    u = rng.next_float32()
    dielectric = kind == DIELECTRIC
    reflect = dr.select(fres, u < f, tir & all_paths)
    drop = dielectric & ~fres & tir & (not all_paths)
    reflect = dr.select(dielectric, reflect, True)
    arrived = weight
    weight = dr.select(going_on & (kind == CONDUCTOR), weight * refl, weight)
    reflected_weight = weight
    new_d = dr.select(reflect, r_dir, t_dir)
    if shading_correction:
        ng = si.n
        num = dr.abs(dr.dot(d, n)) * dr.abs(dr.dot(new_d, ng))
        den = dr.abs(dr.dot(d, ng)) * dr.abs(dr.dot(new_d, n))
        # A direction in the tangent plane of either normal has measure zero; such
        # a photon is dropped (factor 0), as in pbrt.
        factor = dr.select(den > 0, num / dr.maximum(den, 1e-30), 0.0)
        weight = dr.select(going_on, weight * factor, weight)
    # Medium after the event: reflection keeps it; transmission enters the object's
    # medium or leaves to vacuum (objects do not nest).
    sigma = dr.select(reflect, sigma, dr.select(entering, obj_sigma, mi.Color3f(0.0)))
    on = going_on & ~drop
    zero = mi.Color3f(0.0)
    return Event(ray=si.spawn_ray(new_d), weight=weight, sigma=sigma, reflected=reflect,
                 going_on=on, dropped=going_on & drop,
                 surface_loss=dr.select(on, arrived - reflected_weight, zero),
                 shading_loss=dr.select(on, reflected_weight - weight, zero),
                 dielectric_reflection=on & dielectric & reflect)
