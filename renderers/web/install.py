"""``python -m renderers.web.install``: ``npm ci`` in the project's JavaScript workspace
(this folder), so that ``node_modules/`` holds exactly what ``package-lock.json`` pins,
then the drei-caustics page's bundle (esbuild, from those packages; kept in a cache
folder, ``renderers/drei/bundle.py``). tox's set-up runs it; a machine without npm gets
one clear line saying what to install.
"""

from __future__ import annotations

import shutil
import subprocess
import sys

from renderers.drei.bundle import DreiSetupError, ensure_bundle
from renderers.web.validator import WORKSPACE

__all__ = ["main"]

#: What a machine without npm needs (Debian's packages; any Node.js 18+ with npm does).
NPM_INSTALL_COMMAND = "apt-get install -y nodejs npm"


def main() -> int:
    """Run ``npm ci --prefix <workspace>``; its exit status, or 1 without npm."""
    npm = shutil.which("npm")
    if npm is None:
        print("caustics: npm is not installed: the JavaScript workspace renderers/web (the "
              "glTF validator the export tests run) needs Node.js 18+ with npm "
              f"(Debian: {NPM_INSTALL_COMMAND})", file=sys.stderr)
        return 1
    done = subprocess.run([npm, "ci", "--prefix", str(WORKSPACE), "--no-audit", "--no-fund"],
                          check=False)
    if done.returncode != 0:
        print(f"caustics: npm ci in {WORKSPACE} failed (exit {done.returncode})",
              file=sys.stderr)
        return done.returncode
    try:
        print(f"caustics: drei-caustics page bundled: {ensure_bundle()}")
    except DreiSetupError as error:
        print(f"caustics: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
