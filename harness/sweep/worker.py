"""What one worker process keeps between tasks: its name and its GL context.

Dask runs each task on a process worker. Mitsuba's variant is chosen once per
process (``renderers.mitsuba._mi.load`` is cached, and it sets
``DRJIT_LIBLLVM_PATH`` before Dr.Jit is imported, so a worker started by ``dask
worker`` needs nothing in its environment). The OpenGL context is made here, once
per process and thread (an EGL context is current in one thread at a time; a Dask
worker runs its tasks on its own executor threads), and kept for the next task, so
a worker compiles each shader once, not once per row.

The module is also the Dask preload of a local cluster's worker processes
(:func:`dask_setup`). They ignore SIGINT, so a Ctrl-C at the terminal, which the
terminal sends to the whole process group, reaches only the client; the client
cancels the sweep and closes the cluster in order, and no worker prints a traceback.
And they share the machine's cores: with :data:`THREADS_ENV` set (the local cluster
sets it to cores / workers), Dr.Jit's thread pool and llvmpipe's rasteriser threads
(``LP_NUM_THREADS``, set in the worker's environment before its GL context exists)
use that many threads, instead of every worker using every core.
"""

from __future__ import annotations

import os
import signal
import socket
import threading

__all__ = ["LOCAL_WORKER", "THREADS_ENV", "dask_setup", "gl_context", "worker_name"]

#: Threads for Dr.Jit in a local cluster's worker (cores / workers).
THREADS_ENV = "CAUSTICS_WORKER_THREADS"

#: The ``worker`` of a task that ran outside any Dask worker (a direct call).
LOCAL_WORKER = "local"

_state = threading.local()


def worker_name() -> str:
    """The Dask worker running this task: its address (``tcp://10.0.0.5:40123``),
    or ``local (host pid N)`` outside a worker."""
    try:
        from dask.distributed import get_worker  # noqa: PLC0415 - only inside a task

        return str(get_worker().address)
    except (ImportError, ValueError):
        return f"{LOCAL_WORKER} ({socket.gethostname()} pid {os.getpid()})"


def gl_context():
    """This process's (and thread's) moderngl context, made on first use."""
    ctx = getattr(_state, "ctx", None)
    if ctx is None:
        # moderngl loads only in a worker that renders a method.
        from renderers.caustics_mapping.context import create_context  # noqa: PLC0415 - moderngl

        ctx = _state.ctx = create_context()
    return ctx


def dask_setup(worker) -> None:
    """Dask preload hook (``preload=["harness.sweep.worker"]``): the worker process
    ignores SIGINT (module docstring). Only in a process of its own, where the
    worker runs in the main thread; a worker inside the client's process is left as
    it is."""
    del worker  # the hook's signature; nothing of the worker is needed
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    threads = os.environ.get(THREADS_ENV, "").strip()
    if threads:
        # renderers.mitsuba (trimesh, scipy) and Dr.Jit load only in a worker told its
        # thread count; the preload module stays light.
        from renderers.mitsuba import load_mitsuba  # noqa: PLC0415 - Dr.Jit, see above

        _, dr, _ = load_mitsuba()
        dr.set_thread_count(int(threads))
