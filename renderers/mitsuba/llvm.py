"""Dr.Jit's LLVM backend: which libLLVM it loads, set explicitly, never installed.

Dr.Jit 1.5's LLVM backend aborts on Debian 12's default LLVM 15 ("Cannot select:
fminimum"); Debian's ``libllvm19`` works. We never leave Dr.Jit to guess: the path is
set explicitly in ``DRJIT_LIBLLVM_PATH`` before Dr.Jit is imported.

Nothing here installs: a missing libLLVM is :class:`LibLLVMNotFoundError` at first use,
which names the set-up step (``caustics setup``, as root) and the manual command.
Installing is :func:`harness.system.ensure_libllvm`'s alone.
"""

from __future__ import annotations

import ctypes
import glob
import os

from renderers.system import SETUP_COMMAND, SystemSetupError

__all__ = ["DEBIAN_LIBLLVM", "INSTALL_COMMAND", "LLVM_GLOBS", "LLVM_PACKAGE",
           "LibLLVMNotFoundError", "configure_drjit", "cuda_device_present", "find_libllvm",
           "missing_message"]

#: Debian package that provides a libLLVM Dr.Jit 1.5 accepts.
LLVM_PACKAGE = "libllvm19"
#: Where Debian installs it, newest first; versions below 16 are refused.
LLVM_GLOBS = (
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.19*",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so*",
    "/usr/lib/aarch64-linux-gnu/libLLVM.so.19*",
    "/usr/lib/aarch64-linux-gnu/libLLVM-19.so*",
    "/usr/lib/llvm-19/lib/libLLVM*.so*",
)
#: The package manager's command (as root), for the set-up step and for messages.
INSTALL_COMMAND = f"apt-get update && apt-get install -y {LLVM_PACKAGE}"
#: Where Debian's package puts the library on x86-64: the value to give
#: ``DRJIT_LIBLLVM_PATH`` after a manual install.
DEBIAN_LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


class LibLLVMNotFoundError(SystemSetupError):
    """No libLLVM >= 16 for Dr.Jit's LLVM backend; the message names the set-up step."""


def find_libllvm() -> str | None:
    """Path of a usable libLLVM (>= 16), honouring an existing ``DRJIT_LIBLLVM_PATH``."""
    preset = os.environ.get("DRJIT_LIBLLVM_PATH")
    if preset and os.path.isfile(preset):
        return preset
    for pattern in LLVM_GLOBS:
        hits = sorted(glob.glob(pattern))
        if hits:
            return hits[0]
    return None


def missing_message() -> str:
    """What to do when :func:`find_libllvm` finds nothing: the set-up step, the manual
    install with the path to set, and the CUDA variant that needs no libLLVM."""
    preset = os.environ.get("DRJIT_LIBLLVM_PATH")
    where = (f"DRJIT_LIBLLVM_PATH={preset} is not a file, and " if preset else "")
    return (f"Dr.Jit's LLVM backend needs libLLVM >= 16 and none was found ({where}"
            f"nothing matches {', '.join(LLVM_GLOBS) or 'no search path'}); install "
            f"it with `{SETUP_COMMAND}` (as root), or `{INSTALL_COMMAND}` and then "
            f"DRJIT_LIBLLVM_PATH={DEBIAN_LIBLLVM}; on an NVIDIA GPU, "
            "CAUSTICS_MITSUBA_VARIANT=cuda_ad_rgb needs no libLLVM")


def configure_drjit() -> str:
    """Set ``DRJIT_LIBLLVM_PATH`` explicitly (before Dr.Jit is imported); return it.

    Returns
    -------
    str
        Path of the shared library.

    Raises
    ------
    LibLLVMNotFoundError
        None found; the message names ``caustics setup`` and the manual command.
        Nothing is installed.
    """
    path = find_libllvm()
    if path is None:
        raise LibLLVMNotFoundError(missing_message())
    os.environ["DRJIT_LIBLLVM_PATH"] = path
    return path


def cuda_device_present() -> bool:
    """Whether the NVIDIA driver reports a CUDA device: ``cuInit`` and
    ``cuDeviceGetCount`` of ``libcuda.so.1`` through ctypes, without importing Dr.Jit
    (which must not be imported before ``DRJIT_LIBLLVM_PATH`` is settled). False where
    the driver library is missing or reports no device."""
    try:
        driver = ctypes.CDLL("libcuda.so.1")
    except OSError:
        return False
    count = ctypes.c_int(0)
    return (driver.cuInit(0) == 0 and driver.cuDeviceGetCount(ctypes.byref(count)) == 0
            and count.value > 0)
