"""``python -m harness.system``: the system packages the harness needs, found or
installed (as root), and what was found.

* Debian's ``libllvm19`` for Dr.Jit's LLVM backend (:mod:`renderers.mitsuba.llvm`);
* Debian's ``chromium``, the browser the report's browser test drives through
  Playwright (``executable_path="/usr/bin/chromium"``; Playwright's own browser
  downloads are never used).
"""

from __future__ import annotations

import os
import sys

from renderers.mitsuba.llvm import configure_drjit, cuda_device_present
from renderers.system import SystemSetupError, find_or_install

__all__ = ["ensure_chromium", "main"]

#: Debian package and binary of the browser the report's browser test uses.
CHROMIUM_PACKAGE = "chromium"
CHROMIUM_PATH = "/usr/bin/chromium"
CHROMIUM_INSTALL_COMMAND = f"apt-get update && apt-get install -y {CHROMIUM_PACKAGE}"



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
    return find_or_install(
        lambda: CHROMIUM_PATH if os.path.isfile(CHROMIUM_PATH) else None,
        CHROMIUM_PACKAGE, CHROMIUM_INSTALL_COMMAND, install=install,
        missing=f"the report's browser test needs {CHROMIUM_PATH} and it was not found")


def main() -> int:
    """``python -m harness.system``: install/check system packages; print what was found.

    A missing libLLVM is an error, except where a CUDA device is present: Mitsuba
    then traces on ``cuda_ad_rgb``, which needs none, and a warning says that
    ``llvm_ad_rgb`` is unavailable. A missing chromium is an error on CI (``CI``
    set, where the browser test must run) and a warning elsewhere (the browser
    test then skips and says why).
    """
    try:
        print(f"libLLVM for Dr.Jit: {configure_drjit(install=True)}")
    except SystemSetupError as error:
        if not cuda_device_present():
            print(f"caustics: {error}", file=sys.stderr)
            return 1
        print(f"caustics: warning: {error}; a CUDA device is present, so Mitsuba traces "
              "on cuda_ad_rgb and llvm_ad_rgb is unavailable", file=sys.stderr)
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
