"""Run a planned sweep on a Dask client: what is new is computed, the rest is read.

The task graph, per reference not in the reference cache: K seed tasks
(:func:`.seeds.trace_seed`) and one merge (:func:`.seeds.merge_reference`); per
row not in the results cache: a render (:func:`.rows.render_row`, asking for the
``GPU`` resource when the cluster offers it) and a score that needs the render and
both references (:func:`.rows.score_row`). References found in the reference cache
are scattered to two workers instead (scattered data cannot be recomputed, so one
worker's loss must not take the only copy). Renders go first, so the workers render
while the references trace.

Everything is written by the client (this process), as each task's result
arrives: a merged reference into the reference cache
(:func:`renderers.mitsuba.reference.cached_reference`, as ``caustics compare``
caches its references), a scored row with its data files and page
(:func:`harness.compare.isolation.write_outputs`, as ``caustics compare`` writes
them) into the results cache, both atomically; a worker writes nothing. So a worker
killed mid-task loses nothing (Dask runs the task again elsewhere; a task whose
worker dies three times is failed with ``KilledWorker``), and Ctrl-C leaves both
caches with whole entries only.

A task that raises costs its row(s), never the sweep: the row records its stage
(``reference``, ``render`` or ``score``) and the one-line error, and every other row
goes on; so does a row whose comparison has no answer (its status, ``no caustic``:
stage ``score``). Failed rows are not cached; a rerun tries them again.
"""

from __future__ import annotations

import dataclasses
import shutil
import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tqdm import tqdm

from harness.compare.isolation import status_failure, write_outputs
from harness.sweep.cache import CachedRow, ResultsCache
from harness.sweep.cluster import GPU, ClusterInfo, worker_versions
from harness.sweep.plan import RowJob, SweepPlan, plan_sweep
from harness.sweep.rows import render_row, row_values, score_row
from harness.sweep.seeds import merge_reference, trace_seed
from harness.terminal import error_line
from renderers.mitsuba.reference import CUT_WARNING, CutFluxWarning, cached_reference
from renderers.results import RenderResult
from reports.records import SceneComparison
from scenes import Scene

__all__ = ["PRIORITY", "RowResult", "SweepRun", "run_sweep"]

#: Dask priorities (higher first): renders, then merges and scores as soon as their
#: inputs are there, seeds in between.
PRIORITY = {"render": 30, "score": 20, "merge": 10, "seed": 0}


@dataclass(frozen=True)
class RowResult:
    """One row's outcome.

    Attributes
    ----------
    job : RowJob
    values : dict of str to float
        ``relmse``, ``ssim``, ``flip``, ``flux_ratio`` (:data:`.rows.KEY_VALUES`),
        ``relmse_noise_floor``; empty for a failed row.
    time_warm_ms : float or None
        The method's warm frame time (:class:`.rows.RowRender`).
    worker : str
        The worker that rendered the row ("" when it failed before rendering).
    cached : bool
        Read from the results cache (nothing computed).
    error, stage : str
        For a failed row: the one-line error and where (``reference``, ``render``,
        ``score``, ``page``); "" otherwise.
    page : Path or None
        The folder holding the row's page (in the results cache, or written in place).
    details : dict
        Reference noise, timer, GL renderer.
    """

    job: RowJob
    values: dict[str, float] = field(default_factory=dict)
    time_warm_ms: float | None = None
    worker: str = ""
    cached: bool = False
    error: str = ""
    stage: str = ""
    page: Path | None = None
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def failed(self) -> bool:
        return bool(self.error)


@dataclass
class SweepRun:
    """What :func:`run_sweep` did: rows in plan order, the plan they came from (keyed
    by the workers' versions), tasks run, references traced and read."""

    rows: list[RowResult]
    plan: SweepPlan
    tasks: int = 0
    references_traced: int = 0
    references_cached: int = 0
    cluster: ClusterInfo | None = None


