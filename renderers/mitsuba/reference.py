"""The cached Mitsuba reference of a scene: K seeds, noise target, budget.

Receiver maps: each round traces one launch per seed (K independent PCG32
streams): first the launches of :func:`.photons.launch_plan` for the starting budget
``settings.photons`` (whole launches of 2^20 photons, a remainder as one smaller
launch, every launch stratified at its own size), then whole launches. After each
round, the per-seed estimates (each seed's sums over its photons so far / those
photons; every seed traces the same launches) give the mean, the variance of the
mean and the relative noise per channel over this reference's own caustic region (the
scored region's rule, :mod:`.noise`); :class:`ReceiverRounds` keeps these rounds, for
this process and for a sweep's per-seed tasks alike. Rounds stop (``stopped_by``):

* ``"target_noise"``: the noise (the largest channel's) is at most
  ``settings.target_noise``;
* ``"budget"``: the starting budget is spent and the target is out of reach within
  ``settings.reference_time_cap``: noise falls as 1 / sqrt(photons), so the target
  needs photons x (noise / target)^2 per seed, and at the last round's rate those
  would end past the cap (or the noise is not finite);
* ``"time_cap"``: past the budget, the cap is reached (or the target turned out of
  reach within it) before the target.

Camera image: K seeds of ``settings.spp`` samples per
pixel, mean and variance of the mean; by the camera tracer (:mod:`.camera_trace`:
camera rays through the counted specular chains, shaded with direct light and the
caustic irradiance of its own per-seed lookup maps) or, with ``camera="ptracer"``,
by Mitsuba's particle tracer (:mod:`.camera`: specular objects and all seen through
them render black).

One road for every reference, ``caustics compare`` and a sweep's alike: the receiver
maps' estimate (:class:`ReceiverRounds`, traced in this process or as a sweep's
per-seed tasks) becomes the reference through :func:`reference_result` (the camera
image, the metadata), and the cache is read and written through
:func:`cached_reference` (one lock per key).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from renderers.mitsuba import _mi
from renderers.mitsuba.cache import (
    CAMERA_INTEGRATORS,
    cache_dir,
    cache_key,
    check_camera,
    entry_lock,
    load_entry,
    write_result_dir,
)
from renderers.mitsuba.camera import (
    CAMERA_LIMITS,
    camera_cut_fraction,
    camera_max_depth,
    render_camera,
)
from renderers.mitsuba.camera import MAX_SPECULAR_EVENTS as CAMERA_MAX_EVENTS
from renderers.mitsuba.camera_lookup import FOOTPRINT_PERCENTILE, LOOKUP_CAP, LookupPlan
from renderers.mitsuba.camera_trace import camera_trace_limits, render_traced_camera
from renderers.mitsuba.noise import caustic_region, relative_noise_per_channel, seed_statistics
from renderers.mitsuba.photons import (
    DEFAULT_BATCH,
    MAX_SPECULAR_EVENTS,
    ROULETTE_FROM,
    ROULETTE_SURVIVAL,
    PhotonTracer,
    event_chains_counted,
    launch_plan,
)
from renderers.results import ReceiverMap, RenderResult
from scenes import effects_of
from scenes.geometry import build_geometry
from scenes.model import Scene

__all__ = [
    "CUT_WARNING",
    "CutFluxWarning",
    "ReceiverEstimate",
    "ReceiverRounds",
    "cached_reference",
    "cut_fraction",
    "estimate_receivers",
    "reference_metadata",
    "reference_result",
    "render_reference",
    "stop_reason",
]

TIMER = "time.perf_counter (wall clock, includes JIT compilation)"


class CutFluxWarning(UserWarning):
    """The reference's path limit cut off more than :data:`CUT_WARNING` of the flux."""


