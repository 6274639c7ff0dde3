"""Display transforms of the report: the difference maps' scale and false colour.

Luminance and the tone curve (for SSIM and previews) are :mod:`scenes.colour`'s, the
one place the metrics, the renderers and the report take them from.

The difference maps' scale is fixed per scene from the reference alone
(:func:`difference_range`): ± :data:`DIFF_RANGE_FRACTION` of the reference's
:data:`DIFF_RANGE_PERCENTILE` th-percentile luminance, so every method of a scene is
drawn on one scale, known before any method has rendered. False colour marks what
falls outside its scale (:data:`CLIP_ABOVE`, :data:`CLIP_BELOW`) and what is not a
number (:data:`UNDEFINED`) instead of folding it into the ends.
"""

from __future__ import annotations

import numpy as np

from scenes.colour import white_point

__all__ = ["CLIP_ABOVE", "CLIP_BELOW", "DIFF_RANGE_FRACTION", "DIFF_RANGE_PERCENTILE",
           "DIFF_RANGE_RULE", "MARKED_LEVELS", "UNDEFINED", "difference_range", "false_colour"]

#: The difference scale is ± this fraction of the reference's robust maximum luminance.
DIFF_RANGE_FRACTION = 0.25
#: The reference's robust maximum: this percentile of its luminance (the top 0.5 % of
#: pixels, a caustic's hottest texels and fireflies, do not set the scale).
DIFF_RANGE_PERCENTILE = 99.5
#: The rule, as the report states it.
DIFF_RANGE_RULE = (f"{100 * DIFF_RANGE_FRACTION:g} % of the reference's "
                   f"{DIFF_RANGE_PERCENTILE:g}th-percentile luminance")
#: sRGB bytes of values above a false-colour scale (magenta), below it (green) and not
#: a number (mid grey): none is a colour of the diverging or sequential maps used.
CLIP_ABOVE = (255, 0, 255)
CLIP_BELOW = (0, 200, 0)
UNDEFINED = (128, 128, 128)
#: Levels of a colormap whose map marks clipped values: with the three marker colours
#: a map has at most 256 colours, one palette.
MARKED_LEVELS = 256 - 3


def difference_range(reference: np.ndarray, *, mask: np.ndarray | None = None) -> float:
    """The symmetric limit of a scene's difference maps (same units as ``reference``):
    :data:`DIFF_RANGE_FRACTION` × the reference's :data:`DIFF_RANGE_PERCENTILE` th-
    percentile luminance inside ``mask`` (:func:`scenes.colour.white_point`; an all-black reference
    gives 0.25, so the colour bar stays defined). A function of the reference alone,
    so every method of a scene gets the same scale."""
    return DIFF_RANGE_FRACTION * white_point(reference, mask=mask,
                                             percentile=DIFF_RANGE_PERCENTILE)


def false_colour(values: np.ndarray, *, vmin: float, vmax: float,
                 colormap: str = "RdBu_r", mark_clipped: bool = False) -> np.ndarray:
    """Map a scalar image (H, W) to uint8 RGB (H, W, 3) with a matplotlib colormap.

    Use a diverging map (``RdBu_r``, symmetric ``vmin = -vmax``) for signed
    differences and a sequential one (``magma``) for absolute ones; the same
    ``vmin``/``vmax`` must label the colour bar drawn beside it. Without
    ``mark_clipped`` values beyond the scale take its end colours and NaN the colour
    of 0; with it they are drawn in :data:`CLIP_ABOVE` (> ``vmax``),
    :data:`CLIP_BELOW` (< ``vmin``) and :data:`UNDEFINED` (NaN), and the colormap is
    sampled at 253 levels, so that its levels and the three markers fit a 256-colour
    palette (``reports.images.encode_png`` stores such a map losslessly as one); draw
    its colour bar with ``mark_clipped`` too, so that both use the same levels.
    """
    from matplotlib import colormaps  # noqa: PLC0415 - heavy, only when false colour is drawn

    if not vmax > vmin:
        raise ValueError(f"need vmax > vmin, got [{vmin}, {vmax}]")
    scaled = (np.nan_to_num(np.asarray(values, np.float64)) - vmin) / (vmax - vmin)
    cmap = colormaps[colormap].resampled(MARKED_LEVELS) if mark_clipped else colormaps[colormap]
    rgba = cmap(np.clip(scaled, 0.0, 1.0))
    rgb = (rgba[..., :3] * 255 + 0.5).astype(np.uint8)
    if mark_clipped:
        raw = np.asarray(values, np.float64)
        rgb[raw > vmax] = CLIP_ABOVE
        rgb[raw < vmin] = CLIP_BELOW
        rgb[np.isnan(raw)] = UNDEFINED
    return rgb