def _row_record(job: RowJob, comparison: SceneComparison, render) -> dict:
    """The values a results-cache entry keeps for a row."""
    reference = comparison.provenance.reference
    timed = render.timed
    return {"scene": job.scene.name, "method": job.method,
            "setting": {k: v for k, v in job.setting.items},
            "values": row_values(comparison),
            "time_warm_ms": timed.warm_seconds * 1e3, "worker": render.worker,
            "details": {"timer": timed.timer, "gl_renderer": timed.gl_renderer,
                        "reference_noise": reference.get("relative_noise"),
                        "reference_photons": reference.get("photons"),
                        "reference_seeds": reference.get("seeds")}}


def _from_record(job: RowJob, record: dict, *, page: Path, cached: bool) -> RowResult:
    values = {k: float("nan") if v is None else float(v)
              for k, v in record.get("values", {}).items()}
    warm = record.get("time_warm_ms")
    return RowResult(job=job, values=values, time_warm_ms=None if warm is None else float(warm),
                     worker=str(record.get("worker", "")), cached=cached, page=page,
                     details=dict(record.get("details") or {}))


def _page_writer(comparison: SceneComparison) -> Callable[[Path], None]:
    def write(folder: Path) -> None:
        # The page's links to the shared style sheet are ../_static/: the folder is
        # copied into the output beside the sweep's index, which writes _static.
        write_outputs(folder.parent, folder.name, comparison)
    return write


def _store_reference(root: Path | None, scene: Scene, result: RenderResult) -> None:
    """Put a merged reference into the reference cache (unless an entry is there)."""
    fraction = result.metadata.get("cut_flux_fraction") or 0.0
    if fraction > CUT_WARNING:
        warnings.warn(f"{result.metadata.get('scene')}: the reference's safety cap cut off "
                      f"{fraction:.2e} of the emitted caustic flux", CutFluxWarning,
                      stacklevel=2)
    if root is not None:
        cached_reference(scene, key=result.metadata["hash"], root=root,
                         render=lambda: result)


class _Progress:
    """A tqdm bar over the tasks (nothing with ``enabled=False``)."""

    def __init__(self, total: int, rows: int, *, enabled: bool):
        self.bar = None
        self.rows, self.done, self.failed = rows, 0, 0
        if enabled and total:
            self.bar = tqdm(total=total, desc="sweep", unit="task", leave=False)

    def task(self) -> None:
        if self.bar is not None:
            self.bar.update(1)

    def row(self, failed: bool) -> None:
        self.done += 1
        self.failed += failed
        if self.bar is not None:
            self.bar.set_postfix(rows=f"{self.done}/{self.rows}", failed=self.failed)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


@dataclass
class _Graph:
    """The submitted futures: references (merge or scattered) by key, the seed and
    merge tasks, and each pending row's render and score by row key."""

    references: dict = field(default_factory=dict)
    seeds: list = field(default_factory=list)
    merges: dict = field(default_factory=dict)
    renders: dict = field(default_factory=dict)
    scores: dict = field(default_factory=dict)

    def all(self) -> list:
        return [*self.seeds, *self.merges, *self.renders.values(), *self.scores.values()]


