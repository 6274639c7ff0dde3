"""The Mitsuba reference as Dask tasks: one task per seed, one merge.

A single-process reference (:func:`renderers.mitsuba.reference.estimate_receivers`)
traces its K seeds in rounds of one launch per seed: the launches of
:func:`renderers.mitsuba.photons.launch_plan` for the starting budget (whole launches
of 2^20 photons and one smaller remainder, each stratified at its own size), then
whole launches while the noise target looks reachable within
``reference_time_cap``. Seed k's launch of round j draws from the PCG32 streams keyed
by (seed k, j), so what a seed traces does not depend on the others. The rounds'
bookkeeping (every seed's estimate, the mean over seeds and its variance, the
per-channel noise over the caustic region, the stop rule, the metadata) is
:class:`renderers.mitsuba.reference.ReceiverRounds`.

Here each seed is a task (:func:`trace_seed`): it traces that seed's launches of the
starting budget, exactly as the single process does (same streams, same lanes), and
returns each launch's sums. The merge (:func:`merge_reference`) adds them round by
round to a :class:`~renderers.mitsuba.reference.ReceiverRounds`; if the stop rule
goes on past the budget, the merge itself traces the further whole launches of
every seed (same seeds, same streams, seed after seed, as the single process). So
it produces the estimate a single process would have produced with the same seeds:
the same maps up to the order of the float32 atomic additions inside Dr.Jit's
parallel scatter (which differs between any two runs, in one process too), the same
photon count, noise and stop, wherever the stop rule does not hinge on timing
(elapsed time, see :func:`merge_reference`). Budget launches after a stop by the
target are traced but not used (seeds run in parallel, so the stop is known only at
the merge); the result records how many rounds it used of how many traced.

The merge then makes the reference from the rounds' estimate exactly as
``render_reference`` does (:func:`renderers.mitsuba.reference.reference_result`):
the camera image, whose caustic lookup maps take their photon count from the
photons the receiver maps used (only the merge knows that count, so the camera is
not parallel over seeds; it is the same image a single process makes), and the same
metadata. The client stores it in the reference cache under the same key
(:func:`renderers.mitsuba.reference.cached_reference`): a later ``caustics compare``
of that scene finds it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from harness.sweep.worker import worker_name
from renderers.mitsuba import mitsuba_versions
from renderers.mitsuba.photons import DEFAULT_BATCH, PhotonTracer, launch_plan
from renderers.mitsuba.reference import TIMER, ReceiverRounds, reference_result
from renderers.results import RenderResult
from scenes import Scene
from scenes.errors import HarnessError
from scenes.geometry import build_geometry

__all__ = ["MergeError", "SeedBatch", "merge_reference", "trace_seed"]


class MergeError(HarnessError):
    """Seed batches that cannot be one reference (missing seeds, other versions)."""


@dataclass(frozen=True, eq=False)
class SeedBatch:
    """One seed of a reference, traced by one task: its launches of the starting budget.

    Attributes
    ----------
    index : int
        Position among the reference's K seeds (0 .. K-1); the seed is
        ``settings.seed + index``.
    seed : int
        The seed.
    batch : int
        Lanes of a whole launch: the launches are ``launch_plan(settings.photons, batch)``.
    caustic : tuple of tuple of ndarray
        Per launch (= round, PCG32 stream), per receiver: the unnormalised caustic sums
        (float64, (H, W, 3), W/m² × photons) of that launch's photons.
    photons : tuple of int
        Photons of each launch (per channel pass).
    emitted, cut : tuple of ndarray
        Per launch, the emitted and the cut-off flux (RGB, W × photons; zero in
        chain mode): :class:`renderers.mitsuba.photons.PhotonSums`.
    seconds : tuple of float
        Seconds from the task's start (before the tracer is built, as
        ``estimate_receivers`` counts) to the end of each launch
        (``time.perf_counter``, JIT compilation included).
    launch_seconds : tuple of float
        Seconds each launch took.
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
    batch: int
    caustic: tuple[tuple[np.ndarray, ...], ...]
    photons: tuple[int, ...]
    emitted: tuple[np.ndarray, ...]
    cut: tuple[np.ndarray, ...]
    seconds: tuple[float, ...]
    launch_seconds: tuple[float, ...]
    extents: tuple[tuple[float, float, float, float], ...]
    channel_passes: int
    worker: str
    versions: dict


