"""Small sweeps and a real Dask cluster for the sweep tests.

The scenes are the bundled glass sphere (two refractions) and water pool (one
refraction) with a 48 × 36 camera; the sweep file shrinks every map and budget
(vertex grid 32, maps 128 px, receiver map 48 × 48, 20 000 photons per seed, 2
seeds, 2 spp; a noise target of 0.5, which that one launch meets, so no reference
traces past its budget), so a row costs a few seconds, most of it HDR-FLIP's fixed cost per
call (about 0.3–0.9 s on this machine, ten calls per row).

:class:`DaskCluster` starts a real ``dask scheduler`` and ``dask worker`` processes
on 127.0.0.1 (each worker one thread, no nanny, so killing its process kills the
worker) and stops exactly the processes it started, by their ids.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from scenes import SCENES_DIR as SCENES

#: Scene files of the small sweep (bundled scenes with a small camera).
SMALL_SCENES = ("glass_sphere", "water_pool")
#: Photons per seed of the small sweep's references.
PHOTONS = 20_000

SWEEP = """
[sweep]
name = "{name}"
description = "{description}"
scenes = {scenes}
presets = ["paper"]
repeats = 1

[sweep.settings]
grid = 32
caustic_map = 128
positions_map = 128
shadow_map = 128
receiver_map = [48, 48]

[sweep.grid]
iterations = {iterations}

[sweep.reference]
{photons}seeds = 2
spp = 2
target_noise = 0.5
"""


def sweep_text(*, name: str, scenes: list[str], iterations=(1, 3),
               photons: int | None = PHOTONS,
               description: str = "two scenes x two settings x two reference seeds") -> str:
    """The small sweep file's text (``photons`` None: the scenes' own budget)."""
    return SWEEP.format(name=name, description=description, scenes=json.dumps(scenes),
                        iterations=json.dumps(list(iterations)),
                        photons="" if photons is None else f"photons = {photons}\n")


def small_scene(folder: Path, name: str, *, file: str | None = None, **replace: str) -> Path:
    """A bundled scene with a 48 × 36 camera (and any text replaced), written to
    ``folder/file`` (default ``<name>.toml``)."""
    text = (SCENES / f"{name}.toml").read_text()
    marker = "resolution = [512, 512]"
    assert marker in text, name
    text = text.replace(marker, "resolution = [48, 36]")
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    path = folder / (file or f"{name}.toml")
    path.write_text(text)
    return path


def write_sweep(folder: Path, scenes=SMALL_SCENES, *, name: str = "small.toml",
                photons: int = PHOTONS) -> Path:
    """The small sweep file over ``scenes`` (files written beside it)."""
    folder.mkdir(parents=True, exist_ok=True)
    for scene in scenes:
        if not (folder / f"{scene}.toml").exists():
            small_scene(folder, scene)
    path = folder / name
    path.write_text(sweep_text(name="small", scenes=[f"{s}.toml" for s in scenes],
                               photons=photons))
    return path


def read_rows(path: Path) -> list[dict[str, str]]:
    """results.csv as dicts."""
    import csv  # noqa: PLC0415 - small helper

    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def _dask() -> list[str]:
    """The ``dask`` command of this environment."""
    script = Path(sys.executable).with_name("dask")
    return [str(script)] if script.exists() else [sys.executable, "-m", "dask"]


class DaskCluster:
    """A real scheduler and worker processes on 127.0.0.1 (see the module docstring).

    ``workers`` maps a worker's name to extra ``dask worker`` arguments (e.g.
    ``["--resources", "GPU=1"]``).
    """

    def __init__(self, folder: Path, workers: dict[str, list[str]]):
        self.folder = folder
        self.file = folder / "scheduler.json"
        self.processes: dict[str, subprocess.Popen] = {}
        self.addresses: dict[str, str] = {}
        self._start(workers)

    def _spawn(self, name: str, args: list[str]) -> None:
        with open(self.folder / f"{name}.log", "wb") as log:  # the child keeps its copy
            self.processes[name] = subprocess.Popen(
                [*_dask(), *args], stdout=log, stderr=subprocess.STDOUT, cwd=self.folder,
                start_new_session=True)

    def _start(self, workers: dict[str, list[str]]) -> None:
        from dask.distributed import Client  # noqa: PLC0415

        self.folder.mkdir(parents=True, exist_ok=True)
        self._spawn("scheduler", ["scheduler", "--host", "127.0.0.1", "--port", "0",
                                  "--no-dashboard", "--scheduler-file", str(self.file)])
        deadline = time.monotonic() + 60
        while not self.file.exists():
            assert time.monotonic() < deadline, self.log("scheduler")
            time.sleep(0.1)
        for name, extra in workers.items():
            self._spawn(name, ["worker", "--scheduler-file", str(self.file), "--nworkers", "1",
                               "--nthreads", "1", "--no-nanny", "--no-dashboard", "--name",
                               name, "--local-directory", str(self.folder / name), *extra])
        with Client(scheduler_file=str(self.file), timeout=30) as client:
            client.wait_for_workers(len(workers), timeout=120)
            info = client.scheduler_info(n_workers=-1)["workers"]
            self.addresses = {w["name"]: address for address, w in info.items()}

    def log(self, name: str) -> str:
        return (self.folder / f"{name}.log").read_text(errors="replace")

    def kill(self, name: str) -> None:
        """SIGKILL one worker's process (no clean-up, no goodbye to the scheduler)."""
        self.processes[name].send_signal(signal.SIGKILL)
        self.processes[name].wait(timeout=30)

    def close(self) -> None:
        """Stop the workers, then the scheduler (a worker closing says goodbye to it)."""
        workers = [p for name, p in self.processes.items() if name != "scheduler"]
        for group in (workers, [self.processes["scheduler"]]):
            for process in group:
                if process.poll() is None:
                    process.terminate()
            for process in group:
                try:
                    process.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait(timeout=10)


@pytest.fixture
def dask_cluster(tmp_path):
    """A factory of :class:`DaskCluster` s, each stopped after the test."""
    started = []

    def start(workers: dict[str, list[str]], folder: Path | None = None) -> DaskCluster:
        cluster = DaskCluster(folder or tmp_path / f"cluster{len(started)}", workers)
        started.append(cluster)
        return cluster

    yield start
    for cluster in started:
        cluster.close()


def caustics(*args: str, **kwargs) -> subprocess.CompletedProcess | subprocess.Popen:
    """Run ``caustics ARGS`` as a real process (``popen=True``: do not wait)."""
    popen = kwargs.pop("popen", False)
    command = [sys.executable, "-m", "harness", *args]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    if popen:
        return subprocess.Popen(command, env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True, start_new_session=True,
                                **kwargs)
    return subprocess.run(command, env=env, capture_output=True, text=True, check=False,
                          **kwargs)
