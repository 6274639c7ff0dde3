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

Beside each difference map (method − reference, luminance, on the scene's scale
``exposure["diff_range"]``, :func:`reports.display.difference_range`: values beyond it
marked, their share stated) stand, where the record carries the reference's variance:

* the reference's standard error ``σ = Σ_c w_c sqrt(Var_c)`` (luminance, Rec. 709
  weights ``w``; the upper bound the probe and the profiles use, exact for perfectly
  correlated channels), on 0 .. its 99.5th percentile;
* the z-score ``z = (L_method − L_reference) / σ``, clipped at ±:data:`Z_LIMIT`, with
  the share of texels (full resolution) where ``|z| > 3``. With σ an upper bound,
  ``|z|`` is a lower bound of the texel's z-score whatever the channels' correlation.
  For a perfect method with Gaussian noise ``P(|z| > 3) = 0.27 %`` at most.
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
from reports.display import (
    CLIP_ABOVE,
    CLIP_BELOW,
    DIFF_RANGE_RULE,
    UNDEFINED,
    difference_range,
    false_colour,
)
from reports.page_data import view_data
from reports.records import SceneComparison
from scenes.colour import LUMA, luminance, white_point
from scenes.files import atomic_write_bytes

__all__ = ["MAP_COLORMAPS", "THUMBNAIL_SIZE", "Z_LIMIT", "Z_REPORTED", "Assets", "hdr_script",
           "per_view", "thumbnails", "uncertainty_maps", "view_panels", "views"]

THUMBNAIL_SIZE = 128
#: The z-score map's colour bar spans ±Z_LIMIT; beyond it texels are marked.
Z_LIMIT = 5.0
#: The page states the share of texels with |z| above this.
Z_REPORTED = 3.0
#: Colormaps of the false-colour maps: diverging for signed quantities (difference,
#: z-score), sequential for the rest.
MAP_COLORMAPS = {**images.COLORMAPS, "se": "cividis", "z": "coolwarm"}
#: Percentile of the standard-error map's luminance at the top of its colour bar.
SE_PERCENTILE = 99.5
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
            # The scene's rule, from the reference alone (every method gets the same).
            limit = difference_range(raw["reference"]) if "reference" in raw else 1.0
        limit = float(limit)
        signed = luminance(raw["signed"])
        finite = np.isfinite(signed)
        clipped = int(np.count_nonzero(np.abs(signed[finite]) > limit))
        panel["maps"].append(_map_panel(
            assets, view, "signed", luminance(shown["signed"]), vmin=-limit, vmax=limit,
            title="Difference (method − reference)",
            label="luminance of method − reference, " + panel["units"],
            clip={"count": clipped, "total": int(finite.sum()), "what": "pixels"},
            note=f"The scene's scale, the same for every method: ±{DIFF_RANGE_RULE}."))
        if method is not None and reference is not None:
            panel["maps"] += uncertainty_maps(assets, view, raw, shown, factor=factor,
                                              units=panel["units"])
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


def _standard_error(variance: np.ndarray, factor: int = 1) -> np.ndarray:
    """Per-channel standard error ``sqrt(Var / f²)`` of a (box mean of) ``Var[mean]``
    (negative or NaN variances, which no estimator should give, count as 0)."""
    variance = np.maximum(np.nan_to_num(np.asarray(variance, np.float64)), 0.0)
    return np.sqrt(variance / factor**2)


def _z_score(signed: np.ndarray, se: np.ndarray) -> np.ndarray:
    """``z = L(signed) / Σ_c w_c σ_c`` per pixel, NaN where the standard error is 0."""
    se_lum = se @ LUMA if se.ndim == 3 else se
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(se_lum > 0, luminance(signed) / np.where(se_lum > 0, se_lum, 1.0),
                        np.nan)


