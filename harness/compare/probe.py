"""Does a scene form a caustic at all? A small photon probe that lets ``validate``
predict ``compare``.

``compare`` fails a scene whose reference puts no caustic light on any receiver
(:class:`~harness.compare.isolation.NoCausticError`): every caustic metric would be
0/0. It finds out only after the full reference render. The geometric checks in
:mod:`scenes.geometry.checks` catch the plain cases (no specular object, an object
outside a spot light's cone) but not a caustic that forms and then misses every
receiver, since where it lands depends on the refraction. So ``validate`` traces a
few photons with the reference's own tracer (:class:`~renderers.mitsuba.photons.
PhotonTracer` in ``caustic_only`` mode: every photon is aimed at a specular
object's bounding sphere, and only the counted specular chains deposit) and reads
the caustic flux off its maps.

The probe's caustic flux is an unbiased estimate of the reference's, with the same
tracer, chains and receivers (only the map resolution differs, and flux does not
depend on it). It is zero only when none of :data:`PROBE_PHOTONS` photons aimed at
the objects lands on a receiver along a counted chain. A caustic the probe misses
is then carried by less than about 3 / :data:`PROBE_PHOTONS` (5e-5) of the
object-directed flux at 95 % confidence (the rule of three), too little for any
metric ``compare`` reports to be more than noise.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from scenes import Scene
from scenes.schema import Problem

__all__ = ["PROBE_PHOTONS", "CausticProbe", "no_caustic_problem", "probe_caustic"]

#: Photons the probe traces (per channel pass): one Dr.Jit launch, about 0.5 s on
#: two CPU cores for the bundled scenes once the kernels are cached.
PROBE_PHOTONS = 1 << 16

#: The probe's maps per receiver (texels): flux is a sum, so any size would do.
_PROBE_MAP = (16, 16)


@dataclasses.dataclass(frozen=True)
class CausticProbe:
    """What the probe found.

    Attributes
    ----------
    photons : int
        Photons traced per channel pass.
    caustic_flux_w : float
        Estimated caustic flux on all receivers (W, summed over RGB).
    """

    photons: int
    caustic_flux_w: float


def probe_caustic(scene: Scene, *, photons: int = PROBE_PHOTONS, seed: int = 0) -> CausticProbe:
    """Trace ``photons`` photons at ``scene``'s specular objects with the reference
    tracer and return the caustic flux they put on the receivers.

    Flux per receiver is Σ texels E · A_texel / N, with E the deposited irradiance
    sum (W/m²) and A_texel the texel's area in the receiver's (u, v) extent (m²).
    """
    from renderers.mitsuba.photons import PhotonTracer  # noqa: PLC0415 (heavy: Mitsuba)

    tracer = PhotonTracer(scene, resolution=_PROBE_MAP, caustic_only=True)
    sums = tracer.trace(photons, seed=seed)
    texels = _PROBE_MAP[0] * _PROBE_MAP[1]
    flux = 0.0
    for maps, (umin, umax, vmin, vmax) in zip(sums.caustic, tracer.extents, strict=True):
        texel_area = (umax - umin) * (vmax - vmin) / texels
        flux += float(np.sum(maps)) * texel_area / sums.photons
    return CausticProbe(photons=sums.photons, caustic_flux_w=flux)


def no_caustic_problem(scene: Scene, probe: CausticProbe) -> Problem | None:
    """The ``validate`` error for a scene whose probe found no caustic, or None."""
    if probe.caustic_flux_w > 0.0:
        return None
    return Problem(scene.source, "receivers", (
        f"no caustic: none of {probe.photons} photons the reference tracer aimed at the "
        "specular objects reached a receiver along a counted chain, so compare would "
        "fail on this scene (check where the light, objects and receivers are)"))
