"""The reference camera image: camera rays through the specular chains, on Mitsuba.

ptracer (:mod:`.camera`) renders specular objects seen directly black, and all
that is seen only through them. This tracer instead follows each camera ray,
with Dr.Jit on Mitsuba's ray tracing, through the specular events the photon
tracer counts (:mod:`.photons`) to its first diffuse hit, and shades that hit
with the light's analytic direct irradiance and the photon tracer's caustic
irradiance (:mod:`.camera_shading` has the maths of both).

Pixels. Each pixel takes ``spp`` subpixel samples: with s = floor(sqrt(spp)), the
first s^2 are jittered in the cells of an s x s grid over the pixel, the rest
uniform in it. The scene's sensor (:func:`.exporter.sensor_dict`) has a **box
filter** of one pixel and no border samples, so each sample counts for its own
pixel only, with weight one: the pixel value is the mean of its samples.

Chains, the photon tracer's rules read from the camera's side (T T, T and R are
their own reverses): a ray that hits a specular object follows it through at most
as many events as the longest counted chain; at a diffuse surface it is shaded if
it arrived directly (no event) or after exactly the chain of the object it first
hit (``L T T D`` through a closed dielectric, ``L T D`` a water surface,
``L R D`` a conductor), all events on that one object; otherwise it is black.
With ``settings.all_specular_paths`` every chain of 1 to MAX_SPECULAR_EVENTS
events counts; a ray still scattering at the cap is stopped, and the fraction of
samples so stopped is recorded (``camera_cut_fraction``). Rays that leave the
scene see nothing: radiance 0. Dispersion: one pass per channel with that
channel's IOR and light (:func:`.exporter.export_scene`'s ``channel``).

Caustic lookup maps: their resolution follows the camera's footprint on each
receiver, measured here (:meth:`CameraTracer.footprints`); the rule, the photons
it takes and the lookups are in :mod:`.camera_lookup`.

Noise: K = ``settings.seeds`` independent seeds; each seed has its own subpixel
jitter, its own light samples and its **own caustic lookup maps**, traced with
that seed, so the per-pixel variance of the mean (:func:`.noise.seed_statistics`)
includes the maps' noise.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from tqdm import tqdm

from renderers.mitsuba import _mi
from renderers.mitsuba.camera import MAX_SPECULAR_EVENTS
from renderers.mitsuba.camera_lookup import (
    FOOTPRINT_PERCENTILE,
    LOOKUP_CAP,
    LookupMaps,
    LookupPlan,
    plan_lookup,
)
from renderers.mitsuba.camera_shading import camera_event, receiver_radiance
from renderers.mitsuba.exporter import channel_mask, export_scene
from renderers.mitsuba.noise import seed_statistics
from renderers.mitsuba.photons import PhotonTracer, chain_code, lane_rng
from scenes import effects_of, event_chain
from scenes.geometry import SceneGeometry, build_geometry
from scenes.model import DiffuseMaterial, Scene

__all__ = ["CameraTracer", "ChainEnd", "TracedCamera", "camera_trace_limits",
           "render_traced_camera"]

#: Camera samples per kernel launch (about 300 B of state each).
BATCH_LANES = 1 << 20
#: Photon-tracer stream of the lookup maps (the receiver maps use streams 0, 1, ...).
LOOKUP_STREAM = 1 << 20
#: Stream that keys the camera samples' random numbers.
CAMERA_STREAM = 1 << 21


def camera_trace_limits(plan: LookupPlan) -> tuple[str, ...]:
    """What the camera tracer does not simulate, for the result's metadata."""
    w, h = plan.resolution
    lookup = (f"caustic irradiance looked up bilinearly in photon-traced maps of {w}x{h} "
              "texels per receiver")
    if plan.capped:
        lookup += (f" (capped at {LOOKUP_CAP}: coarser than the camera footprint of "
                   f"{100 - FOOTPRINT_PERCENTILE:.0f} % of the pixels)")
    return (
        lookup,
        "only the counted specular chains are followed from the camera: in chain mode "
        "a dielectric's reflection (the sky or floor mirrored in the glass) is not seen",
        "no diffuse interreflection: receivers are lit by direct light and the counted "
        "caustic chains only",
        "diffuse objects get direct light only (no caustic map on them)",
        "pinhole camera, box pixel filter",
    )


