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
A path then goes on until it leaves the scene, reaches a receiver or is absorbed;
only a safety cap of :data:`MAX_SPECULAR_EVENTS` events stops endless loops of
total internal reflection, and the flux of the paths the cap stops is recorded
(``PhotonSums.cut``), never dropped silently. No Russian roulette is used.

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
"""

from __future__ import annotations

import dataclasses

import numpy as np

from renderers.mitsuba import _mi
from renderers.mitsuba.emission import (
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
    "MAX_SPECULAR_EVENTS",
    "PhotonSums",
    "PhotonTracer",
    "event_chains_counted",
    "trace_receiver_maps",
]

#: Safety cap on the specular events of one path when all L S+ D paths are counted:
#: high enough that it only stops paths trapped by total internal reflection (an
#: 8-event cap lost 2.4 % of the bunny's caustic flux; the cut flux is recorded).
MAX_SPECULAR_EVENTS = 64
#: In all-paths mode, the paths still alive after this many events (about 1 % of the
#: bunny's) are compacted and followed in one symbolic loop up to the cap.
_TAIL_FROM = 8
#: Photons per kernel launch (memory ~ 100 B per lane).
DEFAULT_BATCH = 1 << 20

_T, _R = 1, 2  # event codes: code = code * 3 + event


def _chain_code(chain: str) -> int:
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
        chains.append(f"L S+ D (any objects; safety cap {MAX_SPECULAR_EVENTS} events, "
                      "cut flux recorded)")
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
    """

    total: list
    caustic: list
    photons: int
    emitted: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    cut: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    casts: int = 0


