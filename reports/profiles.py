"""Line profiles through an image: method against reference, with the reference's
standard error, sampled pixel by pixel (no interpolation, so every sample is a value
of the EXR).

Sampling. A line from pixel ``(x0, y0)`` to pixel ``(x1, y1)`` (``x`` the column,
``y`` the row of the array as stored, so of the EXR) takes

    n = max(|x1 − x0|, |y1 − y0|) + 1

samples, one per column or row along the longer axis (a DDA line):

    x_i = x0 + floor(i (x1 − x0) / (n − 1) + 1/2),   y_i likewise,   i = 0 .. n − 1.

The page's JavaScript (``reports/static/profile.js``) uses the same expression in
the same floating-point order, so a profile drawn on the page and this module's
agree sample for sample.

Standard error. The reference is a mean over K seeds; its variance per pixel and
channel is ``Var[mean]`` (``<view>/reference_variance``), so its standard error is
``σ_c = sqrt(Var[mean]_c)``. The luminance ``L = Σ_c w_c E_c`` (Rec. 709 weights
``w``) of correlated channels has

    σ_L ≤ Σ_c w_c σ_c

with equality when the channels are perfectly correlated, as they are for a grey
light carried by the same photons through a non-dispersive object. The upper bound
is reported (never an underestimate, whatever the correlation).

Default profile: the horizontal line, across the whole map, through the maximum of
the reference's luminance inside the caustic region (the whole map when the region
is empty or absent).
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass

import numpy as np

from scenes.colour import LUMA, luminance

__all__ = ["PROFILE_COLUMNS", "Profile", "default_profile", "line_pixels", "peak_pixel",
           "profile_csv", "sample_profile"]

#: Columns of a profile's CSV (values in the image's units; x, y in EXR pixels).
PROFILE_COLUMNS = (
    "sample", "x", "y",
    "method_r", "method_g", "method_b", "method_lum",
    "reference_r", "reference_g", "reference_b", "reference_lum",
    "reference_se_r", "reference_se_g", "reference_se_b", "reference_se_lum",
)


@dataclass(frozen=True)
class Profile:
    """Samples of one line through a view.

    Attributes
    ----------
    x, y : ndarray of int, shape (n,)
        Pixel column and row of each sample (array rows, as in the EXR; receiver
        maps have row 0 at v = vmin).
    method, reference : ndarray of float64, shape (n, 3)
        Linear RGB at those pixels (W m⁻² sr⁻¹ for the camera, W/m² for maps).
    reference_se : ndarray of float64, shape (n, 3), or None
        The reference's standard error ``sqrt(Var[mean])`` at those pixels, same
        units; None when the reference carries no variance.
    """

    x: np.ndarray
    y: np.ndarray
    method: np.ndarray
    reference: np.ndarray
    reference_se: np.ndarray | None = None

    @property
    def method_luminance(self) -> np.ndarray:
        """Rec. 709 luminance of the method, shape (n,)."""
        return self.method @ LUMA

    @property
    def reference_luminance(self) -> np.ndarray:
        """Rec. 709 luminance of the reference, shape (n,)."""
        return self.reference @ LUMA

    @property
    def reference_se_luminance(self) -> np.ndarray | None:
        """Upper bound ``Σ_c w_c σ_c`` of the luminance's standard error (see the
        module docstring), shape (n,); None without variance."""
        return None if self.reference_se is None else self.reference_se @ LUMA


def line_pixels(start: tuple[int, int], end: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Pixels of the line from ``start = (x0, y0)`` to ``end = (x1, y1)``, both
    included (see the module docstring); a line of one point when they coincide.

    Returns
    -------
    x, y : ndarray of int
        Column and row of each sample.
    """
    (x0, y0), (x1, y1) = (int(start[0]), int(start[1])), (int(end[0]), int(end[1]))
    dx, dy = x1 - x0, y1 - y0
    steps = max(abs(dx), abs(dy))
    if steps == 0:
        return np.array([x0]), np.array([y0])
    i = np.arange(steps + 1, dtype=np.float64)
    # floor(t + 1/2) rounds half up, as JavaScript's Math.floor(t + 0.5) does.
    x = x0 + np.floor(i * dx / steps + 0.5).astype(np.int64)
    y = y0 + np.floor(i * dy / steps + 0.5).astype(np.int64)
    return x, y