def uncertainty_maps(assets: Assets, view: str, raw: dict[str, np.ndarray],
                     shown: dict[str, np.ndarray], *, factor: int,
                     units: str) -> list[dict[str, Any]]:
    """The reference's standard-error map and the z-score map of one view (module
    docstring), or one ``missing`` entry saying why there are none.

    Parameters
    ----------
    raw, shown : dict of str to ndarray
        The view's layers at full resolution and as shown (box means, ``factor``):
        ``signed`` (method − reference, (H, W, 3)) and ``reference_variance`` (the
        variance of the reference's mean per pixel and channel, (H, W, 3), units²).
    """
    if "reference_variance" not in raw or "signed" not in raw:
        return [{"kind": "uncertainty", "missing": (
            "No standard-error or z-score map: the reference records no per-pixel "
            "variance for this view.")}]
    se = _standard_error(shown["reference_variance"], factor) @ LUMA
    finite = se[np.isfinite(se)]
    top = float(np.percentile(finite, SE_PERCENTILE)) if finite.size else 0.0
    top = top if _positive(top) else 1.0
    se_map = _map_panel(
        assets, view, "se", se, vmin=0.0, vmax=top, title="Reference standard error",
        label="σ of the reference's luminance, " + units,
        clip={"what": "pixels"},
        note=f"σ = Σ w_c sqrt(Var_c) (Rec. 709 weights), the standard error of the "
             f"reference's mean; the bar ends at its {SE_PERCENTILE:g}th percentile.")
    # The share is a property of the comparison: counted at full resolution.
    z_full = _z_score(np.asarray(raw["signed"], np.float64),
                      _standard_error(raw["reference_variance"]))
    defined = np.isfinite(z_full)
    beyond = int(np.count_nonzero(np.abs(z_full[defined]) > Z_REPORTED))
    total = int(defined.sum())
    share = beyond / total if total else float("nan")
    undefined = int(z_full.size - total)
    z_map = _map_panel(
        assets, view, "z", _z_score(np.asarray(shown["signed"], np.float64),
                                    _standard_error(shown["reference_variance"], factor)),
        vmin=-Z_LIMIT, vmax=Z_LIMIT, title="z-score (method − reference) / σ",
        label="z of the luminance, dimensionless", clip={"what": "pixels"},
        note=("|z| > 3 at {share} of the {total} pixels with a standard error (a perfect "
              "method with Gaussian reference noise: at most 0.27 %){rest}.").format(
            share=_percent(share), total=total,
            rest=f"; {undefined} pixel(s) without one, in grey" if undefined else ""))
    z_map["z_share"] = share
    z_map["z_count"] = beyond
    z_map["z_total"] = total
    return [se_map, z_map]


def _percent(share: float) -> str:
    """A share as a percentage, 3 significant digits ('n/a' when undefined)."""
    return "n/a" if not math.isfinite(share) else f"{100 * share:.3g} %"


def _map_panel(assets: Assets, view: str, kind: str, values: np.ndarray, *, vmin: float,
               vmax: float, title: str, label: str, clip: dict[str, Any] | None = None,
               note: str = "") -> dict[str, Any]:
    """One false-colour map (a (H, W, 3) input as its luminance) and its colour bar.

    With ``clip``, values beyond [vmin, vmax] are drawn in the marker colours
    (:data:`reports.display.CLIP_ABOVE`, ``CLIP_BELOW``; NaN in ``UNDEFINED``) and,
    when ``clip`` holds ``count`` and ``total``, the page states their share.
    """
    scalar = luminance(values) if np.ndim(values) == 3 else np.asarray(values, np.float64)
    colormap = MAP_COLORMAPS[kind]
    marked = clip is not None
    ramp = np.linspace(vmin, vmax, 256)[None, :].repeat(12, axis=0)
    panel = {
        "kind": kind, "title": title, "label": label, "vmin": vmin, "vmax": vmax,
        "note": note, "clip": None, "missing": None,
        "src": assets.add(f"{view}_{kind}.png", images.encode_png(false_colour(
            scalar, vmin=vmin, vmax=vmax, colormap=colormap, mark_clipped=marked),
            palette=True)),
        "bar": assets.add(f"colourbar_{kind}_{view}.png", images.encode_png(false_colour(
            ramp, vmin=vmin, vmax=vmax, colormap=colormap, mark_clipped=marked),
            palette=True)),
    }
    if marked:
        share = (clip["count"] / clip["total"] if clip.get("total") else float("nan")) \
            if "count" in clip else None
        panel["clip"] = {
            "above": "rgb({}, {}, {})".format(*CLIP_ABOVE),
            "below": "rgb({}, {}, {})".format(*CLIP_BELOW) if vmin < 0 else None,
            "undefined": "rgb({}, {}, {})".format(*UNDEFINED),
            "share": share, "share_text": None if share is None else _percent(share),
            "count": clip.get("count"), "total": clip.get("total"), "what": clip["what"]}
    return panel


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
    false-colour table (:func:`reports.images.lookup_table`, 256 RGB bytes in base64);
    ``window.causticsLuma``: the luminance weights :data:`scenes.colour.LUMA` (the
    page's probe and canvases weigh RGB with them, so they have no copy of their own)."""
    lines = ["window.causticsHdr = window.causticsHdr || {};",
             f"window.causticsLuma = {json.dumps(LUMA.tolist())};"]
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
