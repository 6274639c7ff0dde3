"""Does a scene form a caustic at all? A small photon probe that lets ``validate``
predict ``compare``.

``compare`` fails a scene whose reference puts no caustic light on any receiver (its
comparison's status is ``no caustic``, :data:`reports.records.NO_CAUSTIC`): every
caustic metric would be 0/0. It finds out only after the full reference render. The
geometric checks in :mod:`scenes.geometry.checks` catch the plain cases (no specular
object, an object outside a spot light's cone) but not a caustic that forms and then
misses every receiver, since where it lands depends on the refraction. So
``validate`` traces a few photons with the reference's own tracer
(:class:`~renderers.mitsuba.photons.PhotonTracer` in ``caustic_only`` mode: every
photon is aimed at a specular object's bounding sphere, and only the counted
specular chains deposit) and reads the caustic flux off its maps.

The probe's caustic flux is an unbiased estimate of the reference's, with the same
tracer, chains and receivers (only the map resolution differs, and flux does not
depend on it). It is zero only when none of :data:`PROBE_PHOTONS` photons aimed at
the objects lands on a receiver along a counted chain. A caustic the probe misses
is then carried by less than about 3 / :data:`PROBE_PHOTONS` (5e-5) of the
object-directed flux at 95 % confidence (the rule of three), too little for any
metric ``compare`` reports to be more than noise.

The same tracer, asked for its flux budget (:func:`reference_budget`), says where
the light aimed at the objects went along the reference's event chains: missed,
total internal reflection, cut by the event cap, off every receiver, an uncounted
chain, absorbed, or deposited (:data:`~renderers.mitsuba.photons.BUDGET_ITEMS`).
``compare`` runs it beside the cached reference (which it does not change):
:data:`BUDGET_PHOTONS` photons per channel pass in :data:`BUDGET_LAUNCHES`
independent launches, on a seed disjoint from both references'.

Standard error of a share s = X / E (X an item's watts, E the emitted watts, both
sums over the launches, RGB summed): the launches are independent (within one,
lanes are stratified, so lanes are not), so with r_l = X_l - s E_l per launch,

    SE(s) = sqrt( sum_p n_p var_p(r) ) / E,

var_p the sample variance of r over the n_p launches of channel pass p (one pass,
or three with dispersion): the delta method for a ratio of sums, which also holds
the emitted weight's own noise (it varies per photon for spot lights and
overlapping targets).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from scenes import Scene
from scenes.model import AreaLight, PlaneReceiver
from scenes.schema import Problem

__all__ = ["BUDGET_LAUNCHES", "BUDGET_PHOTONS", "PROBE_PHOTONS", "CausticProbe", "ReferenceBudget",
           "no_caustic_problem", "probe_caustic", "reference_budget"]

#: Photons the probe traces (per channel pass): one Dr.Jit launch, about 0.5 s on
#: two CPU cores for the bundled scenes once the kernels are cached.
PROBE_PHOTONS = 1 << 16

#: The probe's maps per receiver (texels): flux is a sum, so any size would do.
_PROBE_MAP = (16, 16)

#: Photons of the reference's flux-budget trace, per channel pass: a share's
#: standard error is then about sqrt(s (1 - s) / 2^20) < 5e-4 for photons of equal
#: weight; measured 1.1 s (glass_sphere) and 0.9 s (bunny) on two CPU cores.
BUDGET_PHOTONS = 1 << 20
#: Independent launches the budget trace is split into (per channel pass): the
#: standard errors come from their spread (15 degrees of freedom).
BUDGET_LAUNCHES = 16
#: The budget trace's random sequence: seed ``settings.seed + BUDGET_SEED_OFFSET``
#: (the reference uses seeds seed .. seed + K - 1 and the independent reference
#: seed + K .. seed + 2K - 1, K <= 64) and stream 0.
BUDGET_SEED_OFFSET = 20_000


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


@dataclasses.dataclass(frozen=True, eq=False)
class ReferenceBudget:
    """Where the reference's caustic-targeted light went (:func:`reference_budget`).

    Attributes
    ----------
    photons : int
        Photons traced per channel pass.
    launches : int
        Independent launches (over all channel passes).
    seed, stream : int
        The trace's random sequence.
    emitted_w : ndarray (3,)
        Flux emitted toward the objects' bounding spheres (W, RGB).
    items_w : dict of str to ndarray (3,)
        Watts (RGB) per item of :data:`~renderers.mitsuba.photons.BUDGET_ITEMS`.
    share, share_se : dict of str to float
        Each item's share of the emitted flux (RGB summed) and its standard error
        (see the module docstring).
    maps_flux_w : ndarray (3,) or None
        Flux on the trace's own caustic maps (Σ E · texel area; planar receivers
        only, else None): what ``deposited`` must equal.
    seconds : float
        Wall time of the trace (tracer set-up included).
    event_chains : list of str
        The specular chains the tracer counted.
    all_paths : bool
        The tracer counted every L S+ D path (``cap`` is then the safety cap).
    aimed : bool
        The photons were aimed at the objects' bounding spheres (every light but an
        area light, whose photons leave in all directions).
    screened : int
        Photons left out because their emission pdf was rounded to zero (see
        ``renderers.mitsuba.photons._Tally.screen``); they miss the objects.
    """

    photons: int
    launches: int
    seed: int
    stream: int
    emitted_w: np.ndarray
    items_w: dict
    share: dict
    share_se: dict
    maps_flux_w: np.ndarray | None
    seconds: float
    event_chains: list
    all_paths: bool = False
    screened: int = 0
    aimed: bool = True

    @property
    def unaccounted_w(self) -> np.ndarray:
        """Emitted minus the sum of the items (W, RGB): zero when the budget closes."""
        return self.emitted_w - sum(self.items_w.values())

    def provenance(self) -> dict:
        """What the report and metrics.json say about the trace."""
        return {"photons_per_channel_pass": self.photons, "launches": self.launches,
                "seed": self.seed, "stream": self.stream, "seconds": self.seconds,
                "emitted_w": self.emitted_w.tolist(),
                "unaccounted_w": self.unaccounted_w.tolist(),
                "maps_flux_w": None if self.maps_flux_w is None else self.maps_flux_w.tolist(),
                "event_chains": self.event_chains, "screened_photons": self.screened}


def _share_errors(sums, share: dict) -> dict:
    """Standard error of each share from the launches' spread (module docstring)."""
    items = sums.budget.sum(axis=2)              # (launches, items), RGB summed
    emitted = sums.launch_emitted.sum(axis=1)    # (launches,)
    passes = np.asarray(sums.launch_pass)
    total = float(emitted.sum())
    from renderers.mitsuba.photons import BUDGET_ITEMS  # noqa: PLC0415 (heavy: Mitsuba)

    errors = {}
    for j, item in enumerate(BUDGET_ITEMS):
        residual = items[:, j] - share[item] * emitted
        variance = 0.0
        for p in np.unique(passes):
            r = residual[passes == p]
            if r.size > 1:
                variance += r.size * float(np.var(r, ddof=1))
        errors[item] = float(np.sqrt(variance)) / total if total > 0 else float("nan")
    return errors


