"""System packages the renderers need: found on the machine, never installed here.

Importing or using a renderer never runs a package manager. Where a system package
is missing, first use raises :class:`SystemSetupError` naming the command that
installs it: :data:`SETUP_COMMAND` (``caustics setup``, the same code as ``python -m
harness.system``, the explicit set-up step that tox runs first), or the package
manager's own command for those who install by hand.
"""

from __future__ import annotations

from scenes.errors import HarnessError

__all__ = ["SETUP_COMMAND", "SystemSetupError"]

#: The explicit set-up step: finds, and as root installs, every system package.
SETUP_COMMAND = "caustics setup"


class SystemSetupError(HarnessError, RuntimeError):
    """A system package is missing (and, in the set-up step, could not be installed);
    the message names the command that installs it."""
