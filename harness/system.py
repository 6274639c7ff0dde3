"""The set-up step: the system packages the harness needs, found or installed (as
root), and what was found. ``caustics setup`` and ``python -m harness.system`` (which
tox runs before every environment) are this one module.

* Debian's ``libllvm19`` for Dr.Jit's LLVM backend (:mod:`renderers.mitsuba.llvm`);
* Debian's ``chromium``, the browser the report's browser test drives through
  Playwright (``executable_path="/usr/bin/chromium"``; Playwright's own browser
  downloads are never used).

This is the only module that runs a package manager, and only when called: importing
the harness or loading a renderer never installs anything (a missing package is a
typed error at first use naming ``caustics setup``).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import warnings
from collections.abc import Callable

from renderers.mitsuba.llvm import (
    INSTALL_COMMAND,
    LLVM_PACKAGE,
    configure_drjit,
    cuda_device_present,
    find_libllvm,
    missing_message,
)
from renderers.system import SystemSetupError

__all__ = ["ensure_chromium", "ensure_libllvm", "find_or_install", "main", "set_up"]

#: Debian package and binary of the browser the report's browser test uses.
CHROMIUM_PACKAGE = "chromium"
CHROMIUM_PATH = "/usr/bin/chromium"
CHROMIUM_INSTALL_COMMAND = f"apt-get update && apt-get install -y {CHROMIUM_PACKAGE}"


def _apt_install(package: str) -> None:
    """``apt-get install`` one Debian package, non-interactively (root only)."""
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    install = ["apt-get", "install", "-y", "-q", "--no-install-recommends", package]
    # A fresh machine may have no package lists; update only when the install fails.
    if subprocess.run(install, env=env, capture_output=True, check=False).returncode == 0:
        return
    subprocess.run(["apt-get", "update", "-q"], env=env, check=True, capture_output=True)
    subprocess.run(install, env=env, check=True, capture_output=True)


def find_or_install(find: Callable[[], str | None], package: str, command: str, *,
                    install: bool, missing: str) -> str:
    """``find()``, else apt-install ``package`` (root and ``install`` only) and find
    again; :class:`SystemSetupError` with the exact ``command`` when that is not
    possible."""
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
    """Find libLLVM for Dr.Jit, installing Debian's ``libllvm19`` when root and
    ``install``, and set ``DRJIT_LIBLLVM_PATH`` to it.

    Returns
    -------
    str
        Path of the shared library.

    Raises
    ------
    SystemSetupError
        Not found, and not installable here; the message gives the exact command.
    """
    find_or_install(find_libllvm, LLVM_PACKAGE, INSTALL_COMMAND, install=install,
                    missing=missing_message())
    return configure_drjit()


def ensure_chromium(*, install: bool = True) -> str:
    """Find Debian's chromium for the browser test, apt-installing it when root and
    ``install``.

    Returns
    -------
    str
        Path of the browser binary (``/usr/bin/chromium``).

    Raises
    ------
    SystemSetupError
        Not found, and not installable here; the message gives the exact command.
    """
    return find_or_install(
        lambda: CHROMIUM_PATH if os.path.isfile(CHROMIUM_PATH) else None,
        CHROMIUM_PACKAGE, CHROMIUM_INSTALL_COMMAND, install=install,
        missing=f"the report's browser test needs {CHROMIUM_PATH} and it was not found")


def set_up(*, install: bool = True) -> None:
    """Find, and with ``install`` (as root) install, each system package; print what
    was found, one line each on stdout.

    A missing libLLVM is an error, except where a CUDA device is present: Mitsuba
    then traces on ``cuda_ad_rgb``, which needs none, and a warning says that
    ``llvm_ad_rgb`` is unavailable. A missing chromium is an error on CI (``CI``
    set, where the browser test must run) and a warning elsewhere (the browser
    test then skips and says why).

    Raises
    ------
    SystemSetupError
        A package that must be there is missing; the message names the command.
    """
    try:
        print(f"libLLVM for Dr.Jit: {ensure_libllvm(install=install)}")
    except SystemSetupError as error:
        if not cuda_device_present():
            raise
        warnings.warn(f"{error}; a CUDA device is present, so Mitsuba traces on "
                      "cuda_ad_rgb and llvm_ad_rgb is unavailable", stacklevel=2)
    try:
        print(f"chromium for the report's browser test: {ensure_chromium(install=install)}")
    except SystemSetupError as error:
        if os.environ.get("CI"):
            raise
        warnings.warn(str(error), stacklevel=2)


def main(argv: list[str] | None = None) -> int:
    """``python -m harness.system [--check]``: ``caustics setup``, the same code and
    the same exit status (0 done, 1 a package is missing)."""
    from harness.cli import main as cli_main  # noqa: PLC0415 - the CLI dispatches here

    return cli_main(["setup", *(sys.argv[1:] if argv is None else argv)])


if __name__ == "__main__":
    raise SystemExit(main())
