"""The root of the harness's typed errors; the CLI turns any of them into exit 1."""

from __future__ import annotations

__all__ = ["HarnessError"]


class HarnessError(Exception):
    """Base of every error the harness raises on purpose (bad input, missing system
    packages, corrupt files, renderer failures). Never a bug."""
