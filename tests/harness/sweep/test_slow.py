"""Longer sweep tests (``tox -e slow``): Ctrl-C in the middle of a sweep on a local
cluster, and GPU work kept to the workers that offer a GPU."""

from __future__ import annotations

import os
import signal
import subprocess
import time

import pytest

import harness.sweep.cluster as cluster_module
from harness.cli import main
from harness.sweep.cache import ResultsCache, results_dir
from renderers.mitsuba.cache import load_entry

from .conftest import caustics, read_rows, small_scene, sweep_text, write_sweep

pytestmark = pytest.mark.slow

INTERRUPTED = sweep_text(name="interrupted", scenes=["glass_sphere.toml", "water_pool.toml"],
                         photons=None)


def _group(pgid: int) -> str:
    """``ps`` lines of the processes still in group ``pgid``."""
    return subprocess.run(["ps", "-o", "pid,stat,cmd", "-g", str(pgid)], capture_output=True,
                          text=True, check=False).stdout


def _group_ends(pgid: int, *, within: float) -> bool:
    """Whether every process of group ``pgid`` is gone within ``within`` seconds."""
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.2)
    return False


def test_ctrl_c_leaves_both_caches_whole(tmp_path):
    """Regression lock (the caches' contract: Ctrl-C leaves them consistent), on a real
    local cluster of two process workers: the glass sphere's references are small
    (20 000 photons per seed) and the water pool's large (40M), so the glass rows
    finish while the pool's seeds still trace; then SIGINT goes to the whole process
    group, as a terminal's Ctrl-C does. The sweep stops within seconds with exit
    130 and one ``interrupted`` line (no worker traceback), no process is left, the
    output folder was never swapped in, every results-cache and reference-cache
    entry there is whole (each passes its checks) and no temporary folder is left."""
    folder = tmp_path / "sweep"
    folder.mkdir()
    for name, photons in (("glass_sphere", 20_000), ("water_pool", 40_000_000)):
        path = small_scene(folder, name)
        path.write_text(path.read_text() + f"\n[settings]\nphotons = {photons}\n")
    (folder / "sweep.toml").write_text(INTERRUPTED)
    out, cache = tmp_path / "out", tmp_path / "cache"
    process = caustics("sweep", str(folder / "sweep.toml"), "-o", str(out), "--workers", "2",
                       "--cache-dir", str(cache), popen=True)
    rows = results_dir(cache)
    deadline = time.monotonic() + 300
    while not list(rows.glob("*/row.json")):
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.2)
    start = time.monotonic()
    os.killpg(process.pid, signal.SIGINT)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, stderr
    assert time.monotonic() - start < 60
    assert stderr.splitlines()[-1] == "interrupted" and "Traceback" not in stderr
    assert _group_ends(process.pid, within=20.0), _group(process.pid)
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.")]
    done = [p.name for p in rows.iterdir() if p.is_dir() and not p.name.startswith(".")]
    assert 1 <= len(done) < 4
    assert all(ResultsCache(rows).load(key) is not None for key in done)
    references = [p.name for p in cache.iterdir() if p.is_dir() and p != rows
                  and not p.name.startswith(".")]
    assert all(load_entry(cache, key)[1] == "hit" for key in references)
    assert not list(cache.rglob(".*.tmp-*"))


def test_renders_run_only_where_a_gpu_is_offered(tmp_path, dask_cluster, monkeypatch):
    """Regression lock (resource tagging): on a real cluster where worker w1 offers
    ``GPU=1`` (``dask worker --resources GPU=1``) and w0 offers nothing, every
    render runs on w1, so every row's ``worker`` is w1; the index names w1 as the
    GPU worker. Then a local cluster of two workers on a machine said to have one
    GPU gives one of them ``GPU=1``, and again every row renders there."""
    cluster = dask_cluster({"w0": [], "w1": ["--resources", "GPU=1"]})
    sweep = write_sweep(tmp_path / "sweep")
    out, cache = tmp_path / "out", tmp_path / "cache"
    assert main(["sweep", str(sweep), "-o", str(out), "--scheduler-file", str(cluster.file),
                 "--cache-dir", str(cache), "-q"]) == 0
    assert {r["worker"] for r in read_rows(out / "results.csv")} == {cluster.addresses["w1"]}
    assert "GPU workers (renders)" in (out / "index.html").read_text()

    monkeypatch.setattr(cluster_module, "local_gpus", lambda: 1)
    local = tmp_path / "local"
    assert main(["sweep", str(sweep), "-o", str(local), "--workers", "2", "--no-cache",
                 "-q"]) == 0
    (worker,) = {r["worker"] for r in read_rows(local / "results.csv")}
    index = (local / "index.html").read_text()
    assert worker in index.split("GPU workers (renders)")[1].split("</dd>")[0]
