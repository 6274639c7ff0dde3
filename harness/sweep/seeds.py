"""The Mitsuba reference as Dask tasks: one task per seed, one merge.

A single-process reference (:func:`renderers.mitsuba.reference.estimate_receivers`)
traces its K seeds in rounds of at most 2^20 photons per seed; after each round it
forms every seed's estimate (its sum over the rounds so far / photons so far), the
mean over seeds and the variance of the mean (:func:`.noise.seed_statistics`), and
stops once the relative noise in the caustic region is at most ``target_noise``, or
at the budget. Seed k draws from PCG32 streams keyed by (seed k, round), so what a
seed traces does not depend on the others.

Here each seed is a task (:func:`trace_seed`): it traces that seed's whole budget
in the same rounds and returns the per-round sums. The merge
(:func:`merge_reference`) replays the rounds in order with the same arithmetic
(float64 sums, the same noise and stopping rule) and so produces the estimate a
single process would have produced with the same seeds: the same maps up to the
order of the float32 atomic additions inside Dr.Jit's parallel scatter (which
differs between any two runs, in one process too), the same photon count, noise
history and stop. Rounds after the stop are traced but not used (seeds run in
parallel, so the stop is known only at the merge); the result records how many
rounds it used of how many traced.

The camera image is traced by the merge, after the replay: the camera tracer's
caustic lookup maps take their photon count from the photons the receiver maps
used (:func:`renderers.mitsuba.camera_trace.render_traced_camera`, called exactly
as ``render_reference`` calls it), and only the replay knows that count. So the
camera is not parallel over seeds; it is the same image a single process makes.

The merged result is a :class:`renderers.results.RenderResult` with the same
metadata as ``render_reference`` writes, so the client stores it in the reference
cache under the same key: a later ``caustics compare`` of that scene finds it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from harness.sweep.worker import worker_name
from renderers.mitsuba import mitsuba_versions
from renderers.mitsuba.camera_trace import render_traced_camera
from renderers.mitsuba.noise import caustic_region, relative_noise, seed_statistics
from renderers.mitsuba.photons import (
    DEFAULT_BATCH,
    PhotonTracer,
)
from renderers.mitsuba.reference import TIMER, cut_fraction, reference_metadata
from renderers.results import ReceiverMap, RenderResult
from scenes import Scene, effects_of
from scenes.errors import HarnessError
from scenes.geometry import build_geometry

__all__ = ["MergeError", "SeedBatch", "merge_reference", "trace_seed"]


class MergeError(HarnessError):
    """Seed batches that cannot be one reference (missing seeds, other versions)."""


@dataclass(frozen=True, eq=False)
class SeedBatch:
    """One seed of a reference, traced by one task.

    Attributes
    ----------
    index : int
        Position among the reference's K seeds (0 .. K-1); the seed is
        ``settings.seed + index``.
    seed : int
        The seed.
    rounds : tuple of tuple of ndarray
        Per round, per receiver: the unnormalised caustic sums (float64, (H, W, 3),
        W/m² × photons) of that round's photons.
    photons : tuple of int
        Photons traced per round (per channel pass).
    emitted, cut : tuple of ndarray
        Per round, the emitted and the cut-off flux (RGB, W × photons; zero in
        chain mode): :class:`renderers.mitsuba.photons.PhotonSums`.
    seconds : tuple of float
        Seconds of tracing up to the end of each round (``time.perf_counter``,
        JIT compilation included).
    extents : tuple of tuple of float
        Each receiver's (u, v) extent.
    channel_passes : int
        Photon-tracer passes per photon: 1, or 3 with dispersion.
    worker : str
        The Dask worker that traced it.
    versions : dict
        Mitsuba and Dr.Jit versions and the variant on that worker.
    """

    index: int
    seed: int
    rounds: tuple[tuple[np.ndarray, ...], ...]
    photons: tuple[int, ...]
    emitted: tuple[np.ndarray, ...]
    cut: tuple[np.ndarray, ...]
    seconds: tuple[float, ...]
    extents: tuple[tuple[float, float, float, float], ...]
    channel_passes: int
    worker: str
    versions: dict


def trace_seed(scene: Scene, index: int, *, batch: int = DEFAULT_BATCH) -> SeedBatch:
    """Trace seed ``scene.settings.seed + index`` of the reference: its whole photon
    budget in rounds of ``batch`` (as :func:`~renderers.mitsuba.reference.estimate_receivers`
    does), caustic maps only. A Dask task."""
    s = scene.settings
    seed = s.seed + index
    geometry = build_geometry(scene)
    start = time.perf_counter()
    tracer = PhotonTracer(scene, geometry=geometry, caustic_only=True)
    per_round = max(1, min(batch, s.photons))
    rounds, photons, emitted, cut, seconds = [], [], [], [], []
    traced = stream = 0
    while traced < s.photons:
        n = min(per_round, s.photons - traced)
        sums = tracer.trace(n, seed=seed, stream=stream, batch=per_round)
        rounds.append(tuple(sums.caustic))
        photons.append(int(sums.photons))
        emitted.append(np.asarray(sums.emitted, np.float64))
        cut.append(np.asarray(sums.cut, np.float64))
        seconds.append(time.perf_counter() - start)
        traced += sums.photons
        stream += 1
    return SeedBatch(index=index, seed=seed, rounds=tuple(rounds), photons=tuple(photons),
                     emitted=tuple(emitted), cut=tuple(cut), seconds=tuple(seconds),
                     extents=tuple(tuple(e) for e in tracer.extents),
                     channel_passes=len(tracer.channels), worker=worker_name(),
                     versions=mitsuba_versions())


def _check(batches: list[SeedBatch], scene: Scene, versions: dict) -> None:
    s = scene.settings
    indices = [b.index for b in batches]
    if indices != list(range(s.seeds)):
        raise MergeError(f"{scene.name}: seed batches {indices} are not the seeds "
                         f"0..{s.seeds - 1} of the reference")
    for b in batches:
        if b.versions != versions:
            raise MergeError(f"{scene.name}: seed {b.seed} was traced on {b.worker} with "
                             f"{b.versions}, the sweep keys its cache by {versions}: install "
                             "the same Mitsuba and Dr.Jit on every worker and the client")
        if b.photons != batches[0].photons or len(b.rounds) != len(batches[0].rounds):
            raise MergeError(f"{scene.name}: seed {b.seed} traced other rounds than seed "
                             f"{batches[0].seed}")


def _replay(batches: list[SeedBatch], target: float):
    """The rounds of a single-process reference, replayed from the seed batches:
    ``(caustic maps, photons, noise, stopped_by, history, rounds used, emitted, cut)``."""
    k, n_rec = len(batches), len(batches[0].extents)
    sums = [[0.0] * n_rec for _ in range(k)]
    traced, history, noise, stopped = 0, [], float("nan"), "budget"
    emitted, cut = np.zeros(3), np.zeros(3)
    caustic: list[ReceiverMap] = []
    used = 0
    for j in range(len(batches[0].rounds)):
        for i in range(k):
            for r in range(n_rec):
                sums[i][r] = sums[i][r] + batches[i].rounds[j][r]
        traced += batches[0].photons[j]
        # As estimate_receivers: the flux counters of the round's last seed.
        emitted += batches[-1].emitted[j]
        cut += batches[-1].cut[j]
        used = j + 1
        noises, caustic = [], []
        for r in range(n_rec):
            mean, var = seed_statistics(np.stack([c[r] for c in sums]) / traced)
            noises.append(relative_noise(mean, var, caustic_region(mean)))
            caustic.append(ReceiverMap(mean.astype(np.float32), batches[0].extents[r],
                                       var.astype(np.float32)))
        finite = [x for x in noises if np.isfinite(x)]
        noise = max(finite) if finite else float("nan")
        # Seeds ran in parallel: the round ended when its slowest seed's did.
        history.append((traced, noise, max(b.seconds[j] for b in batches)))
        if np.isfinite(noise) and noise <= target:
            stopped = "target_noise"
            break
    return caustic, traced, noise, stopped, history, used, emitted, cut


def merge_reference(scene: Scene, key: str, versions: dict,
                    *batches: SeedBatch) -> RenderResult:
    """The reference of ``scene`` from its K seed batches (see the module docstring);
    its metadata as ``render_reference`` writes it, ``hash`` = ``key``. A Dask task.

    Raises
    ------
    MergeError
        The batches are not seeds 0..K-1 of this reference, traced the same rounds,
        under ``versions`` (the versions the cache key was computed with).
    """
    s = scene.settings
    batches = sorted(batches, key=lambda b: b.index)
    _check(batches, scene, versions)
    start = time.perf_counter()
    caustic, traced, noise, stopped, history, used, emitted, cut = _replay(
        batches, s.target_noise)
    merged = time.perf_counter() - start
    traced_camera = render_traced_camera(scene, photons=traced)
    metadata = reference_metadata(
        scene, key=key, versions=versions, photons=traced,
        channel_passes=batches[0].channel_passes, relative_noise=noise, stopped_by=stopped,
        history=history, cut_fraction=cut_fraction(emitted, cut),
        camera_cut=traced_camera.cut_fraction, camera_variance=traced_camera.variance,
        lookup=traced_camera.plan)
    metadata["cache"] = f"miss (merged from {len(batches)} seed tasks)"
    metadata["sweep"] = {"seed_tasks": len(batches), "rounds_traced": len(batches[0].rounds),
                         "rounds_used": used, "workers": sorted({b.worker for b in batches}),
                         "merged_by": worker_name()}
    timings = {"receiver_maps": history[-1][2] if history else 0.0,
               "camera_lookup_maps": traced_camera.seconds["lookup_maps"],
               "camera": traced_camera.seconds["camera"],
               "merge": merged}
    return RenderResult(
        renderer="mitsuba", camera=traced_camera.image.astype(np.float32),
        receivers=tuple(caustic),
        effects=effects_of(scene), timings=timings,
        timer=f"{TIMER}; seeds traced in parallel, one task each: the slowest seed's; "
              "the camera traced by the merge",
        metadata=metadata)
