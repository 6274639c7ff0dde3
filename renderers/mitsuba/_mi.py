"""The one place that imports Mitsuba and Dr.Jit.

:func:`renderers.mitsuba.llvm.configure_drjit` runs first, so Dr.Jit's LLVM backend finds
the libLLVM it needs (>= 16) instead of guessing. The variant is ``llvm_ad_rgb``;
``scalar_rgb`` is a recorded fallback (the camera image works, the vectorised
photon tracer refuses to run on it: one photon per Python call is unusable).
"""

from __future__ import annotations

import functools
from types import ModuleType

from renderers.mitsuba.bsdf import register
from renderers.mitsuba.llvm import configure_drjit
from scenes.errors import HarnessError

__all__ = ["FALLBACK_VARIANT", "PREFERRED_VARIANT", "MitsubaError", "load", "versions"]

PREFERRED_VARIANT = "llvm_ad_rgb"
FALLBACK_VARIANT = "scalar_rgb"


class MitsubaError(HarnessError, RuntimeError):
    """Mitsuba cannot do what was asked in this environment (message says why)."""


@functools.cache
def load() -> tuple[ModuleType, ModuleType, str]:
    """Import Mitsuba and Dr.Jit, select the variant; return ``(mi, dr, variant)``."""
    configure_drjit()
    # Deferred: Dr.Jit reads DRJIT_LIBLLVM_PATH when imported, and the CLI must start
    # without loading either library.
    import drjit as dr  # noqa: PLC0415 - heavy; needs DRJIT_LIBLLVM_PATH set first
    import mitsuba as mi  # noqa: PLC0415 - heavy; needs DRJIT_LIBLLVM_PATH set first

    try:
        mi.set_variant(PREFERRED_VARIANT)
        variant = PREFERRED_VARIANT
    except (ImportError, AttributeError, RuntimeError):
        mi.set_variant(FALLBACK_VARIANT)
        variant = FALLBACK_VARIANT

    register(mi, dr)
    return mi, dr, variant


def versions() -> dict[str, str]:
    """Mitsuba and Dr.Jit versions, for cache keys and sidecars."""
    mi, dr, variant = load()
    return {"mitsuba": mi.__version__, "drjit": dr.__version__, "variant": variant}
