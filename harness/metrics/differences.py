"""Difference images and their false-colour rendering.

Conventions: ``test`` is the caustics-mapping image, ``reference`` Mitsuba's; both
(H, W, 3) float arrays in the same units. Differences are per channel.

* signed     d = test − reference
* absolute   |d|
* relative   d / (reference + ε), ε = 0.01 (in the image's units) by default
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "absolute_difference",
    "false_colour",
    "relative_difference",
    "signed_difference",
]


def _pair(test, reference) -> tuple[np.ndarray, np.ndarray]:
    test = np.asarray(test, np.float64)
    reference = np.asarray(reference, np.float64)
    if test.shape != reference.shape:
        raise ValueError(f"shapes differ: test {test.shape}, reference {reference.shape}")
    return test, reference


def signed_difference(test, reference) -> np.ndarray:
    """d = test − reference."""
    test, reference = _pair(test, reference)
    return test - reference


def absolute_difference(test, reference) -> np.ndarray:
    """|test − reference|."""
    return np.abs(signed_difference(test, reference))


def relative_difference(test, reference, *, epsilon: float = 0.01) -> np.ndarray:
    """(test − reference) / (reference + ε); ε keeps dark pixels from dominating."""
    test, reference = _pair(test, reference)
    return (test - reference) / (np.abs(reference) + epsilon)


def false_colour(values: np.ndarray, *, vmin: float, vmax: float,
                 colormap: str = "RdBu_r") -> np.ndarray:
    """Map a scalar image (H, W) to uint8 RGB (H, W, 3) with a matplotlib colormap.

    Use a diverging map (``RdBu_r``, symmetric ``vmin = -vmax``) for signed
    differences and a sequential one (``magma``) for absolute ones; the same
    ``vmin``/``vmax`` must label the colour bar drawn beside it.
    """
    from matplotlib import colormaps  # noqa: PLC0415 - matplotlib is slow to import

    if not vmax > vmin:
        raise ValueError(f"need vmax > vmin, got [{vmin}, {vmax}]")
    scaled = (np.nan_to_num(np.asarray(values, np.float64)) - vmin) / (vmax - vmin)
    rgba = colormaps[colormap](np.clip(scaled, 0.0, 1.0))
    return (rgba[..., :3] * 255 + 0.5).astype(np.uint8)
