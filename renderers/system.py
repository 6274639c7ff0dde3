"""System packages found on the machine or, as root, installed with apt-get.

One find-or-install path for every package the project needs from Debian
(libLLVM for Dr.Jit, chromium for the report's browser test): look first, install
only when root and allowed, look again, and otherwise raise with the exact command.
"""

from __future__ import annotations

import os
import shutil
import subprocess

from scenes.errors import HarnessError

__all__ = ["SystemSetupError", "find_or_install"]


class SystemSetupError(HarnessError, RuntimeError):
    """A system package is missing and could not be installed; the message says how."""


def _apt_install(package: str) -> None:
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    install = ["apt-get", "install", "-y", "-q", "--no-install-recommends", package]
    # A fresh machine may have no package lists; update only when the install fails.
    if subprocess.run(install, env=env, capture_output=True, check=False).returncode == 0:
        return
    subprocess.run(["apt-get", "update", "-q"], env=env, check=True, capture_output=True)
    subprocess.run(install, env=env, check=True, capture_output=True)


def find_or_install(find, package: str, command: str, *, install: bool, missing: str) -> str:
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


