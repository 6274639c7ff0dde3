"""Accuracy checks: golden references, bounds, and numerical stability.

The golden references (EXR maps with a SHA-256 manifest) and the bounds file ship
inside this package (``data/``), so ``caustics compare`` finds them from any
working directory.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["GOLDEN_DIR", "THRESHOLDS_FILE"]

_DATA = Path(str(resources.files("harness.checks") / "data"))
#: Bundled golden references (``manifest.json`` and ``<scene>/receiver<i>.exr``).
GOLDEN_DIR = _DATA / "golden"
#: Bundled accuracy bounds, checked against :data:`GOLDEN_DIR`.
THRESHOLDS_FILE = _DATA / "thresholds.toml"
