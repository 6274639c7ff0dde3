"""The float data behind a scene page's probe, profiles and canvases: compact, and a
scene's reference written once per report.

Per view, the page reads these layers (row 0 at the top of the display, receiver
maps flipped so +v points up; see :mod:`reports.panels`):

``reference`` (H, W, 3), ``reference_se`` (H, W, 3)
    The reference and its standard error ``sqrt(Var[mean])`` (when the record carries
    ``<view>/reference_variance``). The same for every method of a scene.
``difference`` (H, W, 3)
    method − reference, the float32 ``<view>/signed``.
``method_exceptions`` (H, W, 3)
    NaN where the page's ``fround(reference + difference)`` is the method to within
    the bound below, else the method itself (see :func:`view_data`).
``ssim``, ``flip`` (H, W)
    The metric maps, when computed.

**Written once.** Each layer is a *blob*: a script ``_data/<key>.js`` beside the
pages (``<key>`` the first 128 bits of the SHA-256 of its packed bytes, in hex) that
assigns the packed bytes, in base64, to ``window.causticsBlobs[key]``. A blob's name
is a function of its content, so two pages of one scene (two methods) name the same
reference blob, and writing it again is skipped: no coordination between pages is
needed, and every write is atomic, so an existing blob is whole. Scripts, not
``fetch``, because Chromium blocks ``fetch`` from ``file://`` pages. The folder is
``_data`` because :func:`reports.build.scene_folder` never makes a name with a
leading underscore, so no scene's folder can be it. Each view's own small script
``data_<view>.js`` (beside its page) gives the sizes and the blobs' keys.

**Compact, to a stated bound.** Every value is rounded to :data:`MANTISSA_BITS`
mantissa bits (round to nearest; exponent and sign kept, so tiny values keep their
relative precision, unlike float16): a relative error of at most
2^-(MANTISSA_BITS + 1) = 4.9e-4, half the report's 0.1 % bound
(:data:`RELATIVE_BOUND`), since dropping the last 13 bits of float32 noise is what
lets deflate compress a Monte Carlo image. The difference is shipped as its own
layer because one computed from two rounded images would carry their errors,
unbounded relative to a small difference; the method is then the page's
``fround(reference + difference)`` (error at most 2^-11 (|reference| + |difference|)),
except where that misses ``RELATIVE_BOUND / 2`` relative to the method (a method far
darker than the reference): there ``method_exceptions`` holds the rounded method.
So every value the page shows, method, reference, difference, standard error, SSIM
and FLIP, is within ``RELATIVE_BOUND / 2`` of the comparison's float32 value, per
channel (zero stays exactly zero).

**Packing** (:func:`pack`; the page's ``view_data.js`` undoes it): the float32 bit
patterns as uint32; each colour channel after the first XORed with the one before
(grey pixels then hold 0); channels planar; each row's values replaced by their
difference from the one on the left (mod 2^32); the four bytes of every value split
into four planes (byte 0 of all values, then byte 1, ...); zlib deflate (RFC 1950,
what the browser's ``DecompressionStream("deflate")`` reads).
"""

from __future__ import annotations

import base64
import hashlib
import json
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from scenes.files import atomic_write_bytes

__all__ = ["BLOB_FOLDER", "ENCODING", "MANTISSA_BITS", "RELATIVE_BOUND", "Blob", "PageScripts",
           "ViewData", "blob_script", "data_script", "pack", "page_scripts", "round_mantissa",
           "unpack", "view_data"]

#: Relative agreement promised between every value the page shows and the
#: comparison's (the EXR files'): 0.1 %.
RELATIVE_BOUND = 1e-3
#: Mantissa bits kept of float32's 23: relative rounding error <= 2^-11 = 4.9e-4.
MANTISSA_BITS = 10
#: Name of the packing (:func:`pack`), checked by the page.
ENCODING = "f32-round10-xor-delta-shuffle-deflate"
#: Folder of the blobs, beside the scene folders.
BLOB_FOLDER = "_data"