@dataclass(frozen=True, eq=False)
class ReceiverEstimate:
    """Photon-traced receiver maps with their noise (see :func:`estimate_receivers`).

    Attributes
    ----------
    maps : tuple of ReceiverMap, or None
        Mean total irradiance (direct light and the counted chains; W/m², (H, W, 3),
        row 0 at vmin) and its variance of the mean. None with ``caustic_only``.
    caustic : tuple of ReceiverMap
        Mean caustic irradiance (the counted chains only, no direct light: what the
        radiometric contract calls the receiver map), with its variance of the mean.
    photons : int
        Photons per seed (per channel pass) actually traced: the starting budget, and
        the launches past it.
    relative_noise : float
        Largest, over the receivers and RGB channels, RMS relative standard error
        over the receivers' caustic regions (:mod:`.noise`).
    stopped_by : str
        ``"target_noise"``, ``"budget"`` or ``"time_cap"`` (see the module docstring).
    history : tuple of (int, float, float)
        (photons per seed, relative noise, seconds) after each round.
    seeds : int
        Independent seeds K.
    seed : int
        The first seed.
    channel_passes : int
        Photon-tracer passes per seed: 1, or 3 with dispersion (one per channel).
    cut_fraction : float
        Largest fraction, over RGB, of the emitted flux on paths that the safety cap
        of :data:`.photons.MAX_SPECULAR_EVENTS` stopped (all-paths mode, past Russian
        roulette; 0 in chain mode, whose chains end by definition), over every
        seed's photons.
    relative_noise_per_channel : tuple of float
        (R, G, B): each channel's RMS relative standard error, the largest over the
        receivers (nan for a channel lit nowhere in the regions).
    region_texels : tuple of int
        Texels of each receiver's caustic region the noise was measured over.
    budget : int
        The starting photon budget per seed.
    time_cap : float
        Seconds the rounds may take past the budget (``reference_time_cap``).
    """

    maps: tuple[ReceiverMap, ...] | None
    caustic: tuple[ReceiverMap, ...]
    photons: int
    relative_noise: float
    stopped_by: str
    history: tuple[tuple[int, float, float], ...]
    seeds: int
    seed: int
    channel_passes: int
    cut_fraction: float = 0.0
    relative_noise_per_channel: tuple[float, float, float] = (np.nan, np.nan, np.nan)
    region_texels: tuple[int, ...] = ()
    budget: int = 0
    time_cap: float = np.inf


#: Cut flux fraction above which the reference warns that its path limit loses light.
CUT_WARNING = 1e-4


def cut_fraction(emitted: np.ndarray, cut: np.ndarray) -> float:
    """max over RGB of cut / emitted flux (0 where nothing was emitted)."""
    fractions = np.divide(cut, emitted, out=np.zeros(3), where=emitted > 0)
    return float(fractions.max())


def _warn_cut(scene: Scene, fraction: float, what: str, cap: int) -> None:
    """CutFluxWarning naming the scene when the ``cap`` cut more than CUT_WARNING."""
    if fraction > CUT_WARNING:
        warnings.warn(f"{scene.name}: the safety cap of {cap} specular events "
                      f"cut off {fraction:.2e} of the {what} "
                      "(paths trapped by total internal reflection)", CutFluxWarning,
                      stacklevel=3)


def _progress(total: int, desc: str, enabled: bool):
    if not enabled:
        return nullcontext(None)

    return tqdm(total=total, desc=desc, unit="photon", unit_scale=True, leave=False)


def stop_reason(*, noise: float, target: float, phase: str, elapsed: float, rate: float,
                traced: int, cap: float) -> str | None:
    """Why the rounds stop after this one (``stopped_by``), or None to trace another.

    ``phase``: ``"budget"`` while the starting budget has launches left, ``"spent"``
    right after its last, ``"extended"`` after a launch past it. ``rate``: photons per
    seed per second over the last round; ``elapsed``: seconds since the start. The
    target needs traced x (noise / target)^2 photons per seed (the noise of a mean
    falls as 1 / sqrt(photons)); another round is traced only if, at ``rate``, those
    would be done within ``cap`` seconds.
    """
    if np.isfinite(noise) and noise <= target:
        return "target_noise"
    if phase == "budget":
        return None
    why = "time_cap" if phase == "extended" else "budget"
    if not (np.isfinite(noise) and rate > 0 and target > 0) or elapsed >= cap:
        return why  # no projection (or a target of 0, never reached), or out of time
    needed = traced * (noise / target) ** 2
    return why if elapsed + (needed - traced) / rate > cap else None