@dataclass(frozen=True, eq=False)
class ChainEnd:
    """Where a batch of camera rays ended (Dr.Jit arrays, per lane).

    Attributes
    ----------
    si : mi.SurfaceInteraction3f
        The first diffuse hit reached by a counted chain (meaningless off ``ended``).
    d : mi.Vector3f
        The ray's unit direction arriving there.
    weight : mi.Color3f
        Radiance weight of the chain (Fresnel, reflectance, eta^2, Beer-Lambert).
    ended : mi.Bool
        The lane reached a diffuse surface by a counted chain.
    cut : mi.Bool
        The event cap stopped the lane (all-paths mode only).
    chain : mi.UInt32
        The events on the way, as the digits of a bijective base-3 number (1 a
        transmission, 2 a reflection; 0: none): equal for lanes that took the same
        chain (it wraps around past 20 events, in all-paths mode).
    """

    si: object
    d: object
    weight: object
    ended: object
    cut: object
    chain: object


@dataclass(frozen=True, eq=False)
class TracedCamera:
    """The K-seed camera image of :func:`render_traced_camera`.

    Attributes
    ----------
    image, variance : ndarray, (H, W, 3), float64
        Mean radiance (W m^-2 sr^-1, row 0 at the top) and its variance of the mean.
    plan : LookupPlan
    cut_fraction : float
        Fraction of camera samples the event cap stopped (all-paths mode; else 0).
    seconds : dict
        ``lookup_maps`` and ``camera`` tracing times (s, wall clock).
    """

    image: np.ndarray
    variance: np.ndarray
    plan: LookupPlan
    cut_fraction: float
    seconds: dict


