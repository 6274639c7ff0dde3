"""System packages the harness needs, found or installed, and Dr.Jit's LLVM path.

Also Debian's ``chromium``, the browser the report's browser test drives through
Playwright (``executable_path="/usr/bin/chromium"``; Playwright's own browser
downloads are never used).

Dr.Jit 1.5's LLVM backend aborts on Debian 12's default LLVM 15 ("Cannot select:
fminimum"); Debian's ``libllvm19`` works. We never leave Dr.Jit to guess: the path is
set explicitly in ``DRJIT_LIBLLVM_PATH`` before Dr.Jit is imported.
"""

from __future__ import annotations

import glob
import os
import shutil
import subprocess
import sys

from harness.errors import HarnessError

__all__ = [
    "SystemSetupError",
    "configure_drjit",
    "ensure_chromium",
    "ensure_libllvm",
    "find_libllvm",
    "main",
]

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
#: Debian package and binary of the browser the report's browser test uses.
CHROMIUM_PACKAGE = "chromium"
CHROMIUM_PATH = "/usr/bin/chromium"
CHROMIUM_INSTALL_COMMAND = f"apt-get update && apt-get install -y {CHROMIUM_PACKAGE}"


class SystemSetupError(HarnessError, RuntimeError):
    """A system package is missing and could not be installed; the message says how."""


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


def _apt_install(package: str) -> None:
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    install = ["apt-get", "install", "-y", "-q", "--no-install-recommends", package]
    # A fresh machine may have no package lists; update only when the install fails.
    if subprocess.run(install, env=env, capture_output=True, check=False).returncode == 0:
        return
    subprocess.run(["apt-get", "update", "-q"], env=env, check=True, capture_output=True)
    subprocess.run(install, env=env, check=True, capture_output=True)


def _find_or_install(find, package: str, command: str, *, install: bool, missing: str) -> str:
    """``find()``, else apt-install ``package`` (root and ``install`` only) and find
    again; SystemSetupError with the exact ``command`` when that is not possible."""
    path = find()
    if path:
        return path
    can_install = install and hasattr(os, "geteuid") and os.geteuid() == 0
    if can_install and shutil.which("apt-get"):
        try:
            _apt_install(package)
        except subprocess.CalledProcessError as error:
            raise SystemSetupError(f"installing {package} failed ({error}); run: {command}") \
                from None
        path = find()
        if path:
            return path
    raise SystemSetupError(f"{missing}; as root run: {command}")


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
    return _find_or_install(
        find_libllvm, LLVM_PACKAGE, INSTALL_COMMAND, install=install,
        missing="Dr.Jit's LLVM backend needs libLLVM >= 16 and none was found")


def ensure_chromium(*, install: bool = True) -> str:
    """Find Debian's chromium for the browser test, apt-installing it when root and allowed.

    Returns
    -------
    str
        Path of the browser binary (``/usr/bin/chromium``).

    Raises
    ------
    SystemSetupError
        Not found, and not installable here; the message gives the exact command.
    """
    return _find_or_install(
        lambda: CHROMIUM_PATH if os.path.isfile(CHROMIUM_PATH) else None,
        CHROMIUM_PACKAGE, CHROMIUM_INSTALL_COMMAND, install=install,
        missing=f"the report's browser test needs {CHROMIUM_PATH} and it was not found")


def configure_drjit(*, install: bool = True) -> str:
    """Set ``DRJIT_LIBLLVM_PATH`` explicitly (before Dr.Jit is imported); return it."""
    path = ensure_libllvm(install=install)
    os.environ["DRJIT_LIBLLVM_PATH"] = path
    return path


def main() -> int:
    """``python -m harness.system``: install/check system packages; print what was found.

    A missing libLLVM is an error. A missing chromium is an error on CI (``CI``
    set, where the browser test must run) and a warning elsewhere (the browser
    test then skips and says why).
    """
    try:
        path = configure_drjit(install=True)
    except SystemSetupError as error:
        print(f"caustics: {error}", file=sys.stderr)
        return 1
    print(f"libLLVM for Dr.Jit: {path}")
    try:
        print(f"chromium for the report's browser test: {ensure_chromium(install=True)}")
    except SystemSetupError as error:
        if os.environ.get("CI"):
            print(f"caustics: {error}", file=sys.stderr)
            return 1
        print(f"caustics: warning: {error}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
