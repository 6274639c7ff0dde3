"""The one place that imports Mitsuba and Dr.Jit.

:func:`renderers.mitsuba.llvm.configure_drjit` runs first, so Dr.Jit's LLVM backend finds
the libLLVM it needs (>= 16) instead of guessing; where there is none, the first
:func:`load` raises :class:`renderers.mitsuba.llvm.LibLLVMNotFoundError`, which names
the set-up step (``caustics setup``). Loading never installs anything. Dr.Jit's CUDA
backend compiles through the driver and needs no libLLVM: a forced CUDA variant skips
the step, and so does the choice by device where no libLLVM is found and the driver
reports a CUDA device (an offline GPU machine without libLLVM then traces on
``cuda_ad_rgb``).

The variant is ``cuda_ad_rgb`` where Dr.Jit finds a CUDA device, else ``llvm_ad_rgb``;
the environment variable :data:`VARIANT_ENV` forces one
(``CAUSTICS_MITSUBA_VARIANT=llvm_ad_rgb`` keeps a GPU machine on the CPU). ``scalar_rgb``
is a recorded fallback (the camera image works, the vectorised photon tracer refuses to
run on it: one photon per Python call is unusable). The variant is part of every
reference's cache key.
"""

from __future__ import annotations

import functools
import os
from types import ModuleType

from renderers.mitsuba.bsdf import register
from renderers.mitsuba.llvm import configure_drjit, cuda_device_present, find_libllvm
from scenes.errors import HarnessError

__all__ = ["CUDA_VARIANT", "FALLBACK_VARIANT", "PREFERRED_VARIANT", "VARIANT_ENV",
           "MitsubaError", "load", "versions"]

PREFERRED_VARIANT = "llvm_ad_rgb"
CUDA_VARIANT = "cuda_ad_rgb"
FALLBACK_VARIANT = "scalar_rgb"
#: Names the Mitsuba variant to use, overriding the choice by device.
VARIANT_ENV = "CAUSTICS_MITSUBA_VARIANT"


class MitsubaError(HarnessError, RuntimeError):
    """Mitsuba cannot do what was asked in this environment (message says why)."""


@functools.cache
def load() -> tuple[ModuleType, ModuleType, str]:
    """Import Mitsuba and Dr.Jit, select the variant; return ``(mi, dr, variant)``.

    Raises
    ------
    renderers.mitsuba.llvm.LibLLVMNotFoundError
        The variant needs libLLVM and none is found (nothing is installed: the
        message names ``caustics setup``).
    MitsubaError
        A forced variant Mitsuba cannot use here, or no variant loads.
    """
    forced = os.environ.get(VARIANT_ENV, "").strip()
    if _needs_libllvm(forced):
        configure_drjit()
    # Deferred: Dr.Jit reads DRJIT_LIBLLVM_PATH when imported, and the CLI must start
    # without loading either library.
    import drjit as dr  # noqa: PLC0415 - heavy; needs DRJIT_LIBLLVM_PATH set first
    import mitsuba as mi  # noqa: PLC0415 - heavy; needs DRJIT_LIBLLVM_PATH set first

    if forced:
        try:
            mi.set_variant(forced)
        except (ImportError, AttributeError, RuntimeError, ValueError) as error:
            raise MitsubaError(f"{VARIANT_ENV}={forced}: Mitsuba cannot use this variant "
                               f"here ({error}); available: {', '.join(mi.variants())}"
                               ) from error
        variant = forced
    else:
        variant = _by_device(mi, dr)

    register(mi, dr)
    return mi, dr, variant


def _needs_libllvm(forced: str) -> bool:
    """Whether :func:`load` must settle libLLVM first: not for a forced CUDA variant,
    nor for the choice by device where none is found and a CUDA device is present."""
    if forced:
        return not forced.startswith("cuda_")
    return find_libllvm() is not None or not cuda_device_present()


def _by_device(mi, dr) -> str:
    """``cuda_ad_rgb`` where Dr.Jit has a CUDA device, else ``llvm_ad_rgb``, else the
    scalar fallback."""
    candidates = [PREFERRED_VARIANT, FALLBACK_VARIANT]
    if CUDA_VARIANT in mi.variants() and dr.has_backend(dr.JitBackend.CUDA):
        candidates.insert(0, CUDA_VARIANT)
    for variant in candidates:
        try:
            mi.set_variant(variant)
        except (ImportError, AttributeError, RuntimeError):
            continue
        return variant
    raise MitsubaError(f"none of the Mitsuba variants {candidates} loads here")


def versions() -> dict[str, str]:
    """Mitsuba and Dr.Jit versions, for cache keys and sidecars."""
    mi, dr, variant = load()
    return {"mitsuba": mi.__version__, "drjit": dr.__version__, "variant": variant}
