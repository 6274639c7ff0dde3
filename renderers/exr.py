"""EXR files through the OpenEXR package: atomic writes, checked reads.

Images are float32 arrays of shape (H, W, 3) (an ``RGB`` layer) or (H, W) (one
channel). Writes go to a temporary file in the same directory and are renamed into
place, so a reader never sees a half-written file; the file gets the mode a plain
``open()`` would give it (0666 less the umask), like the harness's other outputs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenEXR

from scenes.errors import HarnessError
from scenes.files import atomic_path

__all__ = ["ExrError", "read_exr", "write_exr"]


class ExrError(HarnessError, ValueError):
    """An EXR file is missing, truncated, corrupt, or lacks a channel."""


def write_exr(path: str | Path, layers: dict[str, np.ndarray], *, half: bool = False) -> None:
    """Write float layers to ``path`` atomically (ZIP compression).

    Parameters
    ----------
    layers
        Name to array: (H, W, 3) arrays become ``NAME.R/G/B`` (``RGB`` becomes
        ``R, G, B``), (H, W) arrays one channel. All must share H and W.
    half
        Store 16-bit floats (for bounded maps such as SSIM and FLIP: about a third of
        the size); the values must lie within half's finite range, ±65504. Otherwise
        32-bit floats.
    """
    path = Path(path)
    shapes = {a.shape[:2] for a in layers.values()}
    if len(shapes) != 1:
        raise ValueError(f"layers differ in size: {sorted(shapes)}")
    dtype = np.float16 if half else np.float32
    channels = {}
    for name, a in layers.items():
        with np.errstate(over="ignore"):  # an overflow is the error raised below
            channels[name] = np.ascontiguousarray(a, dtype=dtype)
        if half and not np.all(np.isfinite(channels[name])):
            raise ValueError(f"{path}: layer {name} does not fit half precision (±65504)")
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    # OpenEXR keeps the mode of the file it writes into: atomic_path's, that of a
    # plain open(), like every other output.
    with atomic_path(path, suffix=".exr") as tmp:
        OpenEXR.File(header, channels).write(str(tmp))


def read_exr(path: str | Path) -> dict[str, np.ndarray]:
    """Read every layer of an EXR as float32 arrays (RGB layers as (H, W, 3)).

    Raises
    ------
    ExrError
        The file is missing, truncated or corrupt, or holds non-finite values.
    """
    path = Path(path)
    if not path.is_file():
        raise ExrError(f"{path}: no such file")
    try:
        channels = OpenEXR.File(str(path)).channels()
        layers = {name: np.asarray(c.pixels, dtype=np.float32) for name, c in channels.items()}
    except Exception as error:  # OpenEXR raises RuntimeError and others on bad files
        raise ExrError(f"{path}: unreadable EXR ({error})") from None
    for name, arr in layers.items():
        if not np.all(np.isfinite(arr)):
            raise ExrError(f"{path}: layer {name} holds NaN or Inf")
    return layers