def _lane_rng(n: int, key: int):
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
    """

    def __init__(self, scene: Scene, *, geometry: SceneGeometry | None = None,
                 resolution: tuple[int, int] | None = None,
                 extents: list | None = None, caustic_only: bool = False,
                 shading_correction: bool = True) -> None:
        _, _, variant = _mi.load()
        if not variant.startswith(("llvm", "cuda")):
            raise _mi.MitsubaError(
                f"the photon tracer needs a vectorised Mitsuba variant, got {variant}"
            )
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
        self.exported: dict = {
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
        chains = [_chain_code(event_chain(o)) if event_chain(o) else -1 for o in scene.objects]
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
        """Trace ``photons`` photons (rounded up to whole batches) per channel pass.

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
        batch = max(1, min(batch, photons))
        launches = -(-photons // batch)
        emitted, cut, casts = np.zeros(3), np.zeros(3), 0
        for c in self.channels:
            for launch in range(launches):
                key = ((seed * 1_000_003 + stream) * 7 + (0 if c is None else c + 1)) \
                    * 1_000_003 + launch
                flux = self._launch(batch, key, c, total, caustic)
                dr.eval(total, caustic)
                emitted += flux[0]
                cut += flux[1]
                casts += flux[2]
        shape = (h, w, 3)
        return PhotonSums(
            total=None if total is None
            else [np.asarray(t, dtype=np.float64).reshape(shape) for t in total],
            caustic=[np.asarray(t, dtype=np.float64).reshape(shape) for t in caustic],
            photons=launches * batch, emitted=emitted, cut=cut, casts=casts,
        )

    def _launch(self, n: int, key: int, channel, total, caustic) -> tuple[np.ndarray, ...]:
        """Trace one batch; returns the (emitted, cut) weight sums (RGB) and the ray
        casts (see PhotonSums)."""
        mi, _, _ = _mi.load()
        rng = _lane_rng(n, key)
        square = stratified_square(rng, n)
        ray, weight = sample_photons(self.scene.light, self.targets, rng,
                                     self.scene_center, self.scene_radius, square=square)
        weight *= mi.Color3f(*map(float, channel_mask(channel)))
        exported = self.exported[channel]
        if self.direct_unshadowed:
            si = self.receivers_only.scene.ray_intersect(ray)
            self._deposit(si, ray.d, weight, si.is_valid(),
                          receiver_ids=self.receivers_only.receiver_ids, total=total, caustic=None)
        # Only all-paths mode has a path limit to account for; chain mode cuts nothing.
        emitted = _rgb_sum(weight, n) if self.all_paths else np.zeros(3)
        cut, casts = self._trace_chain(exported, ray, weight, rng=rng, channel=channel,
                                       total=total,
                                caustic=caustic, lanes=n)
        return emitted, cut, casts

    def _trace_chain(self, exported: ExportedScene, ray, weight, *, rng, channel,
                     total, caustic, lanes: int) -> tuple[np.ndarray, int]:
        """Follow the photons through their specular events, depositing the counted
        ones; returns the weight sum (RGB) of paths the safety cap stopped and the
        number of ray casts traced (lanes x events, the tracer's work).

        The first events are unrolled in Python (chain mode needs the event codes
        of each depth). In all-paths mode, the few paths still alive after
        :data:`_TAIL_FROM` events are compacted and followed in one Dr.Jit
        symbolic loop up to the cap, so long chains of total internal reflection
        cost only the ray casts they make.
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
        for depth in range(head + 1):
            cast += dr.select(active, 1, 0)
            si, hit, weight = self._arrive(exported, ray, weight, sigma, active)
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
                self._deposit(si, ray.d, weight, hit & ok, receiver_ids=exported.receiver_ids,
                              total=total, caustic=caustic if depth > 0 else None)
            if depth == self.max_events and not self.all_paths:
                dr.eval(cast, total, caustic)
                return np.zeros(3), _total(cast, lanes)  # every chain ends here
            event = self._event(exported, si, ray=ray, weight=weight, sigma=sigma, rng=rng,
                                hit=hit, channel=channel)
            sid = dr.reinterpret_array(mi.UInt32, si.shape)
            first = dr.select(depth == 0, sid, first)
            mixed |= sid != first
            code = code * 3 + dr.select(event.reflected, mi.UInt32(_R), mi.UInt32(_T))
            ray, weight, sigma, active = event.ray, event.weight, event.sigma, event.going_on
            if depth == self.max_events:
                # Paths that would go on: the cap cuts them, and their flux is what
                # the cap loses.
                alive = dr.select(active, weight, 0.0)
                dr.eval(alive, cast, total, caustic)  # one kernel for the whole path
                return _rgb_sum(alive, lanes), _total(cast, lanes)
        # Wavefront compaction: keep only the paths still alive. The state is
        # evaluated in one kernel first: each gather from an unevaluated array would
        # otherwise re-run every event so far in a kernel of its own.
        dr.eval(ray, weight, rng, sigma, active, cast, total, caustic)
        casts = _total(cast, lanes)
        idx = dr.compress(active)
        lanes = dr.width(idx)
        if lanes == 0:
            return np.zeros(3), casts
        ray, weight, rng, sigma = (dr.gather(type(x), x, idx) for x in (ray, weight, rng, sigma))
        ray, weight, sigma, active, casts_tail = self._tail(
            exported, ray, weight, sigma, rng, channel=channel, total=total, caustic=caustic,
            lanes=lanes)
        return _rgb_sum(dr.select(active, weight, 0.0), lanes), casts + casts_tail

    def _tail(self, exported: ExportedScene, ray, weight, sigma, rng, *, channel, total,
              caustic, lanes: int):
        """Events ``_TAIL_FROM + 1`` .. cap of the surviving paths in one symbolic loop
        (all-paths mode: every receiver hit counts); returns the state after the
        cap's event and the ray casts made."""
        mi, dr, _ = _mi.load()

        def step(*state):
            ray, weight, sigma, rng, active, depth, casts = state
            si, hit, weight = self._arrive(exported, ray, weight, sigma, active)
            self._deposit(si, ray.d, weight, hit, receiver_ids=exported.receiver_ids,
                          total=total, caustic=caustic)
            event = self._event(exported, si, ray=ray, weight=weight, sigma=sigma, rng=rng,
                                hit=hit, channel=channel)
            # Lanes that stopped keep their state (the loop masks them out).
            return (event.ray, event.weight, event.sigma, rng, event.going_on, depth + 1,
                    casts + 1)

        state = (ray, weight, sigma, rng, dr.full(mi.Bool, True, lanes),
                 dr.full(mi.UInt32, _TAIL_FROM + 1, lanes), dr.zeros(mi.UInt32, lanes))
        ray, weight, sigma, rng, active, _, casts = dr.while_loop(
            state=state,
            cond=lambda *state: state[4] & (state[5] <= self.max_events),
            body=step,
            labels=("ray", "weight", "sigma", "rng", "active", "depth", "casts"),
            label="photon_tail",
        )
        dr.eval(ray, weight, active, casts, total, caustic)
        return ray, weight, sigma, active, _total(casts, lanes)

    def _arrive(self, exported: ExportedScene, ray, weight, sigma, active):
        """Cast ``ray`` for the ``active`` lanes; attenuate by Beer-Lambert over the
        segment (``sigma`` of the medium travelled, 1/m). Returns (si, hit, weight)."""
        _, dr, _ = _mi.load()
        si = exported.scene.ray_intersect(ray, active)
        hit = active & si.is_valid()
        weight = weight * dr.exp(-sigma * dr.select(hit, si.t, 0.0))
        return si, hit, weight

    def _event(self, exported: ExportedScene, si, *, ray, weight, sigma, rng, hit, channel):
        """The specular event at ``si`` (:func:`.specular.specular_event`)."""
        return specular_event(si, ray, weight, sigma, rng, hit=hit,
                              object_ids=exported.object_ids, objects=self.geometry.objects,
                              channel=channel, all_paths=self.all_paths,
                              shading_correction=self.shading_correction)

    def _deposit(self, si, d, weight, mask, *, receiver_ids, total, caustic) -> None:
        """scatter_reduce the photons of ``mask`` into the texel their (u, v) falls in."""
        mi, dr, _ = _mi.load()
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