class _Runner:
    """One run of the pending rows on a client: submits the graph, then handles each
    result as it arrives (module docstring)."""

    def __init__(self, client, plan: SweepPlan, info: ClusterInfo, *, out_dir: Path,
                 results: ResultsCache | None, reference_root: Path | None, run: SweepRun):
        self.client, self.plan, self.info = client, plan, info
        self.out_dir, self.results, self.reference_root = out_dir, results, reference_root
        self.run = run
        self.graph = _Graph()

    def submit(self, pending: list[RowJob]) -> None:
        """Submit the task graph of the ``pending`` rows: the renders first (so idle
        workers share them out before the seeds arrive), then each reference's seeds
        and merge (or its cached entry, scattered), then the scores."""
        client, graph, run = self.client, self.graph, self.run
        resources = {GPU: 1} if self.info.gpu_tagged else None
        # The photon tracer is GPU work too where the workers' Mitsuba runs on CUDA.
        on_gpu = self.plan.versions.get("variant", "").startswith("cuda")
        traced = resources if on_gpu else None
        for job in pending:
            graph.renders[job.key] = client.submit(
                render_row, job.scene, job.method, repeats=self.plan.sweep.repeats,
                key=f"render-{job.folder}-{job.key[:10]}", resources=resources,
                priority=PRIORITY["render"], pure=False)
            run.tasks += 1
        needed = dict.fromkeys(k for job in pending for k in (job.reference, job.independent))
        for key in needed:
            job = self.plan.references[key]
            cached = (cached_reference(job.scene, key=key, root=self.reference_root)
                      if self.reference_root is not None else None)
            if cached is not None:
                # Scattered data cannot be recomputed: keep two copies, so that a
                # worker killed mid-sweep does not take the only one with it.
                graph.references[key] = client.scatter(cached)
                client.replicate([graph.references[key]], n=min(2, len(self.info.workers)))
                run.references_cached += 1
                continue
            tag = f"{job.scene.name}-{job.role}-{key[:10]}"
            seeds = [client.submit(trace_seed, job.scene, i, key=f"seed-{tag}-{seed}",
                                   resources=traced, priority=PRIORITY["seed"], pure=False)
                     for i, seed in enumerate(job.seeds)]
            merge = client.submit(merge_reference, job.scene, key, self.plan.versions, *seeds,
                                  key=f"reference-{tag}", resources=traced,
                                  priority=PRIORITY["merge"], pure=False)
            graph.seeds += seeds
            graph.merges[merge] = key
            graph.references[key] = merge
            run.tasks += len(seeds) + 1
            run.references_traced += 1
        for job in pending:
            extra = {"sweep": self.plan.sweep.name, "setting": job.setting.label,
                     "key": job.key}
            graph.scores[job.key] = client.submit(
                score_row, job.scene, job.method, graph.renders[job.key],
                graph.references[job.reference], graph.references[job.independent],
                extra=extra, key=f"score-{job.folder}-{job.key[:10]}",
                priority=PRIORITY["score"], pure=False)
            run.tasks += 1

    def collect(self, pending: list[RowJob], done: dict[str, RowResult], *,
                progress: bool) -> None:
        """Handle every result as it arrives; each row lands in ``done``."""
        from dask.distributed import as_completed  # noqa: PLC0415 - Dask loads only for a sweep

        graph = self.graph
        jobs = {job.key: job for job in pending}
        row_of = {future: key for key, future in graph.scores.items()}
        bar = _Progress(self.run.tasks, len(pending), enabled=progress)
        # The seed futures live only inside as_completed: once a seed is merged its data
        # may go (Dask recomputes it from the graph should the merge's worker die).
        finished = as_completed(graph.all())
        graph.seeds = []
        try:
            for future in finished:
                bar.task()
                if future in graph.merges or future in row_of:
                    _settle(future)     # a seed is read only by its merge, through Dask
                if future in graph.merges and future.status == "finished":
                    key = graph.merges[future]
                    _store_reference(self.reference_root, self.plan.references[key].scene,
                                     future.result())
                elif future in row_of:
                    key = row_of[future]
                    done[key] = self.row(future, jobs[key])
                    bar.row(done[key].failed)
                    graph.renders.pop(key)  # the workers may drop what only this row needed
        except BaseException:
            self.client.cancel([*graph.renders.values(), *graph.scores.values(),
                                *graph.references.values()])
            raise
        finally:
            bar.close()

    def row(self, future, job: RowJob) -> RowResult:
        """The row of a finished score future: its page written (into the results
        cache when there is one), or the failure."""
        if future.status != "finished":
            return _failure(job, future, self.graph)
        comparison = future.result()
        render = self.graph.renders[job.key].result()
        unanswered = status_failure(comparison)
        if unanswered is not None:  # no caustic: nothing to compare (as in compare)
            return RowResult(job=job, worker=render.worker, error=unanswered.error,
                             stage="score")
        record = _row_record(job, comparison, render)
        try:
            if self.results is not None:
                entry = self.results.store(job.key, record, _page_writer(comparison))
                return _from_record(job, entry.row, page=entry.page, cached=False)
            page = self.out_dir / job.folder
            _page_writer(comparison)(page)
            return _from_record(job, record, page=page, cached=False)
        except OSError:
            raise  # the disk (full, read-only): the user's to fix, not this row's
        except Exception as error:  # a page that cannot be built costs its row
            return RowResult(job=job, worker=render.worker, error=error_line(error),
                             stage="page")


