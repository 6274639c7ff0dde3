"""Where a sweep runs: a Dask distributed cluster, local or existing.

* Default: a local cluster of process workers, one per core (``--workers N``),
  each with one thread, so a worker runs one task at a time and each render is
  timed alone in its process (the Mitsuba variant and the GL context are per
  process: :mod:`.worker`).
* ``--scheduler tcp://host:8786``, or the ``DASK_SCHEDULER_ADDRESS`` environment
  variable (Dask's own ``scheduler-address`` setting): an existing cluster.
* ``--scheduler-file PATH``: the file ``dask scheduler --scheduler-file`` wrote.
* ``--in-process``: one worker thread inside this process (no other process at
  all): for debugging, and the single-process run the tests compare with.

GPU work is tagged: when any worker of the cluster offers the resource ``GPU``
(``dask worker --resources GPU=1``), every method render asks for ``GPU=1`` and so
runs only there; the photon tracer (Dr.Jit on the CPU) runs anywhere. A local
cluster on a machine with NVIDIA GPUs gives that many of its workers ``GPU=1``.

Workers need this project installed (same versions as the client: the merge of a
reference checks Mitsuba's and Dr.Jit's); they need no shared file system, since
every file is written by the client.
"""

from __future__ import annotations

import contextlib
import copy
import logging
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from harness.sweep.worker import THREADS_ENV
from renderers.mitsuba import mitsuba_versions
from scenes.errors import HarnessError

__all__ = ["GPU", "ClusterError", "ClusterInfo", "local_gpus", "open_cluster",
           "worker_versions"]

#: The worker resource that GPU work asks for.
GPU = "GPU"
#: A local scheduler's HTTP server (health checks, and the dashboard where bokeh is
#: installed) on a free port: the default, 8787, may be another cluster's.
_DASHBOARD = ":0"
#: Run in each local worker process as it starts.
_PRELOAD = "harness.sweep.worker"


class ClusterError(HarnessError):
    """The Dask scheduler cannot be reached, or it has no worker."""


@dataclass(frozen=True)
class ClusterInfo:
    """What ran the sweep (for the index page and the summary).

    Attributes
    ----------
    kind : str
        ``local`` (processes), ``in-process`` or ``scheduler``.
    address : str
        The scheduler's address.
    workers : tuple of str
        Worker addresses when the sweep started.
    gpu_workers : tuple of str
        Those offering the ``GPU`` resource.
    dashboard : str or None
        The Dask dashboard's address, when the scheduler serves one.
    """

    kind: str
    address: str
    workers: tuple[str, ...]
    gpu_workers: tuple[str, ...]
    dashboard: str | None = None

    @property
    def gpu_tagged(self) -> bool:
        """Whether renders ask for the ``GPU`` resource."""
        return bool(self.gpu_workers)


def local_gpus() -> int:
    """NVIDIA GPUs the driver lists on this machine (0 without one)."""
    root = Path("/proc/driver/nvidia/gpus")
    try:
        return sum(1 for p in root.iterdir() if p.is_dir())
    except OSError:
        return 0


def _info(client, kind: str) -> ClusterInfo:
    workers = client.scheduler_info(n_workers=-1)["workers"]
    gpu = tuple(sorted(a for a, w in workers.items() if w.get("resources", {}).get(GPU)))
    try:
        dashboard = client.dashboard_link
    except Exception:  # no HTTP service, or a link format Dask cannot fill in
        dashboard = None
    return ClusterInfo(kind, client.scheduler.address, tuple(sorted(workers)), gpu, dashboard)


