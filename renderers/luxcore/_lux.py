"""The one place that imports pyluxcore (LuxCoreRender's Python binding); only the
render worker process (:mod:`renderers.luxcore._worker`) calls :func:`load`.

pyluxcore prints a report of the shared libraries it loads when it is imported;
that report is kept off stdout. :func:`load` initialises LuxCore once with a log
handler that keeps LuxCore's own log in :data:`LOG` (the last lines, for error
messages) instead of printing it.
"""

from __future__ import annotations

import atexit
import collections
import contextlib
import functools
import io
from types import ModuleType

from scenes.errors import HarnessError

__all__ = ["LOG", "LuxCoreUnavailable", "load", "version"]

#: The last lines LuxCore logged (newest last).
LOG: collections.deque[str] = collections.deque(maxlen=200)


class LuxCoreUnavailable(HarnessError, ImportError):
    """pyluxcore cannot be imported in this environment (message says why)."""


def _keep(message: str) -> None:
    LOG.append(message)


@functools.cache
def load() -> ModuleType:
    """Import and initialise pyluxcore; return the module.

    Raises
    ------
    LuxCoreUnavailable
        pyluxcore is not installed or its shared libraries do not load.
    """
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            import pyluxcore  # noqa: PLC0415 - optional extra `crosscheck`; worker process only
    except ImportError as error:
        raise LuxCoreUnavailable(
            f"pyluxcore is not importable ({error}); install the extra: "
            "pip install 'caustics-harness[crosscheck]'"
        ) from None
    pyluxcore.Init(_keep)
    # A Python log handler still registered while the interpreter finalises makes
    # LuxCore call into a dead interpreter (fatal error at exit): drop it first.
    atexit.register(pyluxcore.SetLogHandler, None)
    return pyluxcore


def version() -> str:
    """pyluxcore's version string."""
    return str(load().Version())
