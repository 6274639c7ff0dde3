"""``caustics setup``: find, and as root install, the system packages the harness needs
(:func:`harness.system.set_up`; ``python -m harness.system`` is the same command).

The only command that installs anything: importing the harness or loading a
renderer never does.
"""

from __future__ import annotations

import argparse

from harness.system import set_up

__all__ = ["setup"]


def setup(args: argparse.Namespace) -> int:
    """Install (or, with ``--check``, only look for) libLLVM and chromium; 0 when
    everything needed is there, else :class:`renderers.system.SystemSetupError`
    (exit 1, its message naming the command)."""
    set_up(install=not args.check)
    return 0
