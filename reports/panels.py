"""Images of a report page: HDR previews, float data for probes and profiles,
false-colour maps, region masks, default profiles, thumbnails.

Each page's binary assets go either beside it (PNG and CSV files) or into it
(``data:`` URIs, ``self_contained``); HDR previews always reach the page as
``data:`` URIs (see :mod:`reports.build`). Receiver maps are flipped so +v points up.

Float data for the probe, profiles and canvases (:func:`reports.page_data.view_data`,
``panel["data"]``): per view, the displayed images, rounded to 0.05 % and packed, a
scene's reference shared by its method pages (see :mod:`reports.page_data`). A
preview box-filtered down by ``f`` holds box means: of the values, and for the
standard error ``sqrt(mean(Var) / f²)``, the standard error of a mean of f²
independent pixels.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

from reports import images, profiles
from reports.display import luminance, white_point
from reports.page_data import view_data
from reports.records import SceneComparison
from scenes.files import atomic_write_bytes

__all__ = ["THUMBNAIL_SIZE", "Assets", "hdr_script", "per_view", "thumbnails", "view_panels",
           "views"]

THUMBNAIL_SIZE = 128
_VIEW = re.compile(r"^(camera|receiver\d+)$")


@dataclass
class Assets:
    """Where a page's binary assets go: files beside it, or data: URIs inside it."""

    folder: Path
    self_contained: bool
    written: list[Path] = field(default_factory=list)

    def add(self, name: str, data: bytes, *, mime: str = "image/png") -> str:
        if self.self_contained:
            return images.data_uri(data, mime=mime)
        path = self.folder / name
        atomic_write_bytes(path, data)
        self.written.append(path)
        return quote(name)


def views(comparison: SceneComparison) -> list[str]:
    views = {key.split("/", 1)[0] for key in comparison.images}
    bad = sorted(v for v in views if not _VIEW.match(v))
    if bad:
        raise ValueError(f"image keys must start with camera/ or receiver<i>/, got {bad}")
    return sorted(views, key=lambda v: (v != "camera", len(v), v))


def _positive(value: Any) -> bool:
    return value is not None and math.isfinite(float(value)) and float(value) > 0


def per_view(value: Any, view: str) -> Any:
    return value.get(view) if isinstance(value, dict) else value


def view_panels(comparison: SceneComparison, view: str, assets: Assets,
                 preview_size: int) -> dict[str, Any]:
    """Encode one view's images; receiver maps are flipped so +v points up."""
    flip = view != "camera"
    raw = {key.split("/", 1)[1]: np.asarray(array) for key, array in comparison.images.items()
           if key.split("/", 1)[0] == view}
    shown = {}
    factor = 1
    for kind, array in raw.items():
        shown[kind], factor = images.downsample(array[::-1] if flip else array,
                                                max_size=preview_size)
    method, reference = shown.get("method"), shown.get("reference")
    white = per_view(comparison.exposure.get("white"), view)
    if white is None and reference is not None:
        white = white_point(reference)
    white = float(white) if _positive(white) else 1.0
    panel: dict[str, Any] = {
        "view": view,
        "title": "Camera image" if view == "camera"
        else f"Receiver {view.removeprefix('receiver')} irradiance map",
        "units": "W m⁻² sr⁻¹" if view == "camera" else "W/m²",
        "white": white, "factor": factor, "hdr": None, "maps": [], "regions": None,
        "size": next(iter(shown.values())).shape[:2] if shown else None,
        "shape": raw["method"].shape[:2] if "method" in raw else None,
        "data": None, "profile": None, "peak": None,
    }
    if method is not None and reference is not None:
        panel["hdr"] = {
            layer: images.data_uri(images.encode_png(images.encode_rgbe_stack(array)))
            for layer, array in (("method", method), ("reference", reference))
        }
        panel["size"] = method.shape[:2]
        panel["data"] = view_data(shown, factor=factor)
        # The top of the page's log scales: the largest reference luminance shown.
        lum = luminance(reference)
        lum = lum[np.isfinite(lum)]
        panel["peak"] = float(lum.max()) if lum.size and lum.max() > 0 else None
        if flip:
            panel["profile"] = _default_profile(assets, view, raw, factor=factor,
                                                size=method.shape[:2])
    if "signed" in shown:
        limit = per_view(comparison.exposure.get("diff_range"), view)
        if not _positive(limit):
            lum = np.abs(luminance(shown["signed"]))
            lum = lum[np.isfinite(lum)]
            limit = float(np.percentile(lum, 99)) if lum.size else 0.0
            # The colour bar needs a positive range, whatever the data (all NaN, all 0).
            limit = limit if _positive(limit) else 1.0
        panel["maps"].append(_map_panel(
            assets, view, "signed", shown["signed"], vmin=-float(limit), vmax=float(limit),
            title="Difference (method − reference)",
            label="luminance of method − reference, " + panel["units"]))
    if "ssim" in shown:
        panel["maps"].append(_map_panel(assets, view, "ssim", shown["ssim"], vmin=0.0,
                                        vmax=1.0, title="SSIM map",
                                        label="SSIM (values below 0 shown as 0)"))
    if "flip" in shown:
        panel["maps"].append(_map_panel(assets, view, "flip", shown["flip"], vmin=0.0,
                                        vmax=1.0, title="FLIP map", label="HDR-FLIP error"))
    caustic, obj = shown.get("mask_caustic"), shown.get("mask_object")
    if caustic is not None or obj is not None:
        shape = (caustic if caustic is not None else obj).shape
        png = images.mask_png(None if caustic is None else caustic >= 0.5,
                              None if obj is None else obj >= 0.5, shape)
        panel["regions"] = assets.add(f"{view}_regions.png", png)
    return panel