class ReceiverRounds:
    """The rounds of a reference's receiver maps: each round's per-seed sums in, the
    estimate, its noise and the stop rule out (see the module docstring).

    One bookkeeping for every way of tracing the rounds: :func:`estimate_receivers`
    traces them here, seed after seed (:meth:`trace`); the sweep traces the seeds'
    launches of the starting budget as separate tasks and replays them here
    (:meth:`add`), then traces the rounds past the budget with :meth:`trace`. So the
    maps, the noise, the stop and the metadata are one computation.

    Parameters
    ----------
    extents : sequence of (float, float, float, float)
        Each receiver's (u, v) extent.
    seeds, seed : int
        Independent seeds K, and the first (seed k is ``seed + k``).
    budget : int
        Starting photon budget per seed (per channel pass).
    batch : int
        Lanes of a whole launch; the rounds trace :func:`.photons.launch_plan`
        ``(budget, batch)``, then whole launches.
    target, cap : float
        ``target_noise`` and ``reference_time_cap`` (seconds).
    channel_passes : int
        Photon-tracer passes per photon: 1, or 3 with dispersion.
    caustic_only : bool
        The sums carry only the caustic maps (no ``total``).

    Attributes
    ----------
    plan : tuple of int
        Lanes of the starting budget's launches (one per round).
    photons : int
        Photons per seed added so far.
    history : list of (int, float, float)
        (photons per seed, relative noise, elapsed seconds) after each round.
    noise : float
        The last round's relative noise (the largest channel's; nan before a round).
    per_channel : ndarray (3,)
        The last round's (R, G, B) noise, the largest over the receivers.
    region_texels : tuple of int
        Texels of each receiver's caustic region in the last round.
    stopped_by : str or None
        The stop reason once a round stopped the rounds (:func:`stop_reason`).

    Raises
    ------
    ValueError
        ``budget`` < 1 or ``batch`` out of range (:func:`.photons.launch_plan`).
    """

    def __init__(self, *, extents, seeds: int, seed: int, budget: int, batch: int,
                 target: float, cap: float, channel_passes: int,
                 caustic_only: bool) -> None:
        self.extents = tuple(tuple(e) for e in extents)
        self.seeds, self.seed = int(seeds), int(seed)
        self.budget, self.batch = int(budget), int(batch)
        # One launch per seed per round: the starting budget's launches, then whole ones.
        self.plan = launch_plan(budget, batch)
        self.target, self.cap = float(target), float(cap)
        self.channel_passes = int(channel_passes)
        self.caustic_only = bool(caustic_only)
        n_rec = len(self.extents)
        self._caustic = [[0.0] * n_rec for _ in range(self.seeds)]
        self._total = [[0.0] * n_rec for _ in range(self.seeds)]
        self._emitted, self._cut = np.zeros(3), np.zeros(3)
        self.photons = 0
        self.history: list[tuple[int, float, float]] = []
        self.noise = float("nan")
        self.per_channel = np.full(3, np.nan)
        self.region_texels: tuple[int, ...] = (0,) * n_rec
        self.stopped_by: str | None = None
        self._maps: list[ReceiverMap] = []
        self._caustic_maps: list[ReceiverMap] = []

    @property
    def rounds(self) -> int:
        """Rounds added so far; the next round's launches use PCG32 stream ``rounds``."""
        return len(self.history)

    @property
    def lanes(self) -> int:
        """Lanes of the next round's launch (per seed): the plan's, then ``batch``."""
        return self.plan[self.rounds] if self.rounds < len(self.plan) else self.batch

    @property
    def phase(self) -> str:
        """The stop rule's phase after the rounds so far (:func:`stop_reason`)."""
        return ("budget" if self.rounds < len(self.plan)
                else "spent" if self.rounds == len(self.plan) else "extended")

    def add(self, caustic, *, total=None, photons: int, emitted, cut, elapsed: float,
            seconds: float) -> str | None:
        """Add one round; its stop reason (``stopped_by``), or None to trace another.

        Parameters
        ----------
        caustic : sequence (K) of sequence (receivers) of ndarray
            Per seed, per receiver, the round's unnormalised caustic sums (float64,
            (H, W, 3), W/m² x photons: :attr:`.photons.PhotonSums.caustic`).
        total : same, or None
            The total sums (:attr:`.photons.PhotonSums.total`); None with
            ``caustic_only``.
        photons : int
            Photons per seed this round (per channel pass).
        emitted, cut : sequence (K) of ndarray (3,)
            Per seed, the round's emitted and cut-off flux (RGB, W x photons).
        elapsed : float
            Seconds from the start of the rounds to the end of this one (recorded in
            the history; the stop rule's time).
        seconds : float
            Seconds this round's K launches take when traced one after another: the
            rate the stop rule projects the rounds past the budget with is
            ``photons / seconds`` (photons per seed per second).

        Raises
        ------
        ValueError
            Not K seeds of sums, or a round added after the stop.
        """
        if self.stopped_by is not None:
            raise ValueError(f"the rounds stopped ({self.stopped_by}): no round to add")
        if {len(caustic), len(emitted), len(cut)} != {self.seeds}:
            raise ValueError(f"a round has the sums of {self.seeds} seeds, got "
                             f"{len(caustic)} maps, {len(emitted)} emitted, {len(cut)} cut")
        n_rec = len(self.extents)
        for i in range(self.seeds):
            for r in range(n_rec):
                if not self.caustic_only:
                    self._total[i][r] = self._total[i][r] + total[i][r]
                self._caustic[i][r] = self._caustic[i][r] + caustic[i][r]
        # The cut fraction is over every seed's photons.
        self._emitted += np.sum(emitted, axis=0)
        self._cut += np.sum(cut, axis=0)
        traced = self.photons = self.photons + int(photons)
        channels, maps, caustic_maps, counts = [], [], [], []
        for r in range(n_rec):
            per_seed = np.stack([c[r] for c in self._caustic]) / traced
            cmean, cvar = seed_statistics(per_seed)
            # Noise of what is compared: the caustic map, per channel, over its own
            # caustic region (the scored region's rule, on this reference).
            region = caustic_region(cmean)
            counts.append(int(region.sum()))
            channels.append(relative_noise_per_channel(cmean, cvar, region))
            if not self.caustic_only:
                mean, var = seed_statistics(np.stack([t[r] for t in self._total]) / traced)
                maps.append(ReceiverMap(mean.astype(np.float32), self.extents[r],
                                        var.astype(np.float32)))
            caustic_maps.append(ReceiverMap(cmean.astype(np.float32), self.extents[r],
                                            cvar.astype(np.float32),
                                            seed_maps=per_seed.astype(np.float32)))
        self._maps, self._caustic_maps = maps, caustic_maps
        self.per_channel, self.region_texels = _largest(channels), tuple(counts)
        finite = self.per_channel[np.isfinite(self.per_channel)]
        self.noise = float(finite.max()) if finite.size else float("nan")
        self.history.append((traced, self.noise, float(elapsed)))
        self.stopped_by = stop_reason(noise=self.noise, target=self.target, phase=self.phase,
                                      elapsed=elapsed, rate=photons / max(seconds, 1e-9),
                                      traced=traced, cap=self.cap)
        return self.stopped_by

    def trace(self, tracer: PhotonTracer, *, start: float) -> str | None:
        """Trace the next round with ``tracer``, seed after seed (seed ``seed + k``,
        stream :attr:`rounds`, one launch of :attr:`lanes` lanes stratified at its
        own size), and :meth:`add` it; ``start``: the ``time.perf_counter()`` the
        elapsed time counts from."""
        n, stream = self.lanes, self.rounds
        began = time.perf_counter()
        traced = [tracer.trace(n, seed=self.seed + i, stream=stream, batch=n)
                  for i in range(self.seeds)]
        now = time.perf_counter()
        return self.add([t.caustic for t in traced],
                        total=None if self.caustic_only else [t.total for t in traced],
                        photons=traced[0].photons, emitted=[t.emitted for t in traced],
                        cut=[t.cut for t in traced], elapsed=now - start,
                        seconds=now - began)

    @property
    def cut_fraction(self) -> float:
        """Largest fraction, over RGB, of the emitted flux the safety cap cut off."""
        return cut_fraction(self._emitted, self._cut)

    def estimate(self) -> ReceiverEstimate:
        """The estimate after the rounds so far (:class:`ReceiverEstimate`)."""
        if not self.history:
            raise ValueError("no round traced yet")
        return ReceiverEstimate(
            maps=None if self.caustic_only else tuple(self._maps),
            caustic=tuple(self._caustic_maps), photons=self.photons,
            relative_noise=self.noise, stopped_by=self.stopped_by or "budget",
            history=tuple(self.history), seeds=self.seeds, seed=self.seed,
            channel_passes=self.channel_passes, cut_fraction=self.cut_fraction,
            relative_noise_per_channel=tuple(float(x) for x in self.per_channel),
            region_texels=self.region_texels, budget=self.budget, time_cap=self.cap)


