"""Event-filtered photon tracer on Mitsuba's ray tracing, written in Dr.Jit.

Photons leave the light (:mod:`.emission`), are traced through the caustic
objects with ``scene.ray_intersect`` and our own specular events, and are
``scatter_reduce``-d into each receiver's (u, v) grid when they reach its front
side. Only the event chains the scene's effects name are counted:

=====================  ===========  ===========================================
object                 chain        rule
=====================  ===========  ===========================================
closed dielectric      L T T D      exactly two transmissions, same object
open water surface     L T D        exactly one transmission
conductor              L R D        exactly one reflection
direct light           L D          when ``scene.direct_lighting``; through the
                                    objects' shadow when ``shadows`` is on,
                                    traced past them (receivers only) when off
=====================  ===========  ===========================================

``settings.all_specular_paths`` counts every L S+ D path (any objects) instead.
A path then goes on until it leaves the scene, reaches a receiver or is absorbed.
Past :data:`ROULETTE_FROM` events it plays unbiased Russian roulette at every
event: it survives with probability p = :data:`ROULETTE_SURVIVAL` and its weight
becomes w / p, or it ends (weight 0); the expected weight after the event is
p (w / p) = w, so every map keeps its expectation and no flux is cut in
expectation (paths circling inside a dielectric, each reflection with F close
to 1, or trapped by total internal reflection, end with probability 1 - p per
event instead of at a fixed count). Only a safety cap of
:data:`MAX_SPECULAR_EVENTS` events, far beyond (a path reaches it with
probability p^(4096 - 64) < 1e-17), stops a path for certain, and the flux of the
paths it stops is recorded (``PhotonSums.cut``), never dropped silently.

Specular events
---------------
Refraction uses the shading normal n (the meshes' vertex normals, as the GPU
renderer does), oriented against the incoming direction d:
t = eta d + (eta cos_i - sqrt(k)) n,  k = 1 - eta^2 (1 - cos_i^2), eta = n1 / n2.
k < 0 is total internal reflection: without Fresnel the photon has no
transmitted branch and is **dropped** in chain mode (reflects with weight one in
all-paths mode). With the ``fresnel`` effect, the photon reflects with
probability F (exact dielectric Fresnel, ``mi.fresnel``) and keeps weight one; in
chain mode a reflection breaks the chain and drops it. Conductors reflect with
weight equal to their constant reflectance. A diffuse object absorbs.
Shading normals: a light particle that scatters at an interpolated normal n_s
(geometric normal n_g) gets the adjoint correction of Veach 1997, §5.3,

    w <- w |d . n_s| |d' . n_g| / (|d . n_g| |d' . n_s|),

with d the arriving and d' the leaving direction, so that light tracing and
camera tracing estimate the same transport on meshes (on the geometric normal
itself, n_s = n_g, the factor is 1). The side a photon arrives from (entering or
leaving) is decided by the geometric normal.
Beer-Lambert: every segment travelled inside a dielectric (after a transmission
into it, until the next surface: for a water surface, down to the floor) scales
the weight by exp(-sigma d) per channel.

Irradiance: a photon of weight w (flux x N) landing in texel i of area
A_uv (in (u, v) units) on a surface whose area per unit (u, v) is
J = |dp/du x dp/dv| adds w / (N A_uv J) W/m^2. Planes have J = 1.

Flux budget
-----------
With ``budget=True`` (caustic-only traces) the tracer also tallies, per photon and
RGB channel, where its weight went; every photon ends in exactly one of the
terminal items, and the weight it loses on the way is tallied as it goes, so the
items (:data:`BUDGET_ITEMS`) add up to the emitted weight:

* ``missed``: the first cast meets no object (nothing, or a receiver straight
  from the light: direct light, not a caustic);
* ``tir``: dropped by total internal reflection (chain mode without Fresnel);
* ``cap``: still going after the last event allowed (chain mode: a chain longer
  than any counted one; all-paths mode: the safety cap);
* ``left``: a later cast meets nothing (left the scene off every receiver);
* ``uncounted``: reached a receiver along a chain the effects do not count, or
  through a surface its last segment leaked through (:meth:`PhotonTracer._leaked`);
* ``fresnel``: a Fresnel reflection at a dielectric broke the chain (chain mode),
  and the photon ended anywhere but on a counted chain;
* ``back_or_outside``: a counted chain reached a receiver's back side or a point
  outside its map;
* ``absorbed_medium``: Beer-Lambert, w (1 - exp(-sigma d)) per segment;
* ``absorbed_surface``: (1 - R) w at conductors, and all of w at a diffuse object;
* ``shading``: w (1 - factor) of the adjoint shading-normal factor (signed: a
  factor above one is a gain, a negative loss);
* ``roulette``: Russian roulette past :data:`ROULETTE_FROM` events (all-paths
  mode), signed: w of a path it ends, w - w / p (a gain) of one that survives; its
  expectation is zero;
* ``deposited``: deposited on a counted chain (what the caustic maps hold).

The tallies are per-lane registers summed once per launch; the maps' kernel
never reads them, and a trace without the budget builds exactly the kernel it
built before they existed.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from renderers.mitsuba import _mi
from renderers.mitsuba.emission import (
    MAX_STRATIFIED_LANES,
    Target,
    bounding_sphere,
    sample_photons,
    stratified_square,
)
from renderers.mitsuba.exporter import ExportedScene, channel_mask, export_scene
from renderers.mitsuba.specular import specular_event
from scenes import effects_of, event_chain
from scenes.geometry import SceneGeometry, build_geometry
from scenes.model import Scene

__all__ = [
    "BUDGET_ITEMS",
    "DEFAULT_BATCH",
    "MAX_SPECULAR_EVENTS",
    "ROULETTE_FROM",
    "ROULETTE_SURVIVAL",
    "PhotonSums",
    "PhotonTracer",
    "event_chains_counted",
    "launch_plan",
    "trace_receiver_maps",
]

#: Specular events every L S+ D path is followed for certain (all-paths mode); past
#: them it plays Russian roulette. A hard cut here lost about 1e-4 of the glass
#: sphere's flux with Fresnel (0.7e-4 to 1.3e-4 measured: near-grazing paths circling
#: inside), an 8-event one 2.4 % of the bunny's.
ROULETTE_FROM = 64
#: Russian roulette's survival probability per event past ROULETTE_FROM. Close to
#: one: a path whose own continuation probability q (F of its reflections) is below
#: p adds a factor (1 - q) / (1 - q / p) to its second moment, 1.1 at q = 0.9, and the
#: expected extra events, 1 / (1 - p q) < 100, cost little (few paths get there).
ROULETTE_SURVIVAL = 0.99
#: Safety cap on the specular events of one path (all-paths mode), far past
#: ROULETTE_FROM: roulette ends a path before it with probability
#: 1 - 0.99^4032 > 1 - 1e-17, so only the weight of an endless loop of total internal
#: reflection could reach it; the flux it cuts is recorded.
MAX_SPECULAR_EVENTS = 4096
#: In all-paths mode, the paths still alive after this many events (about 1 % of the
#: bunny's) are compacted and followed in one symbolic loop up to the cap.
_TAIL_FROM = 8
#: Test each photon that reaches a receiver for a leak (:meth:`PhotonTracer._leaked`);
#: False only to measure what the test removes.
LEAK_TEST = True
#: A segment traced back from its receiver may meet a surface this close to its start,
#: as a share of the scene's bounding radius: the surface it left, within the rounding
#: band a grazing segment runs along (the spawn offset over |d . n|: glass_sphere's
#: exit rays at d . n = 0.03 met their own sphere up to 1.5 mm back; with 0.1 % of the
#: radius the test removed 3.3e-5 of its caustic flux, with 0.3 % and 1 % none).
LEAK_MARGIN = 1e-2
#: Photons per kernel launch (memory ~ 100 B per lane).
DEFAULT_BATCH = 1 << 20

_T, _R = 1, 2  # event codes: code = code * 3 + event

#: Where a photon's weight goes (see the module docstring, "Flux budget"), in the
#: order the budget lists them.
BUDGET_ITEMS = ("missed", "tir", "cap", "left", "uncounted", "fresnel", "back_or_outside",
                "absorbed_medium", "absorbed_surface", "shading", "roulette", "deposited")


def launch_plan(photons: int, batch: int = DEFAULT_BATCH) -> tuple[int, ...]:
    """Lanes of each kernel launch that traces ``photons`` photons: whole launches of
    ``batch`` lanes, then the remainder (if any) as one partial launch.

    Every launch is stratified at its own size (:func:`.emission.stratified_square`:
    one stratum per lane, whatever the lane count), so a partial launch has no
    unstratified lanes; it only has coarser strata than a whole one. The sizes sum
    to ``photons`` exactly.

    Raises
    ------
    ValueError
        ``photons`` < 1, or ``batch`` not in 1 .. :data:`.emission.MAX_STRATIFIED_LANES`.
    """
    photons, batch = int(photons), int(batch)
    if photons < 1:
        raise ValueError(f"a trace needs at least one photon, got {photons}")
    if not 1 <= batch <= MAX_STRATIFIED_LANES:
        raise ValueError(f"a launch has 1 to {MAX_STRATIFIED_LANES} lanes, got {batch}")
    whole, rest = divmod(photons, batch)
    return (batch,) * whole + ((rest,) if rest else ())


def chain_code(chain: str) -> int:
    code = 0
    for event in chain.split()[1:-1]:
        code = code * 3 + (_T if event == "T" else _R)
    return code


def event_chains_counted(scene: Scene) -> list[str]:
    """Human-readable list of the light paths the photon tracer counts."""
    chains = []
    if scene.info.direct_lighting:
        chains.append("L D" if scene.info.shadows else "L D (unshadowed)")
    if scene.settings.all_specular_paths:
        chains.append(f"L S+ D (any objects; Russian roulette past {ROULETTE_FROM} "
                      f"events, safety cap {MAX_SPECULAR_EVENTS} events, cut flux recorded)")
    else:
        for i, obj in enumerate(scene.objects):
            if event_chain(obj):
                chains.append(f"{event_chain(obj)} (objects[{i}])")
    return chains


@dataclasses.dataclass(frozen=True, eq=False)
class PhotonSums:
    """Unnormalised sums of one or more batches (divide by ``photons``).

    Attributes
    ----------
    total, caustic : list of ndarray (H, W, 3) float64
        Per receiver, sum of w / (A_uv J) over counted photons: everything counted,
        and only the specular chains (no direct light).
    photons : int
        Photons emitted (per channel pass).
    emitted : ndarray (3,) float64
        Sum of the photons' initial weights (flux x photons, W), RGB (all-paths mode;
        zero in chain mode, which has no path limit).
    cut : ndarray (3,) float64
        Sum of the weights of paths still alive when the safety cap stopped them
        (all-paths mode; zero otherwise). ``cut / emitted`` is the fraction of the
        emitted flux lost to the path limit.
    casts : int
        Ray casts the photons' paths made (past the direct-light pass), summed
        over lanes and events: the tracer's work, to set its cost beside the
        events a path limit allows.
    budget : ndarray (launches, len(BUDGET_ITEMS), 3) float64, or None
        With ``PhotonTracer(..., budget=True)``: per launch, the weight sum (W x
        photons, RGB) of each item of :data:`BUDGET_ITEMS`; ``emitted`` is then
        summed in chain mode too.
    launch_emitted : ndarray (launches, 3) float64, or None
        With the budget: the emitted weight sum of each launch.
    launch_pass : tuple of int, or None
        With the budget: the channel pass (0, or 0..2 with dispersion) of each launch.
    screened : int
        With the budget: photons left out of it because their emission weight was
        not finite or above :data:`_SCREEN_FACTOR` times the light's intensity
        (:meth:`_Tally.screen`).
    """

    total: list
    caustic: list
    photons: int
    emitted: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    cut: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    casts: int = 0
    budget: np.ndarray | None = None
    launch_emitted: np.ndarray | None = None
    launch_pass: tuple[int, ...] | None = None
    screened: int = 0


def lane_rng(n: int, key: int):
    """One PCG32 per lane, its state and stream both hashed (TEA) from (key, lane).

    Plain ``PCG32(n, key, lane)`` gives lane i the same stream (increment) under
    every key, only at another offset, and such streams are measurably correlated
    (about -0.01 between keys for the same lane); with stratified lanes (one lane,
    one place) that made different seeds' maps correlated, and the K-seed variance
    too small. Hashing the key into both the state and the stream decorrelates
    them. The key enters as opaque values: one compiled kernel serves every launch.
    """
    mi, dr, _ = _mi.load()
    key &= 0xFFFFFFFFFFFFFFFF
    lo = dr.opaque(mi.UInt32, key & 0xFFFFFFFF)
    hi = dr.opaque(mi.UInt32, key >> 32)
    lane = dr.arange(mi.UInt32, n)
    a0, a1 = mi.sample_tea_32(lo, lane, 8)
    b0, b1 = mi.sample_tea_32(hi ^ a0, a1, 8)
    state = (mi.UInt64(b0) << 32) | mi.UInt64(a0)
    seq = (mi.UInt64(b1) << 32) | mi.UInt64(a1)
    return mi.PCG32(n, state, seq)


class PhotonTracer:
    """A scene prepared for photon tracing (exported once, traced many times).

    Parameters
    ----------
    scene : Scene
    geometry : SceneGeometry, optional
    resolution : (W, H), optional
        Map size per receiver; default ``settings.receiver_map``.
    extents : list of (umin, umax, vmin, vmax), optional
        Per receiver; default the receiver's own (u, v) extent.
    caustic_only : bool
        Trace only what the caustic maps need (default False: totals too).

        The caustic maps count specular chains only (every counted chain's first
        event is on a caustic object: "L S+ D", "L T T D", "L T D", "L R D"), so a
        photon can contribute only if its emitted ray reaches a caustic object,
        i.e. its direction (point/spot light) or its origin on the plane
        perpendicular to the light (directional light) lies in the cone or disk of
        that object's bounding sphere. With ``caustic_only`` the emission mixture
        has the object targets alone (q_j proportional to their size, summing to
        one, no share aimed at receivers) and the photon's weight divides by that
        mixture pdf. Its support is the union of the object targets, which holds
        every direction that can start a counted chain, so each caustic map's
        expectation is the same integral as with the default mixture (whose
        receiver share only ever lands in the direct term); only its variance
        changes. The direct term is then not traced at all: ``PhotonSums.total``
        is None. Area lights are not focused in either mode; without caustic
        objects the default targets are kept (the caustic maps are zero anyway).
    shading_correction : bool
        Apply the adjoint shading-normal correction (see the module docstring);
        off only to measure its effect.
    budget : bool
        Tally where each photon's weight went (``PhotonSums.budget``; the module
        docstring's "Flux budget"). Needs ``caustic_only``. The maps are the same
        with or without it.
    loaded : dict, optional
        The Mitsuba scenes to trace on, one per channel pass (key None, or 0, 1, 2 with
        the ``dispersion`` effect), as :func:`~.exporter.exported` gives them (a scene
        read back from exported XML); default :func:`~.exporter.export_scene` of each
        pass. Light, materials and chains still come from ``scene``.
    """

    def __init__(self, scene: Scene, *, geometry: SceneGeometry | None = None,
                 resolution: tuple[int, int] | None = None,
                 extents: list | None = None, caustic_only: bool = False,
                 shading_correction: bool = True, budget: bool = False,
                 loaded: dict | None = None) -> None:
        _, _, variant = _mi.load()
        if not variant.startswith(("llvm", "cuda")):
            raise _mi.MitsubaError(
                f"the photon tracer needs a vectorised Mitsuba variant, got {variant}"
            )
        if budget and not caustic_only:
            raise ValueError("the flux budget is tallied on caustic-only traces")
        self.budget = bool(budget)
        self.scene = scene
        self.geometry = geometry or build_geometry(scene)
        self.resolution = tuple(resolution or scene.settings.receiver_map)
        extents = extents or [r.extent for r in self.geometry.receivers]
        self.extents = [tuple(float(x) for x in e) for e in extents]
        self.effects = effects_of(scene)
        self.all_paths = scene.settings.all_specular_paths
        self.shading_correction = bool(shading_correction)
        dispersion = "dispersion" in self.effects
        self.channels = [0, 1, 2] if dispersion else [None]
        if loaded is not None and set(loaded) != set(self.channels):
            raise ValueError(f"loaded scenes for passes {sorted(loaded, key=str)}, the scene "
                             f"has passes {self.channels}")
        self.exported: dict = dict(loaded) if loaded is not None else {
            c: export_scene(scene, geometry=self.geometry, channel=c) for c in self.channels
        }
        info = scene.info
        self.caustic_only = bool(caustic_only)
        direct = info.direct_lighting and not self.caustic_only
        self.direct_full = direct and info.shadows
        self.direct_unshadowed = direct and not info.shadows
        self.receivers_only: ExportedScene | None = (
            export_scene(scene, geometry=self.geometry, include_objects=False)
            if self.direct_unshadowed else None
        )
        targets = [bounding_sphere(o.mesh, "object") for o in self.geometry.objects]
        if direct or not targets:
            targets += [bounding_sphere(r.mesh, "receiver") for r in self.geometry.receivers]
        self.targets: list[Target] = targets
        allp = np.concatenate([r.mesh.positions for r in self.geometry.receivers]
                              + [o.mesh.positions for o in self.geometry.objects]).astype(float)
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        self.scene_center = tuple(((lo + hi) / 2).tolist())
        self.scene_radius = float(np.linalg.norm(hi - lo) / 2) + 1e-3
        chains = [chain_code(event_chain(o)) if event_chain(o) else -1 for o in scene.objects]
        self.chain_codes = chains
        lengths = [len(event_chain(o).split()) - 2 for o in scene.objects if event_chain(o)]
        self.max_events = MAX_SPECULAR_EVENTS if self.all_paths else max(lengths or [0])
        # Depths at which a photon reaching a receiver can be counted (elsewhere the
        # deposit's mask is false for every lane and is left out of the kernel).
        counted = set(range(1, self.max_events + 1)) if self.all_paths else set(lengths)
        if self.direct_full:
            counted.add(0)
        self.deposit_depths = frozenset(counted)

    # ----------------------------------------------------------------- tracing
    def trace(self, photons: int, *, seed: int, stream: int = 0,
              batch: int = DEFAULT_BATCH) -> PhotonSums:
        """Trace ``photons`` photons per channel pass, in the launches of
        :func:`launch_plan` (whole launches of ``batch`` lanes and a partial last one,
        each stratified at its own size).

        ``seed`` and ``stream`` select independent random sequences: (seed, stream)
        pairs never share a PCG32 sequence. With ``caustic_only`` the sums' ``total``
        is None.
        """
        mi, dr, _ = _mi.load()
        w, h = self.resolution
        n_rec = len(self.extents)
        total = None if self.caustic_only else [dr.zeros(mi.Float, w * h * 3)
                                                for _ in range(n_rec)]
        caustic = [dr.zeros(mi.Float, w * h * 3) for _ in range(n_rec)]
        sizes = launch_plan(photons, batch)
        emitted, cut, casts = np.zeros(3), np.zeros(3), 0
        tallies, launch_emitted, launch_pass, screened = [], [], [], 0
        for p, c in enumerate(self.channels):
            for launch, lanes in enumerate(sizes):
                key = ((seed * 1_000_003 + stream) * 7 + (0 if c is None else c + 1)) \
                    * 1_000_003 + launch
                tally = _Tally() if self.budget else None
                flux = self._launch(lanes, key, c, total, caustic, tally=tally)
                dr.eval(total, caustic)
                emitted += flux[0]
                cut += flux[1]
                casts += flux[2]
                if tally is not None:
                    tallies.append(tally.sums(lanes))
                    screened += tally.screened
                    launch_emitted.append(flux[0])
                    launch_pass.append(p)
        shape = (h, w, 3)
        return PhotonSums(
            total=None if total is None
            else [np.asarray(t, dtype=np.float64).reshape(shape) for t in total],
            caustic=[np.asarray(t, dtype=np.float64).reshape(shape) for t in caustic],
            photons=sum(sizes), emitted=emitted, cut=cut, casts=casts,
            budget=np.stack(tallies) if self.budget else None,
            launch_emitted=np.stack(launch_emitted) if self.budget else None,
            launch_pass=tuple(launch_pass) if self.budget else None, screened=screened,
        )

    def _launch(self, n: int, key: int, channel, total, caustic, *,
                tally: _Tally | None = None) -> tuple[np.ndarray, ...]:
        """Trace one batch; returns the (emitted, cut) weight sums (RGB) and the ray
        casts (see PhotonSums). ``tally`` collects the flux budget (``budget``)."""
        mi, _, _ = _mi.load()
        rng = lane_rng(n, key)
        square = stratified_square(rng, n)
        ray, weight = sample_photons(self.scene.light, self.targets, rng,
                                     self.scene_center, self.scene_radius, square=square)
        weight *= mi.Color3f(*map(float, channel_mask(channel)))
        exported = self.exported[channel]
        if self.direct_unshadowed:
            si = self.receivers_only.scene.ray_intersect(ray)
            self._deposit(si, ray.d, weight, si.is_valid(),
                          receiver_ids=self.receivers_only.receiver_ids, total=total, caustic=None)
        if tally is not None:
            weight = tally.screen(weight, self.scene.light)
        # Only all-paths mode has a path limit to account for; chain mode cuts nothing
        # (the budget needs the emitted weight in every mode).
        emitted = _rgb_sum(weight, n) if self.all_paths or tally is not None else np.zeros(3)
        cut, casts = self._trace_chain(exported, ray, weight, rng=rng, channel=channel,
                                       total=total,
                                caustic=caustic, lanes=n, tally=tally)
        return emitted, cut, casts

    def _trace_chain(self, exported: ExportedScene, ray, weight, *, rng, channel,
                     total, caustic, lanes: int,
                     tally: _Tally | None = None) -> tuple[np.ndarray, int]:
        """Follow the photons through their specular events, depositing the counted
        ones; returns the weight sum (RGB) of paths the safety cap stopped and the
        number of ray casts traced (lanes x events, the tracer's work).

        The first events are unrolled in Python (chain mode needs the event codes
        of each depth). In all-paths mode, the few paths still alive after
        :data:`_TAIL_FROM` events are compacted and followed in one Dr.Jit
        symbolic loop up to the cap, so long chains of total internal reflection
        cost only the ray casts they make; past :data:`ROULETTE_FROM` events each
        event plays Russian roulette (:func:`_roulette`).
        """
        mi, dr, _ = _mi.load()
        active = mi.Bool(True)
        code = mi.UInt32(0)
        first = mi.UInt32(0)
        mixed = mi.Bool(False)
        sigma = mi.Color3f(0.0)
        tail = self.all_paths and self.max_events > _TAIL_FROM
        head = _TAIL_FROM if tail else self.max_events
        cast = mi.UInt32(0)  # ray casts per lane
        broken = mi.Bool(False)  # a Fresnel reflection broke the chain (budget only)
        for depth in range(head + 1):
            cast += dr.select(active, 1, 0)
            arriving = weight
            si, hit, weight = self._arrive(exported, ray, weight, sigma, active)
            deposited, ok = mi.Bool(False), mi.Bool(False)
            if depth in self.deposit_depths:
                if self.all_paths:
                    ok = mi.Bool(depth > 0)
                else:
                    ok = mi.Bool(False)
                    for j, oid in enumerate(exported.object_ids):
                        if self.chain_codes[j] > 0:
                            ok |= (first == oid) & (code == self.chain_codes[j])
                    ok &= ~mixed
                if self.direct_full:
                    ok |= code == 0
                ok &= ~self._leaked(exported, si, ray.d, hit & ok)
                deposited = self._deposit(si, ray.d, weight, hit & ok,
                                          receiver_ids=exported.receiver_ids, total=total,
                                          caustic=caustic if depth > 0 else None)
            last = depth == self.max_events and not self.all_paths
            if tally is not None:
                tally.arrival(si, receiver_ids=exported.receiver_ids, active=active, hit=hit,
                              ok=ok, deposited=deposited, broken=broken, first=depth == 0,
                              arriving=arriving, weight=weight, last=last)
            if last:
                dr.eval(cast, total, caustic, *([] if tally is None else tally.registers()))
                return np.zeros(3), _total(cast, lanes)  # every chain ends here
            event = self._event(exported, si, ray=ray, weight=weight, sigma=sigma, rng=rng,
                                hit=hit, channel=channel)
            if tally is not None:
                tally.event(event, weight=weight, alive=hit & ~tally.on_receiver,
                            broken=broken)
                if not self.all_paths:
                    broken |= event.dielectric_reflection
            sid = dr.reinterpret_array(mi.UInt32, si.shape)
            first = dr.select(depth == 0, sid, first)
            mixed |= sid != first
            code = code * 3 + dr.select(event.reflected, mi.UInt32(_R), mi.UInt32(_T))
            ray, weight, sigma, active = event.ray, event.weight, event.sigma, event.going_on
            if self.all_paths and depth >= ROULETTE_FROM:
                weight, active = _roulette(weight, active, rng, tally=tally)
            if depth == self.max_events:
                # Paths that would go on: the cap cuts them, and their flux is what
                # the cap loses.
                alive = dr.select(active, weight, 0.0)
                registers = []
                if tally is not None:
                    tally.add("cap", active, weight)
                    registers = tally.registers()
                dr.eval(alive, cast, total, caustic, *registers)  # one kernel for the path
                return _rgb_sum(alive, lanes), _total(cast, lanes)
        # Wavefront compaction: keep only the paths still alive. The state is
        # evaluated in one kernel first: each gather from an unevaluated array would
        # otherwise re-run every event so far in a kernel of its own.
        dr.eval(ray, weight, rng, sigma, active, cast, total, caustic,
                *([] if tally is None else tally.registers()))
        casts = _total(cast, lanes)
        if tally is not None:
            tally.close(lanes)  # the head's registers, summed before the lanes change
        idx = dr.compress(active)
        lanes = dr.width(idx)
        if lanes == 0:
            return np.zeros(3), casts
        ray, weight, rng, sigma = (dr.gather(type(x), x, idx) for x in (ray, weight, rng, sigma))
        ray, weight, sigma, active, casts_tail = self._tail(
            exported, ray, weight, sigma, rng, channel=channel, total=total, caustic=caustic,
            lanes=lanes, tally=tally)
        return _rgb_sum(dr.select(active, weight, 0.0), lanes), casts + casts_tail

    def _tail(self, exported: ExportedScene, ray, weight, sigma, rng, *, channel, total,
              caustic, lanes: int, tally: _Tally | None = None):
        """Events ``_TAIL_FROM + 1`` .. cap of the surviving paths in one symbolic loop
        (all-paths mode: every receiver hit counts; Russian roulette past
        :data:`ROULETTE_FROM` events); returns the state after the cap's event and
        the ray casts made. With ``tally``, the budget's registers ride in the loop's
        state (one per item, for the compacted lanes)."""
        mi, dr, _ = _mi.load()
        items = len(BUDGET_ITEMS) if tally is not None else 0
        # Roulette is compiled into the loop only when the loop reaches its events.
        roulette = self.max_events >= ROULETTE_FROM

        def step(*state):
            ray, weight, sigma, rng, active, depth, casts = state[:7]
            arriving = weight
            si, hit, weight = self._arrive(exported, ray, weight, sigma, active)
            landed = hit & ~self._leaked(exported, si, ray.d, hit)
            deposited = self._deposit(si, ray.d, weight, landed,
                                      receiver_ids=exported.receiver_ids, total=total,
                                      caustic=caustic)
            event = self._event(exported, si, ray=ray, weight=weight, sigma=sigma, rng=rng,
                                hit=hit, channel=channel)
            step_tally = None
            if items:
                step_tally = _Tally(dict(zip(BUDGET_ITEMS, state[7:], strict=True)))
                step_tally.arrival(si, receiver_ids=exported.receiver_ids, active=active,
                                   hit=hit, ok=mi.Bool(True), deposited=deposited,
                                   broken=mi.Bool(False), first=False, arriving=arriving,
                                   weight=weight, last=False)
                step_tally.event(event, weight=weight, alive=hit & ~step_tally.on_receiver,
                                 broken=mi.Bool(False))
            weight, going_on = event.weight, event.going_on
            if roulette:
                weight, going_on = _roulette(weight, going_on, rng, tally=step_tally,
                                             play=depth >= ROULETTE_FROM)
            registers = () if step_tally is None else tuple(step_tally.registers())
            # Lanes that stopped keep their state (the loop masks them out).
            return (event.ray, weight, event.sigma, rng, going_on, depth + 1,
                    casts + 1, *registers)

        zeros = tuple(dr.zeros(mi.Color3f, lanes) for _ in range(items))
        state = (ray, weight, sigma, rng, dr.full(mi.Bool, True, lanes),
                 dr.full(mi.UInt32, _TAIL_FROM + 1, lanes), dr.zeros(mi.UInt32, lanes), *zeros)
        ray, weight, sigma, rng, active, _, casts, *registers = dr.while_loop(
            state=state,
            cond=lambda *state: state[4] & (state[5] <= self.max_events),
            body=step,
            labels=("ray", "weight", "sigma", "rng", "active", "depth", "casts",
                    *BUDGET_ITEMS[:items]),
            label="photon_tail",
        )
        dr.eval(ray, weight, active, casts, total, caustic, *registers)
        if tally is not None:
            tail_tally = _Tally(dict(zip(BUDGET_ITEMS, registers, strict=True)))
            tail_tally.add("cap", active, weight)
            tally.merge(tail_tally, lanes)
        return ray, weight, sigma, active, _total(casts, lanes)

    def _arrive(self, exported: ExportedScene, ray, weight, sigma, active):
        """Cast ``ray`` for the ``active`` lanes; attenuate by Beer-Lambert over the
        segment (``sigma`` of the medium travelled, 1/m). Returns (si, hit, weight)."""
        _, dr, _ = _mi.load()
        si = exported.scene.ray_intersect(ray, active)
        hit = active & si.is_valid()
        weight = weight * dr.exp(-sigma * dr.select(hit, si.t, 0.0))
        return si, hit, weight

    def _leaked(self, exported: ExportedScene, si, d, mask):
        """The lanes of ``mask`` whose last segment (direction ``d``, reaching the
        receiver hit ``si``) leaked through a surface: traced back from the receiver,
        it meets one more than :data:`LEAK_MARGIN` short of where it started.

        The ray cast is not watertight: a ray through a shared edge or vertex of a
        mesh can miss both triangles. In exact arithmetic the segment meets nothing
        either way; traced back it crosses the edge at other rounding, and is caught.
        On ``scenes/hard/concave/bowl_shallow_sun60`` every photon the reference put on
        the floor (6 of 4 x 2^22, 5.4e-6 W) had passed through the bowl: its segment
        from the inside wall to the floor crosses the cap's sphere 0.6 to 1.3 m from
        where it starts. Elsewhere the test removes little (4 x 2^21 photons, share of
        the caustic flux): bowl_sun 1.1e-6, cup_sun 2e-7, spot_torus 2e-6, the bunny
        9e-5 (a mesh of 28,088 vertices), glass_sphere none. A segment that only grazes
        a surface within rounding may be dropped too: a set of rays of measure zero."""
        mi, dr, _ = _mi.load()
        if not LEAK_TEST:
            return mi.Bool(False)
        back = si.spawn_ray(-d)
        back.maxt = dr.maximum(si.t - LEAK_MARGIN * self.scene_radius, 0.0)
        return mask & exported.scene.ray_test(back, mask)

    def _event(self, exported: ExportedScene, si, *, ray, weight, sigma, rng, hit, channel):
        """The specular event at ``si`` (:func:`.specular.specular_event`)."""
        return specular_event(si, ray, weight, sigma, rng, hit=hit,
                              object_ids=exported.object_ids, objects=self.geometry.objects,
                              channel=channel, all_paths=self.all_paths,
                              shading_correction=self.shading_correction)

    def _deposit(self, si, d, weight, mask, *, receiver_ids, total, caustic):
        """scatter_reduce the photons of ``mask`` into the texel their (u, v) falls in;
        returns the lanes deposited (read only by the flux budget)."""
        mi, dr, _ = _mi.load()
        deposited = mi.Bool(False)
        w, h = self.resolution
        sid = dr.reinterpret_array(mi.UInt32, si.shape)
        front = dr.dot(d, si.sh_frame.n) < 0  # Lambertian receivers are one-sided
        jac = dr.norm(dr.cross(si.dp_du, si.dp_dv))
        for r, rid in enumerate(receiver_ids):
            umin, umax, vmin, vmax = self.extents[r]
            texel_area = (umax - umin) * (vmax - vmin) / (w * h)
            fu = (si.uv.x - umin) / (umax - umin) * w
            fv = (si.uv.y - vmin) / (vmax - vmin) * h
            inside = (fu >= 0) & (fu < w) & (fv >= 0) & (fv < h)
            m = mask & (sid == rid) & front & inside & (jac > 0)
            index = (mi.UInt32(dr.clip(fv, 0, h - 1)) * w
                     + mi.UInt32(dr.clip(fu, 0, w - 1))) * 3
            value = weight / (texel_area * dr.select(jac > 0, jac, 1.0))
            for ch in range(3):
                if total is not None:
                    dr.scatter_reduce(dr.ReduceOp.Add, total[r], value[ch], index + ch, m)
                if caustic is not None:
                    dr.scatter_reduce(dr.ReduceOp.Add, caustic[r], value[ch], index + ch, m)
            deposited |= m
        return deposited


def _roulette(weight, going_on, rng, *, tally: _Tally | None = None, play=True):
    """Russian roulette on the photons ``going_on`` (where ``play``, a Python or
    Dr.Jit bool): each survives with probability p = :data:`ROULETTE_SURVIVAL`, its
    weight divided by p, or ends. E[weight after] = p (w / p) = w: unbiased. One
    uniform number is drawn from ``rng`` for every lane. Returns (weight, going_on);
    ``tally`` books w of an ended photon and w - w / p of a survivor as ``roulette``.
    """
    mi, dr, _ = _mi.load()
    p = ROULETTE_SURVIVAL
    rolled = going_on & play
    survives = rng.next_float32() < p
    ended = rolled & ~survives
    kept = rolled & survives
    boosted = weight * (1.0 / p)
    if tally is not None:
        tally.add("roulette", ended, weight)
        tally.add("roulette", kept, weight - boosted)
    weight = dr.select(kept, boosted, dr.select(ended, mi.Color3f(0.0), weight))
    return weight, going_on & ~ended


#: A photon's weight is I / pdf with pdf = sum_j q_j / Omega_j >= q_j / (4 pi) (or
#: E0 / pdf with pdf >= q_j / (pi r_j^2)): a weight 1e20 times the light's intensity
#: needs q_j below 1e-19, so such a weight is not a sampled pdf but one rounded to
#: zero (``emission.sample_photons`` re-tests the cone it sampled in, and a direction
#: on the cone's edge can test outside: weight I / 1e-30, or E0 / 0 = inf).
_SCREEN_FACTOR = 1e20


class _Tally:
    """Per-lane registers of the flux budget (one Color3f per item of
    :data:`BUDGET_ITEMS`) and, once a launch's lanes are summed, their RGB sums.

    ``arrival`` classifies where a cast ended, ``event`` what the specular event
    took; each photon ends in one terminal item, and the weight it loses on the way
    goes to ``absorbed_medium``, ``absorbed_surface`` and ``shading`` as it is lost.
    """

    def __init__(self, registers: dict | None = None):
        mi, _, _ = _mi.load()
        self.acc = registers or {item: mi.Color3f(0.0) for item in BUDGET_ITEMS}
        self.summed = np.zeros((len(BUDGET_ITEMS), 3))
        self.on_receiver = mi.Bool(False)
        self.screened = 0

    def screen(self, weight, light):
        """Leave out of the budget the photons whose emission pdf was rounded to zero
        (see :data:`_SCREEN_FACTOR`): their weight is not finite or absurd, and would
        swamp the emitted sum. Such photons leave along the edge of a target's cone
        or disk, which bounds the object with a margin, so they miss it and never
        reach a caustic map; they are counted in ``screened``."""
        _, dr, _ = _mi.load()
        power = np.asarray(getattr(light, "intensity", getattr(light, "irradiance", 1.0)),
                           float)
        bound = _SCREEN_FACTOR * max(float(np.max(power)), 1e-30)
        largest = dr.maximum(dr.maximum(weight[0], weight[1]), weight[2])
        bad = ~dr.isfinite(largest) | (largest > bound)
        self.screened = int(dr.count(bad)[0]) if dr.width(bad) > 1 else int(bool(bad[0]))
        return dr.select(bad, 0.0, weight)

    def add(self, item: str, mask, value) -> None:
        """Add ``value`` (Color3f) of the lanes in ``mask`` to ``item``."""
        _, dr, _ = _mi.load()
        self.acc[item] = self.acc[item] + dr.select(mask, value, 0.0)

    def arrival(self, si, *, receiver_ids, active, hit, ok, deposited, broken, first: bool,
                arriving, weight, last: bool) -> None:
        """Tally a cast of the ``active`` lanes: Beer-Lambert on the segment, and the
        photons whose path ends here (nothing met, a receiver, or the chain's last
        event reached on an object)."""
        mi, dr, _ = _mi.load()
        sid = dr.reinterpret_array(mi.UInt32, si.shape)
        on_receiver = mi.Bool(False)
        for rid in receiver_ids:
            on_receiver |= sid == rid
        self.on_receiver = on_receiver
        self.add("absorbed_medium", active, arriving - weight)
        self.add("missed" if first else "left", active & ~hit, weight)
        self.add("deposited", deposited, weight)
        landed = hit & on_receiver & ~deposited
        if first:
            self.add("missed", landed, weight)
        else:
            self.add("back_or_outside", landed & ok, weight)
            self.add("fresnel", landed & ~ok & broken, weight)
            self.add("uncounted", landed & ~ok & ~broken, weight)
        if last:  # an object after the last counted event: the chain would go on
            on_object = hit & ~on_receiver
            self.add("fresnel", on_object & broken, weight)
            self.add("cap", on_object & ~broken, weight)

    def event(self, event, *, weight, alive, broken) -> None:
        """Tally a specular event at the lanes ``alive`` (hit an object): dropped by
        total internal reflection, absorbed by a diffuse object, or the weight a
        conductor and the shading-normal factor took from a photon going on."""
        self.add("tir", event.dropped, weight)
        absorbed = alive & ~event.going_on & ~event.dropped
        self.add("fresnel", absorbed & broken, weight)
        self.add("absorbed_surface", absorbed & ~broken, weight)
        self.add("absorbed_surface", event.going_on, event.surface_loss)
        self.add("shading", event.going_on, event.shading_loss)

    def registers(self) -> list:
        """The per-lane registers, in :data:`BUDGET_ITEMS` order (to evaluate)."""
        return [self.acc[item] for item in BUDGET_ITEMS]

    def close(self, lanes: int) -> None:
        """Sum the registers over ``lanes`` lanes into ``summed`` and start afresh."""
        mi, _, _ = _mi.load()
        self.summed += np.stack([_rgb_sum(self.acc[item], lanes) for item in BUDGET_ITEMS])
        self.acc = {item: mi.Color3f(0.0) for item in BUDGET_ITEMS}

    def merge(self, other: _Tally, lanes: int) -> None:
        """Add another tally's registers over ``lanes`` lanes (the compacted tail)."""
        other.close(lanes)
        self.summed += other.summed

    def sums(self, lanes: int) -> np.ndarray:
        """(items, 3) weight sums of the launch (its ``lanes`` lanes)."""
        self.close(lanes)
        return self.summed


def _total(count, lanes: int) -> int:
    """Sum of a per-lane UInt32 count over ``lanes`` lanes, as an int."""
    mi, dr, _ = _mi.load()
    return int(dr.sum(dr.zeros(mi.UInt64, lanes) + mi.UInt64(count))[0])


def _rgb_sum(weight, lanes: int) -> np.ndarray:
    """Sum of a Color3f over ``lanes`` lanes, as a float64 RGB vector (a uniform
    weight may be a width-1 literal: it is broadcast to every lane first)."""
    mi, dr, _ = _mi.load()
    lanes_zero = dr.zeros(mi.Float, lanes)
    return np.array([float(dr.sum(lanes_zero + weight[c])[0]) for c in range(3)],
                    dtype=np.float64)


def trace_receiver_maps(scene: Scene, *, photons: int, seed: int,
                        resolution: tuple[int, int] | None = None,
                        extents: list | None = None) -> list[np.ndarray]:
    """One seed of the photon tracer: irradiance per receiver.

    Returns
    -------
    list of ndarray, (H, W, 3), float64
        E in W/m² over each receiver's (u, v) extent, row 0 at vmin.
    """
    tracer = PhotonTracer(scene, resolution=resolution, extents=extents)
    sums = tracer.trace(photons, seed=seed)
    return [t / sums.photons for t in sums.total]