def _rgb(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image, np.float64)
    return image[..., None].repeat(3, axis=-1) if image.ndim == 2 else image


def sample_profile(method: np.ndarray, reference: np.ndarray,
                   reference_variance: np.ndarray | None = None, *,
                   start: tuple[int, int], end: tuple[int, int]) -> Profile:
    """Sample method, reference and the reference's standard error along a line.

    Parameters
    ----------
    method, reference : ndarray, shape (H, W, 3) or (H, W)
        Linear images in the same units (a scalar image counts as grey).
    reference_variance : ndarray, shape (H, W, 3) or (H, W), optional
        ``Var[mean]`` of the reference per pixel, in units squared; negative
        values (round-off) count as 0.
    start, end : (int, int)
        ``(x, y)`` pixels of the line's ends, inside the image.

    Returns
    -------
    Profile
    """
    method, reference = _rgb(method), _rgb(reference)
    if method.shape != reference.shape:
        raise ValueError(f"shapes differ: method {method.shape}, reference {reference.shape}")
    h, w = reference.shape[:2]
    for name, (px, py) in (("start", start), ("end", end)):
        if not (0 <= px < w and 0 <= py < h):
            raise ValueError(f"{name} {(px, py)} is outside the {w}×{h} image")
    x, y = line_pixels(start, end)
    se = None
    if reference_variance is not None:
        se = np.sqrt(np.maximum(_rgb(reference_variance)[y, x], 0.0))
    return Profile(x=x, y=y, method=method[y, x], reference=reference[y, x], reference_se=se)


def peak_pixel(reference: np.ndarray, *, mask: np.ndarray | None = None) -> tuple[int, int]:
    """``(x, y)`` of the largest finite reference luminance inside ``mask`` (the whole
    image when ``mask`` is None or empty); the first in row-major order on ties."""
    lum = luminance(reference)
    lum = np.where(np.isfinite(lum), lum, -np.inf)
    if mask is not None and np.asarray(mask, bool).any():
        lum = np.where(np.asarray(mask, bool), lum, -np.inf)
    y, x = np.unravel_index(int(np.argmax(lum)), lum.shape)
    return int(x), int(y)


def default_profile(method: np.ndarray, reference: np.ndarray,
                    reference_variance: np.ndarray | None = None, *,
                    mask: np.ndarray | None = None) -> Profile:
    """The horizontal profile across the whole image through :func:`peak_pixel`
    (the caustic's peak when ``mask`` is the caustic region)."""
    _, y = peak_pixel(reference, mask=mask)
    w = np.shape(reference)[1]
    return sample_profile(method, reference, reference_variance, start=(0, y),
                          end=(w - 1, y))


def profile_csv(profile: Profile) -> bytes:
    """The profile as CSV (:data:`PROFILE_COLUMNS`; standard errors empty without
    variance); floats with 9 significant digits, enough to restore a float32."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(PROFILE_COLUMNS)
    m, r, s = profile.method, profile.reference, profile.reference_se
    m_lum, r_lum, s_lum = (profile.method_luminance, profile.reference_luminance,
                           profile.reference_se_luminance)
    for i in range(len(profile.x)):
        errors = ([*s[i], s_lum[i]] if s is not None else [None] * 4)
        values = [*m[i], m_lum[i], *r[i], r_lum[i], *errors]
        writer.writerow([i, int(profile.x[i]), int(profile.y[i]),
                         *("" if v is None else f"{v:.9g}" for v in values)])
    return buffer.getvalue().encode("utf-8")