def trace_seed(scene: Scene, index: int, *, batch: int = DEFAULT_BATCH) -> SeedBatch:
    """Trace seed ``scene.settings.seed + index`` of the reference: its launches of
    ``launch_plan(settings.photons, batch)``, launch j on stream j with as many lanes
    as it has photons (each stratified at its own size), caustic maps only, exactly as
    :func:`~renderers.mitsuba.reference.estimate_receivers` traces that seed's rounds
    of the starting budget. A Dask task."""
    s = scene.settings
    seed = s.seed + index
    plan = launch_plan(s.photons, batch)
    start = time.perf_counter()
    tracer = PhotonTracer(scene, geometry=build_geometry(scene), caustic_only=True)
    caustic, photons, emitted, cut, seconds, launch_seconds = [], [], [], [], [], []
    for stream, n in enumerate(plan):
        began = time.perf_counter()
        sums = tracer.trace(n, seed=seed, stream=stream, batch=n)
        now = time.perf_counter()
        caustic.append(tuple(sums.caustic))
        photons.append(int(sums.photons))
        emitted.append(np.asarray(sums.emitted, np.float64))
        cut.append(np.asarray(sums.cut, np.float64))
        seconds.append(now - start)
        launch_seconds.append(now - began)
    return SeedBatch(index=index, seed=seed, batch=int(batch), caustic=tuple(caustic),
                     photons=tuple(photons), emitted=tuple(emitted), cut=tuple(cut),
                     seconds=tuple(seconds), launch_seconds=tuple(launch_seconds),
                     extents=tuple(tuple(e) for e in tracer.extents),
                     channel_passes=len(tracer.channels), worker=worker_name(),
                     versions=mitsuba_versions())


def _check(batches: list[SeedBatch], scene: Scene, versions: dict) -> None:
    s = scene.settings
    indices = [b.index for b in batches]
    if indices != list(range(s.seeds)):
        raise MergeError(f"{scene.name}: seed batches {indices} are not the seeds "
                         f"0..{s.seeds - 1} of the reference")
    first = batches[0]
    for b in batches:
        if b.versions != versions:
            raise MergeError(f"{scene.name}: seed {b.seed} was traced on {b.worker} with "
                             f"{b.versions}, the sweep keys its cache by {versions}: install "
                             "the same Mitsuba and Dr.Jit on every worker and the client")
        if b.seed != s.seed + b.index:
            raise MergeError(f"{scene.name}: batch {b.index} traced seed {b.seed}, the "
                             f"reference's seed {b.index} is {s.seed + b.index}")
        if (b.batch != first.batch or b.photons != launch_plan(s.photons, b.batch)
                or len(b.caustic) != len(b.photons) or b.extents != first.extents):
            raise MergeError(f"{scene.name}: seed {b.seed} traced other launches than "
                             f"launch_plan({s.photons}, {first.batch}) of seed {first.seed}")


def merge_reference(scene: Scene, key: str, versions: dict,
                    *batches: SeedBatch) -> RenderResult:
    """The reference of ``scene`` from its K seed batches (see the module docstring);
    its metadata as ``render_reference`` writes it, ``hash`` = ``key``. A Dask task.

    The budget's rounds are replayed from the batches; if the stop rule then goes on
    (target not met, and in reach within ``reference_time_cap``), this task traces
    the whole launches past the budget for every seed, seed after seed, until the rule
    stops. Elapsed time, which the stop rule and ``noise_history`` count from the
    start of the rounds: in the budget's rounds, the slowest seed's time from its
    task's start (the seeds ran in parallel); past the budget, the slowest seed's time
    for the whole budget plus the seconds since this merge started (the replay, the
    tracer's build and the launches it traced). The rate the rule projects the
    extension with is the last budget round's photons over the sum of the seeds'
    launch times: the merge traces the seeds one after another, as a single process.

    Raises
    ------
    MergeError
        The batches are not seeds 0..K-1 of this reference, traced the launches of
        the same plan, under ``versions`` (the versions the cache key was computed
        with).
    """
    start = time.perf_counter()
    s = scene.settings
    batches = sorted(batches, key=lambda b: b.index)
    _check(batches, scene, versions)
    first = batches[0]
    rounds = ReceiverRounds(extents=first.extents, seeds=s.seeds, seed=s.seed,
                            budget=s.photons, batch=first.batch, target=s.target_noise,
                            cap=s.reference_time_cap, channel_passes=first.channel_passes,
                            caustic_only=True)
    why = None
    for j in range(len(first.photons)):
        why = rounds.add([b.caustic[j] for b in batches], photons=first.photons[j],
                         emitted=[b.emitted[j] for b in batches],
                         cut=[b.cut[j] for b in batches],
                         elapsed=max(b.seconds[j] for b in batches),
                         seconds=sum(b.launch_seconds[j] for b in batches))
        if why is not None:
            break
    extended = 0
    if why is None:
        # The rounds' clock continues: the budget took the slowest seed's time, then
        # the merge's own (from its start).
        clock = start - max(b.seconds[-1] for b in batches)
        tracer = PhotonTracer(scene, geometry=build_geometry(scene), caustic_only=True)
        while why is None:
            why = rounds.trace(tracer, start=clock)
            extended += 1
    merged = time.perf_counter() - start
    estimate = rounds.estimate()
    result = reference_result(
        scene, estimate, key=key, versions=versions, camera="trace",
        timings={"receiver_maps": estimate.history[-1][2]},
        timer=f"{TIMER}; the starting budget's seeds traced in parallel, one task each: "
              "the slowest seed's; launches past it and the camera traced by the merge")
    result.timings["merge"] = merged
    result.metadata["cache"] = f"miss (merged from {len(batches)} seed tasks)"
    result.metadata["sweep"] = {"seed_tasks": len(batches),
                                "rounds_traced": len(first.photons) + extended,
                                "rounds_traced_by_merge": extended,
                                "rounds_used": rounds.rounds,
                                "workers": sorted({b.worker for b in batches}),
                                "merged_by": worker_name()}
    return result
