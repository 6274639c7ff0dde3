"""Pixels for the report: PNG encoding, RGBE-packed HDR previews, false-colour maps,
colour bars and thumbnails.

Tone mapping and false colour are not reimplemented here: the tone curve is
:func:`scenes.colour.tonemap`, the one the metrics use for SSIM, and false colour
:func:`reports.display.false_colour`, so the report shows exactly the curve the
metrics used.

HDR previews for the exposure control are shipped to the browser as one RGB PNG
holding Ward's RGBE encoding (Graphics Gems II, 1991) in two stacked halves:

* rows ``0 .. H-1``   (top half):    mantissas R, G, B (bytes),
* rows ``H .. 2H-1``  (bottom half): the shared exponent E in all three channels,

so that ``value = (byte + 0.5) · 2^(E − 136)`` per channel, and 0 where E = 0. The
PNG has no alpha channel on purpose: a canvas stores premultiplied alpha, which
would destroy mantissas next to a small alpha. The relative precision is about
2⁻⁸ of the pixel's largest channel, plenty for display.
"""

from __future__ import annotations

import base64
import io

import numpy as np
from PIL import Image

from reports.display import false_colour
from scenes.colour import luminance, tonemap

__all__ = [
    "colour_bar_png",
    "data_uri",
    "decode_rgbe_stack",
    "downsample",
    "encode_png",
    "encode_rgbe_stack",
    "false_colour_png",
    "float32_base64",
    "lookup_table",
    "mask_png",
    "tonemapped_png",
]

#: Colormaps of each map kind (shared with the colour bars).
COLORMAPS = {"signed": "RdBu_r", "ssim": "viridis", "flip": "magma"}
#: Colormap of the page's false-colour view of linear images (log luminance).
IRRADIANCE_COLORMAP = "inferno"


def encode_png(rgb: np.ndarray, *, compress_level: int = 6, palette: bool = False) -> bytes:
    """PNG bytes of a uint8 (H, W, 3) or (H, W) array (no gamma or colour chunks).

    With ``palette``, an RGB image of at most 256 distinct colours (a false-colour
    map: one colormap's levels and the clip markers) is stored as a palette image,
    losslessly: the same pixels in about a third of the bytes. Data images that a
    canvas decodes (RGBE stacks) stay RGB.
    """
    array = np.ascontiguousarray(rgb, dtype=np.uint8)
    buffer = io.BytesIO()
    image = Image.fromarray(array)
    if palette and array.ndim == 3:
        # One 24-bit key per pixel, r·2^16 + g·2^8 + b: its numeric order is the
        # colours' lexicographic order, and a 1-D unique is far cheaper than one over rows.
        rgb24 = array.reshape(-1, 3).astype(np.uint32)
        keys = (rgb24[:, 0] << 16) | (rgb24[:, 1] << 8) | rgb24[:, 2]
        codes, index = np.unique(keys, return_inverse=True)
        if len(codes) <= 256:
            colours = np.stack([codes >> 16, (codes >> 8) & 255, codes & 255], axis=-1)
            image = Image.fromarray(index.reshape(array.shape[:2]).astype(np.uint8))
            image.putpalette(colours.astype(np.uint8).tobytes())
    image.save(buffer, format="PNG", compress_level=compress_level)
    return buffer.getvalue()


def data_uri(data: bytes, *, mime: str = "image/png") -> str:
    """``data:`` URI of ``data`` (base64)."""
    return f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"


def float32_base64(values: np.ndarray) -> str:
    """Base64 of ``values`` as little-endian float32, C order (what the page's
    JavaScript reads back into a ``Float32Array``: 4 bytes per value, 4/3 of that
    in base64)."""
    return base64.b64encode(np.ascontiguousarray(values, "<f4").tobytes()).decode("ascii")


def lookup_table(colormap: str = IRRADIANCE_COLORMAP, *, size: int = 256) -> bytes:
    """``size`` RGB byte triplets of ``colormap`` from 0 to 1, drawn with
    :func:`false_colour`, so the page's false colour is the Python one."""
    ramp = np.linspace(0.0, 1.0, size)[None, :]
    return false_colour(ramp, vmin=0.0, vmax=1.0, colormap=colormap).tobytes()