def reference_budget(scene: Scene, *, photons: int = BUDGET_PHOTONS,
                     launches: int = BUDGET_LAUNCHES, seed: int | None = None,
                     geometry=None) -> ReferenceBudget:
    """Trace ``photons`` photons per channel pass, aimed at ``scene``'s specular
    objects, with the reference's tracer and chains, and tally where their flux went
    (:class:`ReferenceBudget`). ``seed`` defaults to ``settings.seed +
    BUDGET_SEED_OFFSET``."""
    from renderers.mitsuba.photons import (  # noqa: PLC0415 (heavy: Mitsuba)
        BUDGET_ITEMS,
        PhotonTracer,
        event_chains_counted,
    )

    seed = scene.settings.seed + BUDGET_SEED_OFFSET if seed is None else seed
    start = time.perf_counter()
    tracer = PhotonTracer(scene, geometry=geometry, resolution=_PROBE_MAP, caustic_only=True,
                          budget=True)
    batch = max(1, -(-photons // launches))
    sums = tracer.trace(photons, seed=seed, stream=0, batch=batch)
    seconds = time.perf_counter() - start
    n = sums.photons
    items_w = {item: sums.budget[:, j].sum(axis=0) / n for j, item in enumerate(BUDGET_ITEMS)}
    emitted_w = sums.emitted / n
    total = float(emitted_w.sum())
    share = {item: float(v.sum()) / total if total > 0 else float("nan")
             for item, v in items_w.items()}
    planar = all(isinstance(r, PlaneReceiver) for r in scene.receivers)
    maps_flux = None
    if planar:
        texels = _PROBE_MAP[0] * _PROBE_MAP[1]
        maps_flux = np.zeros(3)
        for maps, (umin, umax, vmin, vmax) in zip(sums.caustic, tracer.extents, strict=True):
            maps_flux += maps.reshape(-1, 3).sum(axis=0) * (umax - umin) * (vmax - vmin) \
                / texels / n
    return ReferenceBudget(photons=n, launches=len(sums.launch_pass), seed=seed, stream=0,
                           emitted_w=emitted_w, items_w=items_w, share=share,
                           share_se=_share_errors(sums, share), maps_flux_w=maps_flux,
                           seconds=seconds, screened=sums.screened,
                           all_paths=bool(scene.settings.all_specular_paths),
                           aimed=not isinstance(scene.light, AreaLight),
                           event_chains=[c for c in event_chains_counted(scene)
                                         if not c.startswith("L D")])
