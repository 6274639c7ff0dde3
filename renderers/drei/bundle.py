"""The page's one script: ``js/main.mjs`` bundled by esbuild with three.js and
``@pmndrs/vanilla`` from the project's JavaScript workspace (``renderers/web``, whose
``package-lock.json`` pins them; ``python -m renderers.web.install`` runs ``npm ci``).

The bundle is built locally, on first use or by the set-up, into a cache folder keyed
by the SHA-256 of the entry, the lockfile and esbuild's version, so that an edit to
either rebuilds it and nothing is ever fetched: the page loads three.js and the
component from this one file.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
from pathlib import Path

from renderers.web.validator import WORKSPACE
from scenes.errors import HarnessError
from scenes.files import atomic_write_bytes

__all__ = ["ENTRY", "PACKAGES", "DreiSetupError", "bundle_path", "cache_dir", "ensure_bundle",
           "unavailable_reason"]

#: The page's entry module.
ENTRY = Path(__file__).resolve().parent / "js" / "main.mjs"
#: The workspace packages the bundle needs.
PACKAGES = ("three", "@pmndrs/vanilla", "esbuild")
_ESBUILD = WORKSPACE / "node_modules" / ".bin" / "esbuild"
_INSTALL = "npm ci --prefix renderers/web (or: python -m renderers.web.install)"


class DreiSetupError(HarnessError, RuntimeError):
    """The method cannot run here: a missing browser, Node package or bundle; or the
    page failed."""


def unavailable_reason() -> str | None:
    """Why the bundle cannot be built here (the workspace's packages are missing), or
    None."""
    missing = [p for p in PACKAGES if not (WORKSPACE / "node_modules" / p).is_dir()]
    if missing:
        return (f"the JavaScript workspace lacks {', '.join(missing)}: run `{_INSTALL}`")
    if not _ESBUILD.is_file():
        return f"{_ESBUILD} is missing: run `{_INSTALL}`"
    return None


def cache_dir() -> Path:
    """Where bundles are kept: ``$XDG_CACHE_HOME/caustics-harness/drei`` (default
    ``~/.cache``)."""
    root = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(root) / "caustics-harness" / "drei"


def _esbuild_version() -> str:
    done = subprocess.run([str(_ESBUILD), "--version"], capture_output=True, text=True,
                          check=False, timeout=60)
    if done.returncode != 0:
        raise DreiSetupError(f"{_ESBUILD} --version failed: {done.stderr.strip()}")
    return done.stdout.strip()


def bundle_path(*, folder: Path | None = None) -> Path:
    """The bundle's path for the current entry, lockfile and esbuild (built or not)."""
    digest = hashlib.sha256()
    for part in (ENTRY.read_bytes(), (WORKSPACE / "package-lock.json").read_bytes(),
                 _esbuild_version().encode()):
        digest.update(hashlib.sha256(part).digest())
    return (folder or cache_dir()) / f"drei-{digest.hexdigest()[:16]}.js"


def ensure_bundle(*, folder: Path | None = None) -> Path:
    """The bundle, built with esbuild if this entry and lockfile have none yet.

    Raises
    ------
    DreiSetupError
        The workspace's packages are missing, or esbuild failed (its message).
    """
    reason = unavailable_reason()
    if reason:
        raise DreiSetupError(f"drei-caustics cannot bundle its page: {reason}")
    path = bundle_path(folder=folder)
    if path.is_file():
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    # NODE_PATH lets esbuild resolve the bare imports (three, @pmndrs/vanilla) from the
    # workspace's node_modules although the entry lives outside the workspace.
    env = {**os.environ, "NODE_PATH": str(WORKSPACE / "node_modules")}
    done = subprocess.run(
        [str(_ESBUILD), str(ENTRY), "--bundle", "--format=iife", "--platform=browser",
         "--target=chrome110", "--log-level=warning"],
        capture_output=True, env=env, check=False, timeout=300)
    if done.returncode != 0 or not done.stdout:
        raise DreiSetupError(f"esbuild could not bundle {ENTRY}: "
                             f"{done.stderr.decode(errors='replace').strip()}")
    atomic_write_bytes(path, done.stdout)
    return path