def downsample(image: np.ndarray, *, max_size: int) -> tuple[np.ndarray, int]:
    """Box-filter ``image`` by the smallest integer factor that fits ``max_size``.

    Averaging (not picking) keeps the mean radiance, so an HDR preview still
    shows the right energy. Edge rows/columns that do not fill a whole box are
    dropped.

    Returns
    -------
    ndarray
        The downsampled image (float64 for float input, same dtype otherwise is
        not guaranteed: booleans become the fraction of True in each box).
    int
        The factor (1 = unchanged).
    """
    h, w = image.shape[:2]
    factor = max(1, -(-max(h, w) // max_size))
    if factor == 1:
        return image, 1
    hh, ww = (h // factor) * factor, (w // factor) * factor
    cropped = np.asarray(image[:hh, :ww], np.float64)
    shape = (hh // factor, factor, ww // factor, factor, *image.shape[2:])
    return cropped.reshape(shape).mean(axis=(1, 3)), factor


def encode_rgbe_stack(image: np.ndarray) -> np.ndarray:
    """Pack a linear HDR (H, W, 3) image into the uint8 (2H, W, 3) RGBE stack above.

    Negative and non-finite values are clamped to 0 (they cannot be displayed).
    """
    rgb = np.nan_to_num(np.asarray(image, np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    rgb = np.maximum(rgb, 0.0)
    peak = rgb.max(axis=-1)
    mantissa, exponent = np.frexp(peak)  # peak = mantissa · 2^exponent, mantissa in [0.5, 1)
    visible = peak > 1e-32
    scale = np.where(visible, mantissa * 256.0 / np.where(visible, peak, 1.0), 0.0)
    top = np.clip(np.floor(rgb * scale[..., None]), 0, 255)
    e = np.where(visible, np.clip(exponent + 128, 1, 255), 0)
    # An exponent clipped at 1 (values below 2^-127) or 255 saturates; both are
    # far outside any radiance the harness produces.
    bottom = np.repeat(e[..., None], 3, axis=-1)
    return np.concatenate([top, bottom], axis=0).astype(np.uint8)


def decode_rgbe_stack(stack: np.ndarray) -> np.ndarray:
    """Inverse of :func:`encode_rgbe_stack` (what the page's JavaScript computes)."""
    stack = np.asarray(stack)
    h = stack.shape[0] // 2
    top, e = stack[:h].astype(np.float64), stack[h:, :, 0].astype(np.float64)
    factor = np.where(e > 0, np.ldexp(1.0, (e - 136).astype(int)), 0.0)
    return (top + 0.5) * factor[..., None]


def tonemapped_png(image: np.ndarray, *, white: float) -> bytes:
    """PNG of ``scenes.colour.tonemap(image, white=white)`` (Reinhard + sRGB)."""
    return encode_png(np.round(tonemap(image, white=white) * 255.0))


def false_colour_png(values: np.ndarray, *, kind: str, vmin: float, vmax: float) -> bytes:
    """PNG of a scalar map in the false colour of ``kind`` (see :data:`COLORMAPS`).

    A (H, W, 3) input (a signed RGB difference) is reduced to its luminance, a
    linear combination, so its sign survives.
    """
    scalar = luminance(values) if np.ndim(values) == 3 else np.asarray(values, np.float64)
    return encode_png(false_colour(scalar, vmin=vmin, vmax=vmax, colormap=COLORMAPS[kind]),
                      palette=True)


def colour_bar_png(*, kind: str, vmin: float, vmax: float, width: int = 256,
                   height: int = 12) -> bytes:
    """A horizontal colour bar (vmin on the left) drawn with :func:`false_colour`."""
    ramp = np.linspace(vmin, vmax, width)[None, :].repeat(height, axis=0)
    return encode_png(false_colour(ramp, vmin=vmin, vmax=vmax, colormap=COLORMAPS[kind]),
                      palette=True)


def mask_png(caustic: np.ndarray | None, obj: np.ndarray | None, shape) -> bytes:
    """The regions of the metrics: caustic region orange, masked object grey, else black."""
    rgb = np.zeros((*shape[:2], 3), np.uint8)
    if caustic is not None:
        rgb[np.asarray(caustic, bool)] = (240, 140, 20)
    if obj is not None:
        rgb[np.asarray(obj, bool)] = (110, 110, 110)
    return encode_png(rgb)
