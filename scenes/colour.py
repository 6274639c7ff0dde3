"""Colour maths shared by the renderers, the metrics and the report: luminance and the
tone curve, in one place.

It lives in the bottom layer because every layer above needs it and the report may
not import the renderers (import-linter's contracts); like :mod:`scenes.files`, it
depends on nothing of the project.

Luminance of linear RGB uses the Rec. 709 weights (:data:`LUMA`):

    Y = 0.2126 R + 0.7152 G + 0.0722 B,

in the units of the image (W/m² for an irradiance map, W m⁻² sr⁻¹ for radiance). It
sets the caustic region (:func:`renderers.results.caustic_region`), the flux ratio and
every scalar map the report draws.

The tone curve maps linear HDR to display values in [0, 1]: for SSIM (which must not
see linear HDR) and for previews. It is fixed per comparison and chosen from the
reference alone (:func:`white_point`), so that the real-time image and the reference
go through exactly the same curve:

    t(x) = srgb( k x / (1 + k x) ),   k = 1 / white,

a Reinhard curve with white point ``white`` (same units as ``x``), followed by the
sRGB transfer function (IEC 61966-2-1). SSIM's ``data_range`` is therefore 1. The
report's page draws the same curve in JavaScript (``reports/static/report.js``),
with the weights it is given from :data:`LUMA`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LUMA", "luminance", "srgb_encode", "tonemap", "white_point"]

#: Rec. 709 luma weights for linear RGB (R, G, B); they sum to 1.
LUMA = np.array([0.2126, 0.7152, 0.0722])
#: The tone curve's white: this percentile of the reference's luminance.
WHITE_PERCENTILE = 99.0


def luminance(image: np.ndarray) -> np.ndarray:
    """Linear luminance Y = :data:`LUMA` · RGB of an (H, W, 3) image, float64, in the
    image's units; (H, W) input is taken as luminance already and returned as is."""
    image = np.asarray(image, np.float64)
    return image if image.ndim == 2 else image @ LUMA


def white_point(reference: np.ndarray, *, mask: np.ndarray | None = None,
                percentile: float = WHITE_PERCENTILE) -> float:
    """The reference's ``percentile`` luminance inside ``mask`` (finite values only):
    the tone curve's white, in the reference's units.

    Falls back to 1.0 for an all-black reference, so the curve stays defined.
    """
    lum = luminance(reference)
    values = lum[mask] if mask is not None else lum.ravel()
    values = values[np.isfinite(values)]
    white = float(np.percentile(values, percentile)) if values.size else 0.0
    return white if white > 0 else 1.0


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) on values clipped to [0, 1]."""
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def tonemap(image: np.ndarray, *, white: float) -> np.ndarray:
    """Reinhard with white point ``white`` (the image's units), then sRGB: display
    values in [0, 1], float64, the shape of ``image``. Negative values count as 0.

    Raises
    ------
    ValueError
        ``white`` is not positive.
    """
    if not white > 0:
        raise ValueError(f"white point must be positive, got {white}")
    x = np.maximum(np.asarray(image, np.float64), 0.0) / white
    return srgb_encode(x / (1.0 + x))
