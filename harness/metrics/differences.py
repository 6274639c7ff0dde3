"""Difference images (their false-colour rendering is :func:`reports.display.false_colour`).

Conventions: ``method`` is the caustics-mapping image, ``reference`` Mitsuba's; both
(H, W, 3) float arrays in the same units. Differences are per channel.

* signed     d = method − reference
* absolute   |d|
* relative   d / (reference + ε), ε = 0.01 (in the image's units) by default
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "absolute_difference",
    "relative_difference",
    "signed_difference",
]


def _pair(method, reference) -> tuple[np.ndarray, np.ndarray]:
    method = np.asarray(method, np.float64)
    reference = np.asarray(reference, np.float64)
    if method.shape != reference.shape:
        raise ValueError(f"shapes differ: method {method.shape}, reference {reference.shape}")
    return method, reference


def signed_difference(method, reference) -> np.ndarray:
    """d = method − reference."""
    method, reference = _pair(method, reference)
    return method - reference


def absolute_difference(method, reference) -> np.ndarray:
    """|method − reference|."""
    return np.abs(signed_difference(method, reference))


def relative_difference(method, reference, *, epsilon: float = 0.01) -> np.ndarray:
    """(method − reference) / (reference + ε); ε keeps dark pixels from dominating."""
    method, reference = _pair(method, reference)
    return (method - reference) / (np.abs(reference) + epsilon)