def round_mantissa(values: np.ndarray, bits: int = MANTISSA_BITS) -> np.ndarray:
    """``values`` as float32 rounded to ``bits`` mantissa bits (nearest, ties away
    from zero in magnitude): relative error at most 2^-(bits + 1). Non-finite values,
    subnormal ones (below 1.2e-38, whose precision is absolute) and finite ones the
    rounding would carry past the largest float32 stay as they are."""
    values = np.asarray(values, np.float32)
    drop = 23 - bits
    pattern = values.view(np.uint32).astype(np.uint64)
    # Adding half a unit of the last kept bit, then clearing the dropped bits, rounds
    # the magnitude; a carry into the exponent is the correct next binade.
    rounded = (((pattern + (1 << (drop - 1))) >> drop) << drop).astype(np.uint32)
    out = rounded.view(np.float32)
    normal = np.abs(values) >= np.finfo(np.float32).tiny
    return np.where(normal & np.isfinite(values) & np.isfinite(out), out, values)


#: zlib's level for the packed layers: on the demo's eight 512 x 512 layers level 6
#: wrote 0.9 % more bytes than level 9 in a quarter of the time (0.35 s against 1.37 s).
DEFLATE_LEVEL = 6


def pack(values: np.ndarray) -> bytes:
    """Packed bytes of an (H, W) or (H, W, C) array taken as float32, without loss
    (module docstring; :func:`unpack` inverts it)."""
    values = np.asarray(values, np.float32)
    bits = np.ascontiguousarray(values.reshape(*values.shape[:2], -1)).view(np.uint32)
    xored = bits.copy()
    xored[..., 1:] ^= bits[..., :-1]
    planar = np.ascontiguousarray(np.moveaxis(xored, 2, 0))        # (C, H, W)
    delta = planar.copy()
    delta[..., 1:] -= planar[..., :-1]                              # wraps mod 2^32
    planes = delta.astype("<u4").reshape(-1).view(np.uint8).reshape(-1, 4).T
    return zlib.compress(np.ascontiguousarray(planes).tobytes(), DEFLATE_LEVEL)


def unpack(payload: bytes, shape: tuple[int, ...]) -> np.ndarray:
    """The float32 array of ``shape`` ((H, W) or (H, W, C)) that :func:`pack` packed."""
    h, w = shape[:2]
    c = shape[2] if len(shape) == 3 else 1
    planes = np.frombuffer(zlib.decompress(payload), np.uint8).reshape(4, -1)
    delta = np.ascontiguousarray(planes.T).view("<u4").reshape(c, h, w).astype(np.uint32)
    planar = np.cumsum(delta, axis=2, dtype=np.uint32)              # wraps mod 2^32
    xored = np.moveaxis(planar, 0, 2)
    bits = xored.copy()
    for k in range(1, c):
        bits[..., k] = xored[..., k] ^ bits[..., k - 1]
    return bits.view(np.float32).reshape(shape)


@dataclass(frozen=True)
class Blob:
    """One packed layer and its content-derived key (128 bits of SHA-256, hex)."""

    key: str
    payload: bytes

    @classmethod
    def of(cls, values: np.ndarray) -> Blob:
        payload = pack(values)
        return cls(hashlib.sha256(payload).hexdigest()[:32], payload)

    @property
    def name(self) -> str:
        """File name of its script in :data:`BLOB_FOLDER`."""
        return f"{self.key}.js"


def blob_script(blob: Blob) -> str:
    """Script text that assigns ``blob``'s packed bytes, base64, to
    ``window.causticsBlobs[key]``."""
    return ("window.causticsBlobs = window.causticsBlobs || {};\n"
            f"window.causticsBlobs[{json.dumps(blob.key)}] = "
            f"\"{base64.b64encode(blob.payload).decode('ascii')}\";\n")


@dataclass(frozen=True)
class ViewData:
    """One view's data: ``meta`` (JSON: ``width``, ``height``, ``factor``,
    ``encoding`` and ``layers`` of ``{"channels", "blob"}``) and its blobs."""

    meta: dict[str, Any]
    blobs: tuple[Blob, ...]