def _local_cluster(workers: int, gpus: int):
    """A local cluster of ``workers`` process workers, the first ``gpus`` of them
    offering ``GPU=1``."""
    from dask.distributed import LocalCluster  # noqa: PLC0415 - Dask loads only for a sweep

    # The preload makes each worker process ignore SIGINT and use its share of the
    # cores in Dr.Jit and llvmpipe (harness.sweep.worker).
    share = str(max(1, (os.cpu_count() or 1) // workers))
    options = {"threads_per_worker": 1, "processes": True, "host": "127.0.0.1",
               "dashboard_address": _DASHBOARD, "silence_logs": logging.ERROR,
               "preload": [_PRELOAD],
               "env": {THREADS_ENV: share, "LP_NUM_THREADS": share}}
    if not gpus:
        return LocalCluster(n_workers=workers, **options)
    cluster = LocalCluster(n_workers=0, **options)
    for i in range(workers):
        spec = copy.deepcopy(cluster.new_spec)
        if i < gpus:
            spec["options"]["resources"] = {GPU: 1}
        cluster.worker_spec[f"local-{i}"] = spec
    cluster.scale(workers)
    return cluster


def _connect(address: str | None, scheduler_file: str | None, timeout: float):
    from dask.distributed import Client  # noqa: PLC0415 - Dask loads only for a sweep

    where = address or f"the scheduler in {scheduler_file}"
    try:
        if scheduler_file is not None:
            return Client(scheduler_file=scheduler_file, timeout=timeout)
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError, ValueError) as error:
        message = " ".join(str(error).split()) or type(error).__name__
        raise ClusterError(f"cannot reach the Dask scheduler at {where}: {message}") from None


@contextlib.contextmanager
def open_cluster(*, scheduler: str | None = None, scheduler_file: str | None = None,
                 workers: int | None = None, in_process: bool = False,
                 timeout: float = 60.0) -> Iterator[tuple[object, ClusterInfo]]:
    """A connected ``distributed.Client`` and what it runs on (module docstring);
    the client, and a cluster started here, are closed on exit.

    Parameters
    ----------
    scheduler, scheduler_file
        An existing scheduler (at most one); neither: ``DASK_SCHEDULER_ADDRESS``,
        else a local cluster.
    workers
        Process workers of a local cluster (default: one per core).
    in_process
        A local cluster of one worker thread in this process.
    timeout
        Seconds to wait for an existing scheduler to answer, and again for its
        first worker.

    Raises
    ------
    ClusterError
        The scheduler cannot be reached, or no worker joined in time.
    """
    import dask  # noqa: PLC0415 - Dask loads only for a sweep
    from dask.distributed import Client, LocalCluster  # noqa: PLC0415 - Dask, as above

    address = scheduler or dask.config.get("scheduler-address", None)
    with contextlib.ExitStack() as stack:
        if address or scheduler_file:
            client = stack.enter_context(_connect(address, scheduler_file, timeout))
            kind = "scheduler"
            try:
                client.wait_for_workers(1, timeout=timeout)
            except TimeoutError:
                raise ClusterError(f"the Dask scheduler at {client.scheduler.address} has no "
                                   f"worker (waited {timeout:g} s): start one with "
                                   "`dask worker ADDRESS`") from None
        elif in_process:
            cluster = stack.enter_context(LocalCluster(
                n_workers=1, threads_per_worker=1, processes=False,
                dashboard_address=_DASHBOARD, silence_logs=logging.ERROR))
            client = stack.enter_context(Client(cluster))
            kind = "in-process"
        else:
            count = workers or os.cpu_count() or 1
            cluster = stack.enter_context(_local_cluster(count, min(local_gpus(), count)))
            client = stack.enter_context(Client(cluster))
            client.wait_for_workers(count)
            kind = "local"
        yield client, _info(client, kind)


def worker_versions(client, info: ClusterInfo) -> dict:
    """Mitsuba's and Dr.Jit's versions and variant on the workers (one small task on
    each, which also loads Mitsuba there before the first seed).

    Raises
    ------
    ClusterError
        The workers do not all agree: their seeds could not merge into one reference.
    """
    futures = {address: client.submit(mitsuba_versions, workers=[address], pure=False,
                                      key=f"versions-{address}")
               for address in info.workers}
    found = {address: future.result() for address, future in futures.items()}
    distinct = {tuple(sorted(v.items())) for v in found.values()}
    if len(distinct) > 1:
        listed = "; ".join(f"{a}: {v}" for a, v in sorted(found.items()))
        raise ClusterError("the workers run different Mitsuba or Dr.Jit versions or variants "
                           f"({listed}): install the same on every worker and choose the "
                           "same variant on each")
    return next(iter(found.values()))