def estimate_receivers(scene: Scene, *, photons: int | None = None, seeds: int | None = None,
                       seed: int | None = None, target_noise: float | None = None,
                       time_cap: float | None = None,
                       resolution: tuple[int, int] | None = None, extents: list | None = None,
                       batch: int = DEFAULT_BATCH, progress: bool = False,
                       caustic_only: bool = False) -> ReceiverEstimate:
    """Trace receiver maps with K seeds until the noise target, the budget or the
    time cap (see the module docstring), in one process: the rounds of
    :class:`ReceiverRounds`, each seed's launch after the other's.

    Parameters default to ``scene.settings`` (``photons``: the starting budget per
    seed, always traced unless the target is met first; ``time_cap``:
    ``reference_time_cap``). ``batch``: the lanes of a whole launch.
    ``caustic_only`` traces only the caustic maps (see :class:`.PhotonTracer`:
    every photon is aimed at the caustic objects, none at the receivers; same
    expectation, less noise per photon); ``maps`` is then None. The elapsed time
    counts from before the tracer is built (its JIT compilation included).
    """
    s = scene.settings
    budget = photons if photons is not None else s.photons
    start = time.perf_counter()
    tracer = PhotonTracer(scene, resolution=resolution, extents=extents,
                          caustic_only=caustic_only)
    rounds = ReceiverRounds(
        extents=tracer.extents, seeds=seeds if seeds is not None else s.seeds,
        seed=seed if seed is not None else s.seed, budget=budget, batch=batch,
        target=target_noise if target_noise is not None else s.target_noise,
        cap=float(time_cap if time_cap is not None else s.reference_time_cap),
        channel_passes=len(tracer.channels), caustic_only=caustic_only)
    with _progress(budget, f"photons ({rounds.seeds} seeds)", progress) as bar:
        while True:
            lanes = rounds.lanes
            why = rounds.trace(tracer, start=start)
            if bar is not None:
                bar.total = max(bar.total, rounds.photons)
                bar.update(lanes)
                bar.set_postfix(noise=f"{rounds.noise:.4f}")
            if why is not None:
                break
    estimate = rounds.estimate()
    _warn_cut(scene, estimate.cut_fraction, "emitted caustic flux", tracer.max_events)
    return estimate


