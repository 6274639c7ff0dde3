"""`caustics sweep` on a real Dask cluster: a `dask scheduler` and two `dask worker`
processes on 127.0.0.1 (docs/architecture.md, "What the tests show"): the results
equal a single-process run with the same seeds and both workers rendered rows; a
rerun computes nothing; a worker killed mid-sweep costs no row.

Tolerances. The photon tracer accumulates each receiver map with float32 atomic
additions inside Dr.Jit's parallel scatter, whose order differs between any two runs
(in one process too): two traces of the same seed differ by rounding only. A texel
holding the sum of n photons' contributions can move by at most about n · 2^-24 of
its value, and n is at most the photons per seed, so maps are compared texel by
texel within PHOTONS · 2^-24 (1.2e-3) of their value; the camera tracer's pixels
(direct light, deterministic per seed, plus bilinear lookups in caustic maps of P
photons per seed, traced the same way) within P · 2^-24. The relMSE of a row is d² /
(r² + 0.01) averaged: a relative change δ of the reference moves it by at most 2δ ·
r/|d| ≲ 4δ where the method is off by a quarter of the reference or more (every
caustic texel here), so it is compared within 4 · PHOTONS · 2^-24. Each tolerance is
shown to be able to fail: other seeds (the independent reference) differ by far
more.
"""

from __future__ import annotations

import shutil
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from harness.cli import main
from harness.compare.evaluate import exposure_for, score_value
from harness.compare.regions import caustic_region, scene_caustic_region
from harness.sweep.cache import ResultsCache, results_dir
from harness.sweep.plan import plan_sweep
from harness.sweep.spec import load_sweep
from renderers.exr import read_exr
from renderers.methods import load_method
from renderers.mitsuba import mitsuba_versions
from renderers.mitsuba.cache import read_result_dir
from renderers.mitsuba.reference import render_reference

from .conftest import PHOTONS, DaskCluster, caustics, read_rows, write_sweep

#: float32 rounding of one addition, relative.
ULP = 2.0**-24
MAP_RTOL = PHOTONS * ULP
RELMSE_RTOL = 4 * PHOTONS * ULP


@pytest.fixture(scope="module")
def cluster_run(tmp_path_factory):
    """The small sweep (2 scenes x 2 settings x 2 reference seeds) run once on a real
    scheduler with two workers. The cluster stays up for the module's last test,
    which kills one of its workers."""
    folder = tmp_path_factory.mktemp("cluster-sweep")
    sweep = write_sweep(folder)
    cluster = DaskCluster(folder / "cluster", {"w0": [], "w1": []})
    try:
        # Its own cache: a sweep's cache holds its rows as well as the references, and
        # the tests here count what the first run computed and what a rerun reads.
        out, cache = folder / "out", folder / "cache"
        start = time.perf_counter()
        code = main(["sweep", str(sweep), "-o", str(out), "--scheduler-file",
                     str(cluster.file), "--cache-dir", str(cache), "-q"])
        seconds = time.perf_counter() - start
        yield SimpleNamespace(sweep=sweep, out=out, cache=cache, code=code, seconds=seconds,
                              cluster=cluster, addresses=dict(cluster.addresses),
                              folder=folder, rows=read_rows(out / "results.csv"))
    finally:
        cluster.close()


def _within(actual: np.ndarray, expected: np.ndarray, rtol: float) -> float:
    """Largest |actual - expected| / |expected| (0/0 counts as 0); asserts shapes."""
    actual, expected = np.asarray(actual, np.float64), np.asarray(expected, np.float64)
    assert actual.shape == expected.shape
    diff = np.abs(actual - expected)
    assert np.all(diff <= rtol * np.abs(expected)), float(np.max(diff / np.maximum(
        np.abs(expected), 1e-300)))
    return float(np.max(np.divide(diff, np.abs(expected), out=np.zeros_like(diff),
                                  where=expected != 0)))