def _map_panel(assets: Assets, view: str, kind: str, values: np.ndarray, *, vmin: float,
               vmax: float, title: str, label: str) -> dict[str, Any]:
    return {
        "kind": kind, "title": title, "label": label, "vmin": vmin, "vmax": vmax,
        "src": assets.add(f"{view}_{kind}.png",
                          images.false_colour_png(values, kind=kind, vmin=vmin, vmax=vmax)),
        "bar": assets.add(f"colourbar_{kind}_{view}.png",
                          images.colour_bar_png(kind=kind, vmin=vmin, vmax=vmax)),
    }


def _default_profile(assets: Assets, view: str, raw: dict[str, np.ndarray], *, factor: int,
                     size: tuple[int, int]) -> dict[str, Any]:
    """The default profile of a receiver map (:func:`reports.profiles.default_profile`)
    at full resolution, written as CSV; ``line`` holds its ends in the preview's
    pixels, flipped as shown (row ``(H − 1 − y) // f``)."""
    profile = profiles.default_profile(raw["method"], raw["reference"],
                                       raw.get("reference_variance"),
                                       mask=raw.get("mask_caustic"))
    name = f"profile_{view}.csv"
    height = raw["reference"].shape[0]
    row = min((height - 1 - int(profile.y[0])) // factor, size[0] - 1)
    last = min(int(profile.x[-1]) // factor, size[1] - 1)
    return {"name": name, "href": assets.add(name, profiles.profile_csv(profile),
                                             mime="text/csv"),
            "row": int(profile.y[0]), "samples": len(profile.x),
            "line": [int(profile.x[0]) // factor, row, last, row]}


def hdr_script(panels: list[dict[str, Any]]) -> str:
    """``window.causticsHdr``: the RGBE previews of each view without float data (the
    page draws a view with data from its data); ``window.causticsColormap``: the
    false-colour table (:func:`reports.images.lookup_table`, 256 RGB bytes in base64)."""
    lines = ["window.causticsHdr = window.causticsHdr || {};"]
    for panel in panels:
        if panel["hdr"] is not None and panel["data"] is None:
            lines.append(f"window.causticsHdr[{json.dumps(panel['view'])}] = "
                         f"{json.dumps(panel['hdr'])};")
    table = images.data_uri(images.lookup_table(), mime="application/octet-stream")
    lines.append("window.causticsColormap = " + json.dumps(
        {"name": images.IRRADIANCE_COLORMAP, "base64": table.split(",", 1)[1]}) + ";")
    return "\n".join(lines) + "\n"


def thumbnails(comparison: SceneComparison, folder: str, out_dir: Path,
                self_contained: bool) -> dict[str, str]:
    """Tone-mapped method and reference of the first view, at most THUMBNAIL_SIZE px."""
    names = views(comparison)
    if not names:
        return {}
    view = names[0]
    white = per_view(comparison.exposure.get("white"), view)
    out = {}
    for layer in ("method", "reference"):
        array = comparison.images.get(f"{view}/{layer}")
        if array is None:
            continue
        array = np.asarray(array)[::-1] if view != "camera" else np.asarray(array)
        small, _ = images.downsample(array, max_size=THUMBNAIL_SIZE)
        if not _positive(white):
            white = white_point(comparison.images.get(f"{view}/reference", array))
        png = images.tonemapped_png(small, white=float(white))
        if self_contained:
            out[layer] = images.data_uri(png)
        else:
            atomic_write_bytes(out_dir / folder / f"thumbnail_{layer}.png", png)
            out[layer] = f"{quote(folder)}/thumbnail_{layer}.png"
    return out