def _largest(channels: list[np.ndarray]) -> np.ndarray:
    """(3,) per channel, the largest finite noise over the receivers (nan if none)."""
    stacked = np.stack(channels)
    out = np.full(3, np.nan)
    for c in range(3):
        finite = stacked[:, c][np.isfinite(stacked[:, c])]
        if finite.size:
            out[c] = finite.max()
    return out


def reference_metadata(scene: Scene, estimate: ReceiverEstimate, *, key: str, versions: dict,
                       camera_cut: float, camera_variance: np.ndarray,
                       lookup: LookupPlan | None = None) -> dict:
    """A reference's ``metadata`` (``result.json``): what was traced and how, with
    ``hash`` = ``key``. The receiver maps' part comes from ``estimate`` (however its
    rounds were traced: :class:`ReceiverRounds`): ``photons`` the photons per seed
    traced, ``photon_budget`` the starting budget, ``noise_history`` (photons, noise,
    seconds) per round, ``relative_noise`` the largest channel's,
    ``relative_noise_per_channel`` (R, G, B) and ``noise_region_texels`` (texels of
    each receiver's caustic region), ``stopped_by``, ``cut_flux_fraction``.

    The camera image is ptracer's unless ``lookup`` (the camera tracer's lookup maps)
    is given. ``camera_cut``: ptracer, :func:`.camera.camera_cut_fraction`'s share of
    the image's light; the camera tracer, the fraction of its samples the event cap
    stopped (all-paths mode; 0 in chain mode).
    """
    s = scene.settings
    if lookup is None:
        camera = {
            "camera_integrator": CAMERA_INTEGRATORS["ptracer"],
            "camera_limits": list(CAMERA_LIMITS),
        }
    else:
        camera = {
            "camera_integrator": CAMERA_INTEGRATORS["trace"],
            "camera_limits": list(camera_trace_limits(lookup)),
            # The caustic lookup maps (one per seed) and the footprint rule they follow.
            "camera_lookup": {
                "resolution": list(lookup.resolution),
                "photons": lookup.photons,
                "footprint_percentile": FOOTPRINT_PERCENTILE,
                "footprints": list(lookup.footprints),
                "texels": list(lookup.texels),
                "cap": LOOKUP_CAP,
                "coarser_than_footprint": lookup.capped,
            },
        }
    return {
        "hash": key,
        "variant": versions["variant"],
        "versions": versions,
        "photons": estimate.photons,
        "photon_budget": s.photons,
        "channel_passes": estimate.channel_passes,
        "spp": s.spp,
        "seed": s.seed,
        "seeds": s.seeds,
        "relative_noise": estimate.relative_noise,
        "relative_noise_per_channel": [float(x) for x in estimate.relative_noise_per_channel],
        "noise_region_texels": list(estimate.region_texels),
        "target_noise": s.target_noise,
        "reference_time_cap": s.reference_time_cap,
        "stopped_by": estimate.stopped_by,
        "noise_history": [list(h) for h in estimate.history],
        "event_chains": event_chains_counted(scene),
        "cut_flux_fraction": estimate.cut_fraction,
        "max_specular_events": MAX_SPECULAR_EVENTS,
        # All-paths mode: Russian roulette past this many events, survival probability.
        "roulette_from": ROULETTE_FROM,
        "roulette_survival": ROULETTE_SURVIVAL,
        "camera_max_depth": camera_max_depth(scene),
        # ptracer: share of the camera image's light on paths past the cap, measured by
        # one seed rendered again with twice the cap (camera.camera_cut_fraction); the
        # camera tracer: share of its samples the cap stopped.
        "camera_cut_fraction": camera_cut,
        **camera,
        "scene": scene.name,
        "camera_variance": camera_variance.astype(np.float32),
    }