def test_real_cluster_equals_a_single_process_run(cluster_run):
    """Physical requirement (the same estimator): a sweep of 2 scenes x 2 settings x 2
    reference seeds on a real `dask scheduler` with two `dask worker` processes gives
    every row, both workers rendered rows (the `worker` column), and its results
    equal a single-process run with the same seeds: each merged reference (one task
    per seed) equals `render_reference` in this process, the method maps are
    bit-identical, and the relMSE in results.csv equals the one computed here from
    the single-process maps. Tolerances from float32 rounding (module docstring);
    other seeds break them."""
    assert cluster_run.code == 0
    rows = cluster_run.rows
    assert [(r["scene"], r["iterations"]) for r in rows] == [
        ("glass_sphere", "1"), ("glass_sphere", "3"), ("water_pool", "1"), ("water_pool", "3")]
    assert all(r["error"] == "" and r["cached"] == "false" for r in rows)
    assert {r["worker"] for r in rows} == set(cluster_run.addresses.values())

    plan = plan_sweep(load_sweep(cluster_run.sweep), versions=mitsuba_versions())
    single = {}
    for key, job in plan.references.items():
        merged = read_result_dir(cluster_run.cache / key)     # written by the sweep
        alone = render_reference(job.scene, use_cache=False, progress=False)
        single[key] = alone
        for a, b in zip(merged.receivers, alone.receivers, strict=True):
            worst = _within(a.irradiance, b.irradiance, MAP_RTOL)
            print(f"{job.scene.name} {job.role}: largest relative map difference {worst:.2e}")
            assert np.all(np.isfinite(a.variance)) and a.variance.max() > 0
        s = job.scene.settings
        assert merged.metadata["camera_integrator"] == alone.metadata["camera_integrator"]
        _within(merged.camera, alone.camera, merged.metadata["camera_lookup"]["photons"] * ULP)
        for name in ("photons", "seeds", "seed", "stopped_by", "hash"):
            assert merged.metadata[name] == alone.metadata[name], name
        assert merged.metadata["relative_noise"] == pytest.approx(
            alone.metadata["relative_noise"], rel=RELMSE_RTOL)
        assert merged.metadata["sweep"]["seed_tasks"] == s.seeds == 2

    by_folder = {r["page"]: r for r in rows}
    for job in plan.rows:
        row = by_folder[job.folder]
        page = cluster_run.out / job.folder
        method = load_method(job.method).render(job.scene).receivers[0].irradiance
        on_worker = read_exr(page / "receiver0_method.exr")["RGB"]
        assert np.array_equal(on_worker, method), job.folder          # llvmpipe is ordered
        reference = single[job.reference].receivers[0].irradiance
        other = single[job.independent].receivers[0].irradiance
        # The scored region: the scene's, from the independent reference, as compare's.
        relmse = score_value("relmse", method, reference, mask=scene_caustic_region(other),
                             exposure=exposure_for(reference))
        assert float(row["relmse"]) == pytest.approx(relmse, rel=RELMSE_RTOL)
        print(f"{job.folder}: relMSE {row['relmse']} here {relmse!r}")
        # Non-vacuity: other seeds move the map, and the relMSE, far beyond the bounds.
        region = caustic_region(reference)
        spread = np.abs(other - reference)[region] / reference[region]
        assert np.median(spread) > 10 * MAP_RTOL
        other_relmse = score_value("relmse", method, other, mask=region,
                                   exposure=exposure_for(other))
        assert abs(other_relmse - relmse) > RELMSE_RTOL * relmse
    index = (cluster_run.out / "index.html").read_text()
    assert all(f'href="{job.folder}/index.html"' in index for job in plan.rows)


def test_rerun_recomputes_nothing(cluster_run, tmp_path):
    """Regression lock: the same sweep again (same cache) reads every row from the
    results cache: `cached = true` everywhere, values and workers as computed, every
    page there, and no cluster at all (the scheduler named does not exist: a run
    that needed it would fail to connect)."""
    out = tmp_path / "again"
    start = time.perf_counter()
    code = main(["sweep", str(cluster_run.sweep), "-o", str(out), "--scheduler",
                 "tcp://127.0.0.1:9", "--cache-dir", str(cluster_run.cache), "-q"])
    seconds = time.perf_counter() - start
    assert code == 0
    rows = read_rows(out / "results.csv")
    assert [r["cached"] for r in rows] == ["true"] * 4
    strip = ("cached",)
    assert [{k: v for k, v in r.items() if k not in strip} for r in rows] == [
        {k: v for k, v in r.items() if k not in strip} for r in cluster_run.rows]
    for row in rows:
        assert (out / row["page"] / "index.html").is_file()
        assert (out / row["page"] / "metrics.json").is_file()
    assert seconds < cluster_run.seconds


def _copy_references(source: Path, target: Path) -> None:
    """The reference entries of a cache, without its sweep rows."""
    target.mkdir(parents=True)
    for entry in source.iterdir():
        if entry.is_dir() and entry.name != results_dir(source).name:
            shutil.copytree(entry, target / entry.name)


def test_worker_killed_mid_sweep_loses_nothing(cluster_run, tmp_path):
    """Regression lock (fault tolerance: no result lost): on the real cluster of two workers, one
    worker process is SIGKILLed while it is running a task of the sweep; Dask runs
    its tasks again on the other worker and the sweep completes with every row, no
    error, the values the undisturbed run computed (same cached references, same
    renders: equal), and every results-cache entry whole. (Kills a worker of the
    module's cluster: the last test here.)"""
    cluster = cluster_run.cluster
    cache = tmp_path / "cache"
    _copy_references(cluster_run.cache, cache)  # rows only: renders and scores
    sweep = write_sweep(tmp_path / "sweep", ("glass_sphere",))
    out = tmp_path / "out"
    process = caustics("sweep", str(sweep), "-o", str(out), "--scheduler-file",
                       str(cluster.file), "--cache-dir", str(cache), "-q", popen=True)
    victim = cluster.addresses["w1"]
    from dask.distributed import Client  # noqa: PLC0415

    killed_during = None
    with Client(scheduler_file=str(cluster.file), timeout=30) as client:
        deadline = time.monotonic() + 240
        while killed_during is None and process.poll() is None:
            assert time.monotonic() < deadline, "the victim never ran a task"
            running = client.processing(workers=[victim]).get(victim, ())
            if running:
                time.sleep(0.3)  # well inside the task (a score takes seconds)
                running = client.processing(workers=[victim]).get(victim, ())
                if running:
                    killed_during = list(running)
                    cluster.kill("w1")
            time.sleep(0.05)
        _, stderr = process.communicate(timeout=600)
        survivors = set(client.scheduler_info(n_workers=-1)["workers"])
    assert killed_during, "the sweep finished before a task ran on the victim"
    assert process.returncode == 0, stderr
    assert survivors == {cluster.addresses["w0"]}
    rows = read_rows(out / "results.csv")
    assert len(rows) == 2 and all(r["error"] == "" for r in rows)
    before = {r["page"]: r for r in cluster_run.rows}
    for row in rows:
        for column in ("relmse", "ssim", "flip", "flux_ratio", "relmse_noise_floor"):
            assert row[column] == before[row["page"]][column], column
        assert ResultsCache(results_dir(cache)).load(row["key"]) is not None
    assert not list(results_dir(cache).glob(".*.tmp-*"))
