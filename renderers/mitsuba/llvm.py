"""Dr.Jit's LLVM backend: which libLLVM it loads, set explicitly.

Dr.Jit 1.5's LLVM backend aborts on Debian 12's default LLVM 15 ("Cannot select:
fminimum"); Debian's ``libllvm19`` works. We never leave Dr.Jit to guess: the path is
set explicitly in ``DRJIT_LIBLLVM_PATH`` before Dr.Jit is imported.
"""

from __future__ import annotations

import ctypes
import glob
import os

from renderers.system import find_or_install

__all__ = ["LLVM_PACKAGE", "configure_drjit", "cuda_device_present", "ensure_libllvm",
           "find_libllvm"]

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
INSTALL_COMMAND = f"apt-get update && apt-get install -y {LLVM_PACKAGE}"

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


def ensure_libllvm(*, install: bool = True) -> str:
    """Find libLLVM for Dr.Jit, installing Debian's ``libllvm19`` when root and allowed.

    Returns
    -------
    str
        Path of the shared library.

    Raises
    ------
    SystemSetupError
        Not found, and not installable here; the message gives the exact command.
    """
    return find_or_install(
        find_libllvm, LLVM_PACKAGE, INSTALL_COMMAND, install=install,
        missing="Dr.Jit's LLVM backend needs libLLVM >= 16 and none was found")


def configure_drjit(*, install: bool = True) -> str:
    """Set ``DRJIT_LIBLLVM_PATH`` explicitly (before Dr.Jit is imported); return it."""
    path = ensure_libllvm(install=install)
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
