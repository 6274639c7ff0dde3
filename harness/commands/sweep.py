"""``caustics sweep SWEEP.toml -o DIR``: scenes × methods × settings × reference seeds
on a Dask cluster (:mod:`harness.sweep`).

Writes, through a staging folder swapped in at the end (as ``compare`` does),
``DIR/results.csv`` (:mod:`harness.sweep.results`), ``DIR/index.html`` (error
against cost and the Pareto front per scene, :mod:`reports.sweep`) and one page per
row, ``DIR/<scene>-<method>-<setting>/``, as ``caustics compare`` writes them.
Exit status: 0 every row done; 1 a row failed (its row says why), a bad sweep file,
an unreachable scheduler; 2 conflicting options; 130 interrupted (the caches keep
every row finished so far: the rerun computes only the rest).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

from harness.compare.staging import staged_output
from harness.sweep.cache import ResultsCache, results_dir
from harness.sweep.cluster import open_cluster
from harness.sweep.plan import SweepPlan, plan_sweep
from harness.sweep.results import pareto_keys, write_results_csv
from harness.sweep.run import RowResult, SweepRun, run_sweep
from harness.sweep.spec import load_sweep
from harness.terminal import markup, plain, warn
from harness.writable import usable_cache
from renderers.mitsuba import mitsuba_versions
from renderers.mitsuba.cache import cache_dir
from reports.sweep import SweepIndex, SweepRow, write_sweep_index

__all__ = ["sweep"]


def _index(plan: SweepPlan, run: SweepRun, *, seconds: float, front: set[str]) -> SweepIndex:
    sweep = plan.sweep
    rows = tuple(SweepRow(
        scene=r.job.scene.name, method=r.job.method,
        setting=r.job.setting.shown, values=r.values,
        time_warm_ms=r.time_warm_ms, worker=r.worker, cached=r.cached,
        pareto=r.job.key in front, folder=r.job.folder if r.page is not None else None,
        error=r.error, stage=r.stage) for r in run.rows)
    reference = sweep.reference
    info = {
        "methods": list(sweep.methods),
        "reference": (f"{reference.photons or 'scene'} photons "
                      f"x {reference.seeds or 'scene'} seeds per reference, one task per seed; "
                      "an independent reference on the next seeds for the noise floor"),
        "timed renders per row": sweep.repeats,
        "rows computed": sum(1 for r in run.rows if not r.cached),
        "tasks run": run.tasks,
        "references traced / from the cache": f"{run.references_traced} / "
                                              f"{run.references_cached}",
        "wall time (s)": round(seconds, 1),
    }
    if run.cluster is not None:
        info["cluster"] = f"{run.cluster.kind} ({run.cluster.address})"
        info["workers"] = list(run.cluster.workers)
        if run.cluster.gpu_workers:
            info["GPU workers (renders)"] = list(run.cluster.gpu_workers)
    scenes = tuple((s.name, s.info.description) for s in sweep.scenes)
    return SweepIndex(name=sweep.name, description=sweep.description, file=sweep.file,
                      columns=sweep.columns, rows=rows, scenes=scenes, run=info)


def _number(value) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    return f"{value:.3g}"


def _excess(values: dict, metric: str) -> str:
    """A row's metric for the summary: its excess and 95 % interval first, the raw
    value after (``harness.sweep.rows.row_values``)."""
    excess = values.get(f"excess_{metric}")
    if excess is None or not math.isfinite(excess):
        return f"raw {_number(values.get(metric))}"
    return (f"{_number(excess)} [{_number(values.get(f'excess_{metric}_low'))}, "
            f"{_number(values.get(f'excess_{metric}_high'))}] (raw "
            f"{_number(values.get(metric))})")


def _print_summary(rows: list[RowResult], out: str, seconds: float, run: SweepRun) -> None:
    computed = sum(1 for r in rows if not r.cached)
    table = Table(title=markup(f"sweep: {len(rows)} rows, {computed} computed, "
                               f"{run.tasks} tasks ({seconds:.0f} s) -> {out}/index.html"),
                  caption="receiver 0, the scene's caustic region: the method's own error "
                  "against the noise-free image [95 % interval], then the raw value; SSIM: "
                  "the deficit below a perfect method's; flux: ratio − 1 over the map; "
                  "time: warm frame time")
    for column in ("scene", "method", "setting", "excess relMSE", "SSIM deficit",
                   "flux ratio − 1", "time ms", "worker", "cached"):
        table.add_column(column)
    for r in rows:
        if r.failed:
            cells = (r.job.scene.name, r.job.method, r.job.setting.label,
                     f"FAILED ({r.stage})", *("–",) * 3, r.worker or "–", "no")
        else:
            cells = (r.job.scene.name, r.job.method, r.job.setting.label,
                     *(_excess(r.values, k) for k in ("relmse", "ssim", "flux_ratio")),
                     _number(r.time_warm_ms), r.worker, "yes" if r.cached else "no")
        table.add_row(*(markup(c) for c in cells))
    console = Console()
    if not console.is_terminal:
        console = Console(width=220)
    console.print(table)
    for r in rows:
        if r.failed:
            print(f"error: {plain(r.job.folder)} failed ({r.stage}): {r.error}", file=sys.stderr)


def _conflicting(args: argparse.Namespace) -> str | None:
    if args.workers is not None and (args.scheduler or args.scheduler_file or args.in_process):
        return "--workers sizes a local cluster: not with --scheduler, --scheduler-file or " \
               "--in-process"
    if args.workers is not None and args.workers < 1:
        return "--workers must be at least 1"
    return None


def sweep(args: argparse.Namespace) -> int:
    """``caustics sweep``: see the module docstring."""
    start = time.perf_counter()
    conflict = _conflicting(args)
    if conflict:
        print(f"error: {conflict}", file=sys.stderr)
        return 2
    spec = load_sweep(args.sweep)
    for problem in spec.warnings:
        warn(problem)
    plan = plan_sweep(spec, versions=mitsuba_versions())
    if args.dry_run:
        return _dry_run(plan)
    use_cache = not args.no_cache and usable_cache(cache_dir(args.cache_dir))
    reference_root = cache_dir(args.cache_dir) if use_cache else None
    results = ResultsCache(results_dir(reference_root)) if use_cache else None

    def connect():
        return open_cluster(scheduler=args.scheduler, scheduler_file=args.scheduler_file,
                            workers=args.workers, in_process=args.in_process,
                            timeout=args.connect_timeout)

    with staged_output(args.output) as out_dir:
        run = run_sweep(plan, connect=connect, out_dir=out_dir, results=results,
                        reference_root=reference_root, progress=not args.quiet)
        front = pareto_keys(run.rows)
        write_results_csv(out_dir / "results.csv", run.rows, grid=spec.columns)
        write_sweep_index(out_dir, _index(run.plan, run, seconds=time.perf_counter() - start,
                                          front=front))
    _print_summary(run.rows, str(Path(args.output)), time.perf_counter() - start, run)
    return 1 if any(r.failed for r in run.rows) else 0


def _dry_run(plan: SweepPlan) -> int:
    """Print what the sweep would compute, and stop (nothing renders)."""
    sweep = plan.sweep
    seeds = sum(len(job.seeds) for job in plan.references.values())
    print(f"{plain(sweep.name)}: {len(sweep.scenes)} scenes x {len(sweep.methods)} methods x "
          f"{len(sweep.combinations())} settings = {len(plan.rows)} rows; "
          f"{len(plan.references)} references ({seeds} seed tasks, before the cache)")
    for job in plan.rows:
        print(f"  {plain(job.folder)}  {job.key[:12]}")
    return 0
