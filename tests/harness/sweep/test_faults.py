"""A task that raises, or a comparison with no answer (no caustic), costs its row,
never the sweep: the row records its scene, setting, stage and error in results.csv
and the index, every other row completes, and the failed rows are not cached (a
rerun tries them again)."""

from __future__ import annotations

import time

import harness.sweep.run as run_module
from harness.cli import main
from harness.sweep.cache import ResultsCache, results_dir
from harness.sweep.rows import render_row
from reports.records import NO_CAUSTIC, STATUS_REASONS

from .conftest import read_rows, small_scene, sweep_text

SWEEP = sweep_text(name="faults", description="one good scene, one that fails, one with no caustic",
                   scenes=["glass_sphere.toml", "broken.toml", "nocaustic.toml"], iterations=[3])


def failing_render(scene, method_name, *, repeats):
    """``render_row``, except that the scene named ``broken`` raises (a task of a
    worker; importable, so the in-process worker runs this very function)."""
    if scene.name == "broken":
        raise RuntimeError("injected render failure")
    return render_row(scene, method_name, repeats=repeats)


def test_failing_rows_are_recorded_and_the_sweep_goes_on(tmp_path, monkeypatch, capsys):
    """Regression lock (fault handling), on a real in-process Dask cluster: of three
    scenes, ``broken``'s render task raises (injected) and ``nocaustic``'s receiver
    lies beside the caustic, so its comparison finishes with the status ``no caustic``
    (as in `caustics compare`) and its row fails at the score; the glass sphere
    completes. results.csv and the index name
    each failure's scene, setting, stage and one-line error; exit status 1; stderr
    one line per failed row; only the good row is in the results cache."""
    folder = tmp_path / "sweep"
    folder.mkdir()
    small_scene(folder, "glass_sphere")
    small_scene(folder, "glass_sphere", file="broken.toml",
                **{'name = "glass_sphere"': 'name = "broken"'})
    small_scene(folder, "glass_sphere", file="nocaustic.toml",
                **{'name = "glass_sphere"': 'name = "nocaustic"',
                   "center = [0.0, 0.0, 0.0]": "center = [6.0, 6.0, 0.0]",
                   "size = [8.0, 8.0]": "size = [1.0, 1.0]"})
    (folder / "faults.toml").write_text(SWEEP)
    monkeypatch.setattr(run_module, "render_row", failing_render)
    # Its own cache: the failing rows must not reach the results cache, checked below.
    out, cache = tmp_path / "out", tmp_path / "cache"
    code = main(["sweep", str(folder / "faults.toml"), "-o", str(out), "--in-process",
                 "--cache-dir", str(cache), "-q"])
    assert code == 1
    rows = {r["scene"]: r for r in read_rows(out / "results.csv")}
    assert list(rows) == ["glass_sphere", "broken", "nocaustic"]
    good, broken, dark = rows["glass_sphere"], rows["broken"], rows["nocaustic"]
    assert good["error"] == "" and float(good["relmse"]) > 0 and good["page"]
    assert (broken["iterations"], broken["stage"], broken["error"]) == (
        "3", "render", "RuntimeError: injected render failure")
    assert broken["relmse"] == broken["worker"] == broken["page"] == ""
    assert (dark["stage"], dark["error"]) == ("score", STATUS_REASONS[NO_CAUSTIC])
    assert dark["worker"].startswith("inproc://") and dark["relmse"] == ""
    index = (out / "index.html").read_text()
    assert "2 of 3 rows failed" in index and "injected render failure" in index
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("error:")]
    assert err == ["error: broken-paper-iterations3 failed (render): RuntimeError: injected "
                   "render failure",
                   f"error: nocaustic-paper-iterations3 failed (score): {dark['error']}"]
    cached = ResultsCache(results_dir(cache))
    assert [cached.load(r["key"]) is not None for r in rows.values()] == [True, False, False]


def slow_square(x: int) -> int:
    """A task that takes a second, so that its recomputation is still running when
    the test looks (importable, for the in-process worker)."""
    time.sleep(1.0)
    return x * x


def test_a_result_lost_with_its_worker_is_waited_for():
    """Regression lock (fault tolerance: no row failed for nothing): a task that
    finished on a worker which then dies is ``lost`` (neither finished nor failed)
    until Dask computes it again elsewhere; the sweep's collector waits for that
    (``_settle``) instead of reading a failed row with no error, on a real in-process
    cluster of two workers, one closed after the task finished on it."""
    from dask.distributed import Client, LocalCluster, wait  # noqa: PLC0415

    with LocalCluster(n_workers=2, processes=False, threads_per_worker=1,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        first = cluster.workers[next(iter(cluster.workers))]
        future = client.submit(slow_square, 7, workers=[first.address],
                               allow_other_workers=True, pure=False)
        wait([future])
        cluster.sync(first.close)
        deadline = time.monotonic() + 10
        while future.status == "finished" and time.monotonic() < deadline:
            time.sleep(0.01)
        assert future.status == "lost"          # the race the collector meets
        run_module._settle(future)
        assert future.status == "finished"
        assert future.result() == 49