def _ptracer_camera(scene: Scene, geometry, *, progress: bool, timings: dict):
    """ptracer's K-seed camera image: (mean, variance of the mean, cut fraction)."""
    s = scene.settings
    start = time.perf_counter()
    frames = []
    seeds = range(s.seed, s.seed + s.seeds)
    iterator = seeds
    if progress:
        iterator = tqdm(seeds, desc=f"camera ({s.spp} spp per seed)", unit="seed", leave=False)
    for seed in iterator:
        frames.append(render_camera(scene, spp=s.spp, seed=seed, geometry=geometry))
    camera, camera_var = seed_statistics(np.stack(frames))
    timings["camera"] = time.perf_counter() - start
    start = time.perf_counter()
    camera_cut = camera_cut_fraction(scene, spp=s.spp, seed=s.seed, image=frames[0],
                                     geometry=geometry)
    if s.all_specular_paths:
        timings["camera_cut_probe"] = time.perf_counter() - start
    return camera, camera_var, camera_cut


def reference_result(scene: Scene, estimate: ReceiverEstimate, *, key: str, versions: dict,
                     camera: str = "trace", timings: dict[str, float], timer: str = TIMER,
                     geometry=None, progress: bool = False) -> RenderResult:
    """The reference of ``scene`` from its receiver maps' ``estimate``, however its
    rounds were traced (in this process, or a sweep's seed tasks merged): the camera
    image by ``camera`` (the camera tracer's lookup maps take their photon count from
    the estimate's), the metadata (:func:`reference_metadata`, ``hash`` = ``key``) and
    the result.

    Parameters
    ----------
    timings
        Seconds of the stages so far (the receiver maps'); the camera's are added.
    timer
        What ``timings`` measured.
    geometry
        The scene's meshes (built if None).
    """
    geometry = geometry or build_geometry(scene)
    timings = dict(timings)
    lookup = None
    if camera == "trace":
        # Each seed traces its own lookup maps, scaled from the receiver maps' photons.
        traced = render_traced_camera(scene, photons=estimate.photons, geometry=geometry,
                                      progress=progress)
        image, camera_var, camera_cut = traced.image, traced.variance, traced.cut_fraction
        timings["camera_lookup_maps"] = traced.seconds["lookup_maps"]
        timings["camera"] = traced.seconds["camera"]
        lookup = traced.plan
    else:
        image, camera_var, camera_cut = _ptracer_camera(scene, geometry, progress=progress,
                                                        timings=timings)
    _warn_cut(scene, camera_cut, "camera image", CAMERA_MAX_EVENTS)
    metadata = reference_metadata(scene, estimate, key=key, versions=versions,
                                  camera_cut=camera_cut, camera_variance=camera_var,
                                  lookup=lookup)
    return RenderResult(
        renderer="mitsuba", camera=image.astype(np.float32),
        receivers=tuple(estimate.caustic), effects=effects_of(scene), timings=timings,
        timer=timer, metadata=metadata,
    )


