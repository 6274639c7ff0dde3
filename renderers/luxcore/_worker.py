"""pyluxcore runs in a child process, never in the caller's.

pyluxcore 2.11.2 loads TBB's malloc proxy (``libtbbmalloc_proxy``) with
``RTLD_GLOBAL``; memory that libraries imported afterwards allocate and free then
crosses two allocators ("free(): invalid pointer", e.g. importing scipy.special or
Mitsuba after pyluxcore). A single spawned worker process imports pyluxcore and
renders; the caller sends plain data (:class:`~renderers.luxcore.translate.LuxScene`,
property text) and gets NumPy arrays back. One worker, one render at a time.
"""

from __future__ import annotations

import atexit
import multiprocessing
import time
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool

import numpy as np

from renderers.luxcore import _lux
from renderers.luxcore.errors import LuxCoreError

__all__ = ["run", "shutdown"]

_POOL: ProcessPoolExecutor | None = None
#: How often the session is asked whether it reached its photon count, seconds.
POLL_S = 0.001


def _pool() -> ProcessPoolExecutor:
    global _POOL  # noqa: PLW0603
    if _POOL is None:
        _POOL = ProcessPoolExecutor(max_workers=1,
                                    mp_context=multiprocessing.get_context("spawn"))
    return _POOL


def shutdown() -> None:
    """Stop the worker process (a later call starts a new one)."""
    global _POOL  # noqa: PLW0603
    if _POOL is not None:
        _POOL.shutdown(wait=True)
        _POOL = None


atexit.register(shutdown)


def run(function, *args):
    """Call ``function(*args)`` in the worker and return its result.

    Raises
    ------
    LuxCoreError
        The worker died (a crash inside LuxCore).
    """
    try:
        return _pool().submit(function, *args).result()
    except BrokenProcessPool as error:
        shutdown()
        raise LuxCoreError(f"the LuxCore worker process died: {error}") from None


# --------------------------------------------------------- executed in the worker


def version() -> str:
    """pyluxcore's version (imports it in the worker)."""
    return str(_lux.load().Version())


def render(lux_scene, config: str, film: tuple[int, int]) -> tuple[np.ndarray, int, float]:
    """Render one film; return (raw RGB (H, W, 3) float32, light paths, seconds)."""
    lc = _lux.load()
    scene = lc.Scene()
    for name, mesh in lux_scene.meshes:
        scene.DefineMesh(name,
                         [tuple(p) for p in mesh.positions.astype(float).tolist()],
                         [tuple(f) for f in mesh.faces.astype(int).tolist()],
                         [tuple(n) for n in mesh.normals.astype(float).tolist()],
                         None, None, None)
    props = lc.Properties()
    props.SetFromString(lux_scene.properties)
    cfg = lc.Properties()
    cfg.SetFromString(config)
    try:
        scene.Parse(props)
        session = lc.RenderSession(lc.RenderConfig(cfg, scene))
        start = time.perf_counter()
        session.Start()
        while True:
            time.sleep(POLL_S)
            session.UpdateStats()
            if session.HasDone():
                break
        session.Stop()
        seconds = time.perf_counter() - start
        stats = session.GetStats()
        traced = int(stats.Get("stats.renderengine.total.samplecount").GetFloat())
        w, h = film
        raw = np.zeros((h, w, 3), np.float32)
        session.GetFilm().GetOutputFloat(lc.FilmOutputType.RGB, raw)
    except RuntimeError as error:
        tail = "\n".join(list(_lux.LOG)[-5:])
        raise LuxCoreError(f"LuxCore failed: {error}\n{tail}") from None
    return raw, traced, seconds
