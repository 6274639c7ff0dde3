"""Display transforms: tone mapping (for SSIM and previews) and false colour.

Tone mapping is for metrics that must not see linear HDR (SSIM) and for previews.

The map is fixed per comparison, chosen from the reference alone, so that both the
real-time image and the reference go through exactly the same curve:

    t(x) = srgb( k x / (1 + k x) ),   k = 1 / white,

a Reinhard curve with white point ``white`` (W m⁻² sr⁻¹ or W/m²), followed by the
sRGB transfer function. Output is in [0, 1], so SSIM's ``data_range`` is 1.
"""

from __future__ import annotations

import numpy as np

__all__ = ["false_colour", "luminance", "srgb_encode", "tonemap", "white_point"]

#: Rec. 709 luma weights for linear RGB.
LUMA = np.array([0.2126, 0.7152, 0.0722])


def luminance(image: np.ndarray) -> np.ndarray:
    """Linear luminance of an (H, W, 3) image; (H, W) input is returned as is."""
    image = np.asarray(image, np.float64)
    return image if image.ndim == 2 else image @ LUMA


def white_point(reference: np.ndarray, *, mask: np.ndarray | None = None,
                percentile: float = 99.0) -> float:
    """The reference's ``percentile`` luminance inside ``mask``: the tone curve's white.

    Falls back to 1.0 for an all-black reference, so the curve stays defined.
    """
    lum = luminance(reference)
    values = lum[mask] if mask is not None else lum.ravel()
    values = values[np.isfinite(values)]
    white = float(np.percentile(values, percentile)) if values.size else 0.0
    return white if white > 0 else 1.0


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) on values in [0, 1]."""
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def tonemap(image: np.ndarray, *, white: float) -> np.ndarray:
    """Reinhard with white point ``white``, then sRGB: values in [0, 1], float64."""
    if not white > 0:
        raise ValueError(f"white point must be positive, got {white}")
    x = np.maximum(np.asarray(image, np.float64), 0.0) / white
    return srgb_encode(x / (1.0 + x))


def false_colour(values: np.ndarray, *, vmin: float, vmax: float,
                 colormap: str = "RdBu_r") -> np.ndarray:
    """Map a scalar image (H, W) to uint8 RGB (H, W, 3) with a matplotlib colormap.

    Use a diverging map (``RdBu_r``, symmetric ``vmin = -vmax``) for signed
    differences and a sequential one (``magma``) for absolute ones; the same
    ``vmin``/``vmax`` must label the colour bar drawn beside it.
    """
    from matplotlib import colormaps  # noqa: PLC0415 - heavy, only when false colour is drawn

    if not vmax > vmin:
        raise ValueError(f"need vmax > vmin, got [{vmin}, {vmax}]")
    scaled = (np.nan_to_num(np.asarray(values, np.float64)) - vmin) / (vmax - vmin)
    rgba = colormaps[colormap](np.clip(scaled, 0.0, 1.0))
    return (rgba[..., :3] * 255 + 0.5).astype(np.uint8)
