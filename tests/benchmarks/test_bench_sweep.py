"""Benchmark: wall time of one sweep on a local Dask cluster of 1 and of 2 process
workers, as a ratio (docs/architecture.md, "Sweeps on a Dask cluster").

The sweep is the tests' small one (2 scenes x 2 settings of the paper preset, 2
reference seeds and an independent reference on 2 more) with 200 000 photons per
seed, run end to end by ``caustics sweep`` (cluster start-up, references, renders,
scores, pages, index) without the caches, so both runs compute everything.
ROUNDS rounds alternate 1 and 2 workers, so drift of the machine falls on both
alike; reported: each run's wall time (``time.perf_counter`` around the command)
and the median of the per-round ratios t(1 worker) / t(2 workers). Both runs must
give the same rows and values up to the reference's float32 rounding order;
nothing else is asserted (a speedup is a finding, not a bound).

A local cluster shares the cores out: each of N workers runs Dr.Jit and llvmpipe on
cores / N threads (``harness.sweep.worker``), so one worker uses the whole machine
for its parallel parts and a second worker can only overlap the serial ones (Python,
start-up, HDR-FLIP's fixed cost per call), while it adds its own start-up (Mitsuba,
kernel and shader compilation in a second process).
"""

from __future__ import annotations

import os
import statistics
import time

import pytest

from harness.cli import main
from tests.harness.sweep.conftest import read_rows, write_sweep

ROUNDS = 3
PHOTONS = 200_000


@pytest.mark.bench
def test_bench_sweep_one_and_two_workers(tmp_path):
    """Benchmark (reported, not bounded; module docstring): the 1-vs-2-worker wall-time
    ratio of one sweep; both runs must agree on every row's relMSE within 1e-3
    (float32 rounding order of the photon tracer, far below the reference noise)."""
    sweep = write_sweep(tmp_path / "sweep", photons=PHOTONS)
    seconds = {1: [], 2: []}
    results = {}
    for round_ in range(ROUNDS):
        for workers in (1, 2):
            out = tmp_path / f"out-{workers}-{round_}"
            start = time.perf_counter()
            assert main(["sweep", str(sweep), "-o", str(out), "--workers", str(workers),
                         "--no-cache", "-q"]) == 0
            seconds[workers].append(time.perf_counter() - start)
            results[workers] = read_rows(out / "results.csv")
    for one, two in zip(results[1], results[2], strict=True):
        assert (one["scene"], one["iterations"]) == (two["scene"], two["iterations"])
        assert float(one["relmse"]) == pytest.approx(float(two["relmse"]), rel=1e-3)
    ratios = [a / b for a, b in zip(seconds[1], seconds[2], strict=True)]
    print(f"\nsweep of {len(results[1])} rows, {PHOTONS} photons x 2 seeds per reference, "
          f"on {os.cpu_count()} cores; time.perf_counter around `caustics sweep`, "
          f"{ROUNDS} alternating rounds")
    for workers in (1, 2):
        runs = ", ".join(f"{s:.1f}" for s in seconds[workers])
        print(f"  {workers} worker{'s' if workers > 1 else ''}: {runs} s "
              f"(median {statistics.median(seconds[workers]):.1f} s)")
    print(f"  t(1 worker) / t(2 workers): {statistics.median(ratios):.2f} "
          f"(median of per-round ratios {', '.join(f'{r:.2f}' for r in ratios)})")