def view_data(shown: dict[str, np.ndarray], *, factor: int) -> ViewData:
    """The layers of one view as shown (module docstring), from the page's arrays
    ``shown`` (``method``, ``reference``, and when present ``reference_variance``,
    ``ssim``, ``flip``), box-filtered down by ``factor``: a box of f² independent
    pixels has the standard error ``sqrt(mean(Var) / f²)``."""
    method = np.asarray(shown["method"], np.float32)
    reference = np.asarray(shown["reference"], np.float32)
    # The float32 <view>/signed: a float64 difference of the float32 images, rounded once.
    difference = (method.astype(np.float64) - reference).astype(np.float32)
    layers = {"reference": round_mantissa(reference), "difference": round_mantissa(difference)}
    # What the page computes: fround(reference + difference) of the shipped float32s.
    composed = (layers["reference"].astype(np.float64) + layers["difference"]).astype(np.float32)
    with np.errstate(invalid="ignore"):
        close = np.abs(composed.astype(np.float64) - method) <= RELATIVE_BOUND / 2 * np.abs(method)
    layers["method_exceptions"] = np.where(close, np.float32(np.nan), round_mantissa(method))
    if "reference_variance" in shown:
        variance = np.maximum(np.nan_to_num(np.asarray(shown["reference_variance"],
                                                       np.float64)), 0.0)
        layers["reference_se"] = round_mantissa(np.sqrt(variance / factor**2))
    for name in ("ssim", "flip"):
        if name in shown and np.ndim(shown[name]) == 2:
            layers[name] = round_mantissa(shown[name])
    blobs = {name: Blob.of(array) for name, array in layers.items()}
    h, w = method.shape[:2]
    meta = {"width": int(w), "height": int(h), "factor": int(factor), "encoding": ENCODING,
            "layers": {name: {"channels": 1 if array.ndim == 2 else int(array.shape[2]),
                              "blob": blobs[name].key}
                       for name, array in layers.items()}}
    return ViewData(meta, tuple(blobs.values()))


def data_script(view: str, data: ViewData) -> str:
    """Script text that assigns one view's :attr:`ViewData.meta` to
    ``window.causticsData[view]``."""
    return ("window.causticsData = window.causticsData || {};\n"
            f"window.causticsData[{json.dumps(view)}] = {json.dumps(data.meta)};\n")


@dataclass(frozen=True)
class PageScripts:
    """A page's data scripts: ``inline`` texts (a self-contained page) or ``sources``
    (relative URLs of the files written for a linked page), in loading order."""

    inline: tuple[str, ...]
    sources: tuple[str, ...]


def page_scripts(panels: list[dict[str, Any]], folder: Path, *,
                 self_contained: bool) -> PageScripts:
    """The data scripts of a page whose views are ``panels`` (``view`` and ``data``,
    a :class:`ViewData` or None).

    Linked (not ``self_contained``): writes ``folder/data_<view>.js`` and every blob
    not yet in ``folder.parent / BLOB_FOLDER`` (atomically; one already there has the
    same content, since its name is its hash), and returns their relative URLs.
    Self-contained: writes nothing and returns the same scripts' texts, each blob
    once.
    """
    blobs: dict[str, Blob] = {}
    views: dict[str, str] = {}
    for panel in panels:
        if panel["data"] is not None:
            views[f"data_{panel['view']}.js"] = data_script(panel["view"], panel["data"])
            blobs.update((blob.key, blob) for blob in panel["data"].blobs)
    if self_contained:
        return PageScripts(tuple(blob_script(b) for b in blobs.values()) + tuple(views.values()),
                           ())
    shared = Path(folder).parent / BLOB_FOLDER
    for blob in blobs.values():
        path = shared / blob.name
        if not path.is_file():
            atomic_write_bytes(path, blob_script(blob).encode("ascii"))
    for name, text in views.items():
        atomic_write_bytes(Path(folder) / name, text.encode("utf-8"))
    return PageScripts((), tuple(f"../{BLOB_FOLDER}/{b.name}" for b in blobs.values())
                       + tuple(views))