class CameraTracer:
    """A scene prepared for camera tracing (exported once per channel pass)."""

    def __init__(self, scene: Scene, *, geometry: SceneGeometry | None = None) -> None:
        _, _, variant = _mi.load()
        if not variant.startswith(("llvm", "cuda")):
            raise _mi.MitsubaError(f"the camera tracer needs a vectorised Mitsuba variant, "
                                   f"got {variant}")
        self.scene = scene
        self.geometry = geometry or build_geometry(scene)
        effects = effects_of(scene)
        self.channels = [0, 1, 2] if "dispersion" in effects else [None]
        self.exported = {c: export_scene(scene, geometry=self.geometry, channel=c)
                         for c in self.channels}
        self.shadows = "shadows" in effects
        self.occluders = None if self.shadows else export_scene(
            scene, geometry=self.geometry, include_objects=False).scene
        self.all_paths = scene.settings.all_specular_paths
        chains = [event_chain(o) for o in scene.objects]
        self.chain_codes = [chain_code(c) if c else -1 for c in chains]
        lengths = [len(c.split()) - 2 for c in chains if c]
        self.max_events = MAX_SPECULAR_EVENTS if self.all_paths else max(lengths or [0])
        self.diffuse_objects = [isinstance(o.material, DiffuseMaterial) for o in scene.objects]

    # ------------------------------------------------------------------ tracing
    def _trace(self, channel, ray, rng) -> ChainEnd:
        """Follow ``ray`` through its chain to the first diffuse hit (see the module
        docstring) and return where each lane ended."""
        mi, dr, _ = _mi.load()
        ex = self.exported[channel]
        n = dr.width(ray.o)
        diffuse_ids = list(ex.receiver_ids) + [
            oid for oid, diffuse in zip(ex.object_ids, self.diffuse_objects, strict=True)
            if diffuse]

        def step(*state):
            (ray, weight, sigma, rng, active, depth, first, mixed, code, cut,
             end_si, end_d, end_weight, ended, end_chain) = state
            si = ex.scene.ray_intersect(ray, active)
            hit = active & si.is_valid()
            weight = weight * dr.exp(-sigma * dr.select(hit, si.t, 0.0))  # Beer-Lambert
            sid = dr.reinterpret_array(mi.UInt32, si.shape)
            diffuse = mi.Bool(False)
            for i in diffuse_ids:
                diffuse |= sid == i
            counted = depth == 0
            if self.all_paths:
                counted = mi.Bool(True)
            else:
                for oid, chain in zip(ex.object_ids, self.chain_codes, strict=True):
                    if chain > 0:
                        counted |= ~mixed & (first == oid) & (code == chain)
            now = hit & diffuse & counted
            end_si = dr.select(now, si, end_si)
            end_d = dr.select(now, ray.d, end_d)
            end_weight = dr.select(now, weight, end_weight)
            end_chain = dr.select(now, code, end_chain)
            ended |= now
            specular = hit & ~diffuse
            if self.all_paths:
                cut |= specular & (depth >= self.max_events)
            scatter = specular & (depth < self.max_events)
            event = camera_event(si, ray, weight, sigma, hit=scatter, object_ids=ex.object_ids,
                                 objects=self.geometry.objects, channel=channel,
                                 all_paths=self.all_paths, u=rng.next_float32())
            first = dr.select(depth == 0, sid, first)
            mixed |= sid != first
            code = code * 3 + dr.select(event.reflected, mi.UInt32(2), mi.UInt32(1))
            return (event.ray, event.weight, event.sigma, rng, scatter & event.going_on,
                    depth + 1, first, mixed, code, cut, end_si, end_d, end_weight, ended,
                    end_chain)

        state = (ray, dr.full(mi.Color3f, 1.0, n), dr.zeros(mi.Color3f, n), rng,
                 dr.full(mi.Bool, True, n), dr.zeros(mi.UInt32, n), dr.zeros(mi.UInt32, n),
                 dr.zeros(mi.Bool, n), dr.zeros(mi.UInt32, n), dr.zeros(mi.Bool, n),
                 dr.zeros(mi.SurfaceInteraction3f, n), dr.zeros(mi.Vector3f, n),
                 dr.zeros(mi.Color3f, n), dr.zeros(mi.Bool, n), dr.zeros(mi.UInt32, n))
        if self.all_paths:
            # Long chains (TIR loops) in one symbolic loop: one copy of the body.
            state = dr.while_loop(state=state, cond=lambda *s: s[4], body=step,
                                  label="camera_chain")
        else:
            for _ in range(self.max_events + 1):  # chains of at most two events
                state = step(*state)
        return ChainEnd(si=state[10], d=state[11], weight=state[12], ended=state[13],
                        cut=state[9], chain=state[14])

    def _rays(self, channel, x, y, offset):
        """Camera rays (the scene sensor's) through film positions ((x, y) + offset) /
        (W, H): pixel (x, y), row 0 at the top, ``offset`` in pixels."""
        mi, _, _ = _mi.load()
        w, h = self.scene.camera.resolution
        sensor = self.exported[channel].scene.sensors()[0]
        film = mi.Point2f((mi.Float(x) + offset[0]) / w, (mi.Float(y) + offset[1]) / h)
        ray, _ = sensor.sample_ray(0.0, 0.5, film, mi.Point2f(0.5))
        return ray

    def render(self, *, spp: int, seed: int, lookup: LookupMaps | None
               ) -> tuple[np.ndarray, int, int]:
        """One seed of the camera image.

        Parameters
        ----------
        spp : int
            Samples per pixel (stratified as the module docstring says).
        seed : int
            Keys the samples' random numbers (jitter, light samples, Fresnel choices).
        lookup : LookupMaps or None
            This seed's caustic maps, one per receiver; None: no caustic term.

        Returns
        -------
        image : ndarray, (H, W, 3), float64
            Radiance, W m^-2 sr^-1, row 0 at the top.
        samples, cut : int
            Camera samples traced, and how many the event cap stopped (summed over
            the channel passes).
        """
        mi, dr, _ = _mi.load()
        w, h = self.scene.camera.resolution
        rows = max(1, min(h, BATCH_LANES // (w * spp)))
        side = math.isqrt(spp)
        image = np.zeros((h, w, 3))
        samples = cut_total = 0
        direct = self.scene.info.direct_lighting
        for c in self.channels:
            ex = self.exported[c]
            occluders = ex.scene if self.shadows else self.occluders
            mask = mi.Color3f(*map(float, channel_mask(c)))
            for batch, row0 in enumerate(range(0, h, rows)):
                n = min(rows, h - row0) * w * spp
                key = ((seed * 1_000_003 + CAMERA_STREAM) * 7 + (0 if c is None else c + 1)) \
                    * 1_000_003 + batch
                rng = lane_rng(n, key)
                lane = dr.arange(mi.UInt32, n)
                pixel, j = lane // spp, lane % spp
                x = pixel % w
                y = pixel // w + dr.opaque(mi.UInt32, row0)
                # Stratum (j mod s, j div s) of the s x s grid, jittered; the rest uniform.
                ju, jv = rng.next_float32(), rng.next_float32()
                strat = j < side * side
                offset = (dr.select(strat, (mi.Float(j % side) + ju) / side, ju),
                          dr.select(strat, (mi.Float(j // side) + jv) / side, jv))
                end = self._trace(c, self._rays(c, x, y, offset), rng)
                lit = receiver_radiance(
                    end.si, end.d, end.ended, exported=ex, occluders=occluders,
                    receivers=self.geometry.receivers, objects=self.geometry.objects,
                    lookup=lookup, direct=direct,
                    light_sample=mi.Point2f(rng.next_float32(), rng.next_float32()))
                radiance = end.weight * lit * mask
                sums = [dr.block_sum(radiance[k], spp) for k in range(3)]
                cut_count = dr.sum(mi.UInt32(dr.select(end.cut, 1, 0)))
                dr.eval(sums, cut_count)
                block = np.stack([np.asarray(s, dtype=np.float64) for s in sums], axis=-1)
                image[row0:row0 + n // (w * spp)] += block.reshape(-1, w, 3) / spp
                samples += n
                cut_total += int(cut_count[0])
        return image, samples, cut_total

    # --------------------------------------------------------------- footprint
    def footprints(self) -> list[np.ndarray]:
        """Per receiver, the footprint length sqrt|det J| (receiver units per pixel) of
        each pixel (module docstring): an (H - 1, W - 1) array, NaN where the ray
        through the pixel's centre and those through its right and lower neighbours'
        do not all reach this receiver by the same chain."""
        mi, dr, _ = _mi.load()
        w, h = self.scene.camera.resolution
        c = self.channels[0]
        ex = self.exported[c]
        lane = dr.arange(mi.UInt32, w * h)
        ray = self._rays(c, lane % w, lane // w, (0.5, 0.5))
        end = self._trace(c, ray, lane_rng(w * h, CAMERA_STREAM))
        u, v = end.si.uv.x, end.si.uv.y
        sid = dr.select(end.ended, dr.reinterpret_array(mi.UInt32, end.si.shape), 0)
        dr.eval(u, v, sid, end.chain)
        u, v = (np.asarray(a, dtype=np.float64).reshape(h, w) for a in (u, v))
        sid = np.asarray(sid).reshape(h, w)
        chain = np.asarray(end.chain).reshape(h, w)
        here, right, below = (slice(None, -1), slice(None, -1)), \
            (slice(None, -1), slice(1, None)), (slice(1, None), slice(None, -1))
        du_x, dv_x = u[right] - u[here], v[right] - v[here]
        du_y, dv_y = u[below] - u[here], v[below] - v[here]
        length = np.sqrt(np.abs(du_x * dv_y - dv_x * du_y))
        same = (chain[right] == chain[here]) & (chain[below] == chain[here])
        out = []
        for rid in ex.receiver_ids:
            ok = same & (sid[here] == rid) & (sid[right] == rid) & (sid[below] == rid)
            out.append(np.where(ok, length, np.nan))
        return out

    def lookup_plan(self, photons: int) -> LookupPlan:
        """The lookup maps' resolution and photons per seed for this camera
        (:func:`.camera_lookup.plan_lookup`); ``photons``: the receiver maps' per seed."""
        return plan_lookup(self.footprints(), [r.extent for r in self.geometry.receivers],
                           receiver_map=self.scene.settings.receiver_map, photons=photons)


def render_traced_camera(scene: Scene, *, photons: int, spp: int | None = None,
                         seeds: int | None = None, seed: int | None = None,
                         geometry: SceneGeometry | None = None,
                         progress: bool = False) -> TracedCamera:
    """The camera image over K seeds, each with its own caustic lookup maps.

    Parameters
    ----------
    photons : int
        Photons per seed of the reference's receiver maps (at
        ``settings.receiver_map``); the lookup maps get this times the footprint
        ratio (:func:`.camera_lookup.plan_lookup`).
    spp, seeds, seed
        Default ``scene.settings``: samples per pixel per seed, K, the first seed.
    progress
        A tqdm bar over the seeds (stderr).
    """
    s = scene.settings
    spp, k = spp or s.spp, seeds or s.seeds
    first = s.seed if seed is None else seed
    tracer = CameraTracer(scene, geometry=geometry)
    plan = tracer.lookup_plan(photons)
    chains = any(event_chain(o) for o in scene.objects)
    photon_tracer = (PhotonTracer(scene, geometry=tracer.geometry, resolution=plan.resolution,
                                  caustic_only=True) if chains else None)
    seconds = {"lookup_maps": 0.0, "camera": 0.0}
    frames, samples, cut = [], 0, 0
    iterator = range(first, first + k)
    if progress:
        iterator = tqdm(iterator, desc=f"camera trace ({spp} spp per seed)", unit="seed",
                        leave=False)
    for i in iterator:
        start = time.perf_counter()
        lookup = None
        if photon_tracer is not None:
            sums = photon_tracer.trace(plan.photons, seed=i, stream=LOOKUP_STREAM)
            lookup = LookupMaps.from_arrays([m / sums.photons for m in sums.caustic],
                                            photon_tracer.extents)
        seconds["lookup_maps"] += time.perf_counter() - start
        start = time.perf_counter()
        image, n, stopped = tracer.render(spp=spp, seed=i, lookup=lookup)
        seconds["camera"] += time.perf_counter() - start
        frames.append(image)
        samples, cut = samples + n, cut + stopped
    mean, variance = seed_statistics(np.stack(frames))
    return TracedCamera(image=mean, variance=variance, plan=plan,
                        cut_fraction=cut / samples if samples else 0.0, seconds=seconds)