def cached_reference(scene: Scene, *, key: str, root: Path, camera: str = "trace",
                     render: Callable[[], RenderResult] | None = None
                     ) -> RenderResult | None:
    """The reference of ``scene`` in the cache at ``root`` under ``key``, else
    ``render()``'s, written there; None without ``render``. The key's lock is held
    throughout, so two processes that need one reference render it once (the other
    waits, then reads it), and a reference another process wrote meanwhile is read,
    not written again.

    ``metadata["cache"]`` says ``"hit"`` or why it missed; on a hit
    ``metadata["scene"]`` names ``scene`` (the key is the physics, not the name: a
    renamed scene hits the entry). An entry recording another ``camera`` integrator
    is a miss.
    """
    with entry_lock(root, key):
        result, why = load_entry(root, key, camera=camera)
        if result is not None:
            result.metadata["cache"] = "hit"
            result.metadata["scene"] = scene.name
            return result
        if render is None:
            return None
        result = render()
        write_result_dir(root / key, result)
        result.metadata["cache"] = f"miss ({why})"
        return result


def _render(scene: Scene, *, progress: bool, key: str, versions: dict,
            camera: str) -> RenderResult:
    geometry = build_geometry(scene)
    start = time.perf_counter()
    # Only the caustic maps are kept: no photon is spent on the direct light.
    est = estimate_receivers(scene, progress=progress, caustic_only=True)
    return reference_result(scene, est, key=key, versions=versions, camera=camera,
                            timings={"receiver_maps": time.perf_counter() - start},
                            geometry=geometry, progress=progress)


def render_reference(scene: Scene, *, cache: str | Path | None = None, use_cache: bool = True,
                     progress: bool = True, camera: str = "trace") -> RenderResult:
    """The Mitsuba reference of ``scene``, from the cache or rendered and cached
    (:func:`cached_reference`).

    Parameters
    ----------
    camera
        Camera integrator: ``"trace"``, the camera tracer (:mod:`.camera_trace`), or
        ``"ptracer"``, Mitsuba's particle tracer (:mod:`.camera`). Part of the cache
        key; an entry recording the other integrator is never returned.
    cache
        Cache root; default ``$CAUSTICS_CACHE_DIR`` or ~/.cache/caustics-harness/reference.
    use_cache
        False renders without reading or writing the cache.
    progress
        Show progress bars (tqdm, on stderr).

    Returns
    -------
    RenderResult
        ``camera``: mean radiance over K seeds; ``receivers``: mean irradiance maps
        with ``variance`` (of the mean); ``metadata``: photons, spp, seed(s),
        relative noise, event chains, versions, hash, ``cache`` ("hit" or why it
        missed), ``camera_variance`` (ndarray), ``camera_integrator``
        (``"camera_trace"`` or ``"ptracer"``) and its ``camera_limits``.

    Raises
    ------
    CameraIntegratorError
        ``camera`` names no camera integrator.
    """
    check_camera(camera)
    versions = _mi.versions()
    key = cache_key(scene, versions, camera=camera)

    def render() -> RenderResult:
        return _render(scene, progress=progress, key=key, versions=versions, camera=camera)

    if not use_cache:
        return render()
    return cached_reference(scene, key=key, root=cache_dir(cache), camera=camera,
                            render=render)
