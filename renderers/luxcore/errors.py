"""Errors of the LuxCore cross-check renderer."""

from __future__ import annotations

from scenes.errors import HarnessError

__all__ = ["LuxCoreError"]


class LuxCoreError(HarnessError, RuntimeError):
    """LuxCore failed to render (the message carries its last log lines)."""