def _settle(future) -> None:
    """Wait until ``future`` is final again if its data was lost since it finished:
    a worker that dies after finishing a task takes the result with it, Dask computes
    the task again from the graph (this future still holds it), and meanwhile the
    future is ``lost``, neither finished nor failed (read then, a row failed with no
    error)."""
    if future.status == "lost":
        from dask.distributed import wait  # noqa: PLC0415 - Dask loads only for a sweep

        wait([future])


def _failure(job: RowJob, future, graph: _Graph) -> RowResult:
    """The failed row of ``future`` (a score), naming the stage that failed first."""
    renders, references = graph.renders, graph.references
    stage, error = "score", future.exception()
    for name, dependency in (("reference", references[job.reference]),
                             ("reference", references[job.independent]),
                             ("render", renders[job.key])):
        if getattr(dependency, "status", None) == "error":
            stage, error = name, dependency.exception()
            break
    worker = ""
    if stage != "render" and renders[job.key].status == "finished":
        worker = renders[job.key].result().worker
    return RowResult(job=job, worker=worker, error=error_line(error), stage=stage)


def _announce(info: ClusterInfo, rows: int) -> None:
    """One line on stderr: where the rows run (and the dashboard to watch them)."""
    gpu = f", {len(info.gpu_workers)} with a GPU" if info.gpu_workers else ""
    dashboard = f"; dashboard {info.dashboard}" if info.dashboard else ""
    print(f"sweep: {rows} rows on a {info.kind} Dask cluster at {info.address} "
          f"({len(info.workers)} workers{gpu}){dashboard}", file=sys.stderr)


def _cached_rows(plan: SweepPlan, results: ResultsCache | None) -> dict[str, RowResult]:
    """The rows of ``plan`` the results cache holds, by key."""
    done = {}
    for job in plan.rows:
        cached: CachedRow | None = results.load(job.key) if results is not None else None
        if cached is not None:
            done[job.key] = _from_record(job, cached.row, page=cached.page, cached=True)
    return done


def run_sweep(plan: SweepPlan, *, connect: Callable[[], Any], out_dir: Path,
              results: ResultsCache | None, reference_root: Path | None,
              progress: bool = True) -> SweepRun:
    """Compute the rows of ``plan`` not in ``results`` and write every row's page
    into ``out_dir/<row folder>`` (see the module docstring).

    The workers, not this process, trace the references, so the keys must name
    their Mitsuba and Dr.Jit: when the workers' versions (they must agree,
    :func:`.cluster.worker_versions`) differ from ``plan.versions``, the sweep is
    planned again under theirs before anything is submitted.

    Parameters
    ----------
    connect
        A context-manager factory yielding ``(client, ClusterInfo)``
        (:func:`.cluster.open_cluster`); not called when every row is cached.
    out_dir
        Where the rows' page folders go (the command's staging folder).
    results
        The results cache; None computes every row and caches nothing.
    reference_root
        The reference cache's root; None neither reads nor writes it.
    progress
        A progress bar over the tasks (tqdm, on stderr).
    """
    done = _cached_rows(plan, results)
    run = SweepRun(rows=[], plan=plan)
    if len(done) < len(plan.rows):
        with connect() as (client, info):
            run.cluster = info
            versions = worker_versions(client, info)
            if versions != plan.versions:
                plan = run.plan = plan_sweep(plan.sweep, versions=versions)
                done = _cached_rows(plan, results)
            pending = [job for job in plan.rows if job.key not in done]
            if progress:
                _announce(info, len(pending))
            runner = _Runner(client, plan, info, out_dir=out_dir, results=results,
                             reference_root=reference_root, run=run)
            runner.submit(pending)
            runner.collect(pending, done, progress=progress)
    for job in plan.rows:
        row = done[job.key]
        target = out_dir / job.folder
        if row.page is not None and row.page != target and row.page.is_dir():
            shutil.copytree(row.page, target)
            row = dataclasses.replace(row, page=target)
        run.rows.append(row)
    return run
