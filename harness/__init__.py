"""caustics-harness: ground-truth validation of image-space caustics.

The Python API (:mod:`harness.api`: ``load_scene``, ``compare``, ``render_reference``,
``write_report``, ...) is re-exported here on first use, so that ``import harness``
(the command line's start-up, the pytest plugin's load) stays free of the renderers.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

#: Names re-exported from :mod:`harness.api` (imported when first asked for).
_API = ("Comparison", "ComparisonError", "ComparisonSet", "DEFAULT_METHODS", "Failure",
        "OptionError", "bundled_scenes", "compare", "load_scene", "render_reference",
        "write_report")

__all__ = ["DEFAULT_METHODS", "Comparison", "ComparisonError", "ComparisonSet", "Failure",
           "OptionError", "__version__", "bundled_scenes", "compare", "load_scene",
           "render_reference", "write_report"]


def __getattr__(name: str) -> Any:
    if name in _API:
        return getattr(importlib.import_module("harness.api"), name)
    raise AttributeError(f"module 'harness' has no attribute {name!r}")
