"""Build the HTML comparison report from :class:`~reports.records.SceneComparison`.

Layout written under ``out_dir``::

    index.html              all scenes: key metrics, thresholds, thumbnails
    _static/report.css      (not with self_contained)
    _static/report.js       (not with self_contained)
    <folder>/index.html     one scene; <folder> = scene_folder(name)
    <folder>/*.png, *.svg   previews and plots (not with self_contained)
    <folder>/hdr.js         HDR previews as data: URIs (not with self_contained)

Templates are jinja2 with autoescaping on, so every text from a scene file (name,
description, settings, provenance) renders inert. HDR previews always reach the
page as ``data:`` URIs, because Chromium taints a canvas drawn from a ``file://``
image and the exposure control must read pixels back.
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import re
import unicodedata
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any
from urllib.parse import quote

import jinja2
import numpy as np
from markupsafe import Markup

from reports import images, plots
from reports.display import luminance, white_point
from reports.records import METRIC_FORMULAS, SceneComparison, Table
from scenes.files import atomic_write_bytes, jsonable

__all__ = ["DEFAULT_PREVIEW_SIZE", "KEY_METRICS", "build_report", "scene_folder"]

#: Largest side (pixels) of a preview; larger images are box-filtered down by an
#: integer factor, and the page says so.
DEFAULT_PREVIEW_SIZE = 512
#: Metrics of the summary table, as (view, region, metric), when computed.
KEY_METRICS = (
    ("receiver0", "caustic", "ssim"),
    ("receiver0", "caustic", "relmse"),
    ("receiver0", "caustic", "flip"),
    ("receiver0", "full", "flux_ratio"),
    ("camera", "object_masked", "ssim"),
    ("camera", "object_masked", "flip"),
)
REGION_ORDER = ("full", "caustic", "object_masked")
THUMBNAIL_SIZE = 128
_VIEW = re.compile(r"^(camera|receiver\d+)$")
_RESERVED = {"index.html"}


def scene_folder(name: str, *, taken: Sequence[str] = ()) -> str:
    """A safe folder name for a scene: letters, digits, ``.``, ``_`` and ``-`` only.

    Anything else (``/``, ``<``, spaces, ...) becomes ``_``; leading dots and
    underscores are dropped (so no ``..``, no hidden folder, no clash with
    ``_static``); at most 64 characters; ``scene`` when nothing is left; ``-2``,
    ``-3``, ... appended while the name is in ``taken``.
    """
    text = unicodedata.normalize("NFKD", str(name)).encode("ascii", "ignore").decode()
    folder = re.sub(r"[^A-Za-z0-9._-]+", "_", text).strip("._")[:64].rstrip("._") or "scene"
    taken_set = set(taken) | _RESERVED
    candidate, n = folder, 1
    while candidate in taken_set:
        n += 1
        candidate = f"{folder}-{n}"
    return candidate


def _number(value: Any) -> str:
    """Numbers for tables: 4 significant digits, ∞ and n/a spelled out, None as —."""
    if value is None:
        return "—"
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if math.isnan(value):
            return "n/a"
        if math.isinf(value):
            return "∞" if value > 0 else "−∞"
        return f"{value:.4g}"
    return str(value)


@cache
def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("reports", "templates"),
        autoescape=jinja2.select_autoescape(
            enabled_extensions=("html", "j2"), default_for_string=True, default=True),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["num"] = _number
    env.tests["mapping"] = lambda value: isinstance(value, dict)
    env.tests["sequence_value"] = lambda value: isinstance(value, (list, tuple))
    return env


def _static(name: str) -> str:
    return resources.files("reports").joinpath("static", name).read_text("utf-8")


def _inline_script(text: str) -> Markup:
    """Script text safe to place between ``<script>`` tags (no ``</`` inside)."""
    return Markup(text.replace("</", "<\\/"))


def _script_hashes(*scripts: str) -> Markup:
    """CSP ``'sha256-…'`` sources of the inline scripts: only these may run."""
    return Markup(" ".join(
        f"'sha256-{base64.b64encode(hashlib.sha256(s.encode()).digest()).decode()}'"
        for s in scripts))


@dataclass
class _Assets:
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


def _views(comparison: SceneComparison) -> list[str]:
    views = {key.split("/", 1)[0] for key in comparison.images}
    bad = sorted(v for v in views if not _VIEW.match(v))
    if bad:
        raise ValueError(f"image keys must start with camera/ or receiver<i>/, got {bad}")
    return sorted(views, key=lambda v: (v != "camera", len(v), v))


def _per_view(value: Any, view: str) -> Any:
    return value.get(view) if isinstance(value, dict) else value


def _view_panels(comparison: SceneComparison, view: str, assets: _Assets,
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
    white = _per_view(comparison.exposure.get("white"), view)
    if white is None and reference is not None:
        white = white_point(reference)
    white = float(white) if white and white > 0 else 1.0
    panel: dict[str, Any] = {
        "view": view,
        "title": "Camera image" if view == "camera"
        else f"Receiver {view.removeprefix('receiver')} irradiance map",
        "units": "W m⁻² sr⁻¹" if view == "camera" else "W/m²",
        "white": white, "factor": factor, "hdr": None, "maps": [], "regions": None,
        "size": None,
        "shape": raw["method"].shape[:2] if "method" in raw else None,
    }
    if method is not None and reference is not None:
        panel["hdr"] = {
            layer: images.data_uri(images.encode_png(images.encode_rgbe_stack(array)))
            for layer, array in (("method", method), ("reference", reference))
        }
        panel["size"] = method.shape[:2]
    if "signed" in shown:
        limit = _per_view(comparison.exposure.get("diff_range"), view)
        if not limit or limit <= 0:
            lum = np.abs(luminance(shown["signed"]))
            limit = float(np.percentile(lum, 99)) or 1.0
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


def _map_panel(assets: _Assets, view: str, kind: str, values: np.ndarray, *, vmin: float,
               vmax: float, title: str, label: str) -> dict[str, Any]:
    return {
        "title": title, "label": label, "vmin": vmin, "vmax": vmax,
        "src": assets.add(f"{view}_{kind}.png",
                          images.false_colour_png(values, kind=kind, vmin=vmin, vmax=vmax)),
        "bar": assets.add(f"colourbar_{kind}_{view}.png",
                          images.colour_bar_png(kind=kind, vmin=vmin, vmax=vmax)),
    }


def _metric_tables(comparison: SceneComparison) -> list[dict[str, Any]]:
    by_view: dict[str, list] = {}
    order = list(METRIC_FORMULAS)
    for m in comparison.metrics:
        by_view.setdefault(m.view, []).append(m)
    tables = []
    for view in sorted(by_view, key=lambda v: (v != "camera", len(v), v)):
        rows = sorted(by_view[view], key=lambda m: (
            REGION_ORDER.index(m.region) if m.region in REGION_ORDER else 99, m.region,
            order.index(m.metric) if m.metric in order else 99, m.metric))
        tables.append({"view": view, "rows": rows})
    return tables


def _table(table: Table | None) -> dict[str, Any] | None:
    if table is None:
        return None
    return {"columns": list(table.columns), "rows": [list(r) for r in table.rows]}


def _plot_panels(comparison: SceneComparison, assets: _Assets) -> dict[str, str | None]:
    out: dict[str, str | None] = {"convergence": None, "cost": None}
    if comparison.convergence is not None and comparison.convergence.rows:
        svg = plots.figure_bytes(plots.convergence_figure(comparison.convergence))
        out["convergence"] = assets.add("convergence.svg", svg, mime="image/svg+xml")
    if comparison.cost is not None and comparison.cost.rows:
        svg = plots.figure_bytes(plots.cost_figure(
            comparison.cost, speedup=comparison.speedup, point=comparison.speedup_point))
        out["cost"] = assets.add("cost_accuracy.svg", svg, mime="image/svg+xml")
    return out


def _file_links(comparison: SceneComparison, folder: Path) -> list[dict[str, Any]]:
    """Relative links to the EXR originals; a path that leaves the folder is not linked."""
    links = []
    for label, rel in sorted(comparison.files.items()):
        rel_path = Path(rel)
        safe = not rel_path.is_absolute() and ".." not in rel_path.parts
        links.append({
            "label": label, "path": rel,
            "href": quote(rel_path.as_posix()) if safe else None,
            "exists": safe and (folder / rel_path).is_file(),
        })
    return links


def _thresholds_summary(comparison: SceneComparison) -> dict[str, int]:
    passed = sum(1 for t in comparison.thresholds if t.passed)
    return {"passed": passed, "failed": len(comparison.thresholds) - passed,
            "total": len(comparison.thresholds)}


def _hdr_script(panels: list[dict[str, Any]]) -> str:
    lines = ["window.causticsHdr = window.causticsHdr || {};"]
    for panel in panels:
        if panel["hdr"] is not None:
            lines.append(f"window.causticsHdr[{json.dumps(panel['view'])}] = "
                         f"{json.dumps(panel['hdr'])};")
    return "\n".join(lines) + "\n"


def _build_scene(comparison: SceneComparison, folder: Path, *, self_contained: bool,
                 preview_size: int) -> dict[str, Any]:
    assets = _Assets(folder, self_contained)
    folder.mkdir(parents=True, exist_ok=True)
    panels = [_view_panels(comparison, view, assets, preview_size)
              for view in _views(comparison)]
    hdr_script = _hdr_script(panels)
    context = {
        "c": comparison,
        "panels": panels,
        "metric_tables": _metric_tables(comparison),
        "formulas": METRIC_FORMULAS,
        "convergence": _table(comparison.convergence),
        "cost": _table(comparison.cost),
        "crosscheck": _table(comparison.crosscheck),
        "plots": _plot_panels(comparison, assets),
        "files": _file_links(comparison, folder),
        "thresholds": _thresholds_summary(comparison),
        "provenance": jsonable(comparison.provenance),
        "settings": jsonable(comparison.settings),
        "stability": jsonable(comparison.stability),
        "self_contained": self_contained,
        "static": "../_static/",
        "css": _static("report.css") if self_contained else "",
        "js": _inline_script(_static("report.js")) if self_contained else "",
        "hdr_inline": _inline_script(hdr_script) if self_contained else "",
        "preview_size": preview_size,
    }
    context["script_hashes"] = (_script_hashes(context["hdr_inline"], context["js"])
                                if self_contained else "")
    if not self_contained:
        atomic_write_bytes(folder / "hdr.js", hdr_script.encode("utf-8"))
    html = _environment().get_template("scene.html.j2").render(context)
    atomic_write_bytes(folder / "index.html", html.encode("utf-8"))
    return panels[0] if panels else {}


def _thumbnails(comparison: SceneComparison, folder: str, out_dir: Path,
                self_contained: bool) -> dict[str, str]:
    """Tone-mapped method and reference of the first view, at most THUMBNAIL_SIZE px."""
    views = _views(comparison)
    if not views:
        return {}
    view = views[0]
    white = _per_view(comparison.exposure.get("white"), view)
    out = {}
    for layer in ("method", "reference"):
        array = comparison.images.get(f"{view}/{layer}")
        if array is None:
            continue
        array = np.asarray(array)[::-1] if view != "camera" else np.asarray(array)
        small, _ = images.downsample(array, max_size=THUMBNAIL_SIZE)
        if not white or white <= 0:
            white = white_point(comparison.images.get(f"{view}/reference", array))
        png = images.tonemapped_png(small, white=float(white))
        if self_contained:
            out[layer] = images.data_uri(png)
        else:
            atomic_write_bytes(out_dir / folder / f"thumbnail_{layer}.png", png)
            out[layer] = f"{quote(folder)}/thumbnail_{layer}.png"
    return out


def build_report(out_dir: Path, comparisons: Sequence[SceneComparison], *,
                 self_contained: bool = False,
                 preview_size: int = DEFAULT_PREVIEW_SIZE) -> Path:
    """Write the HTML report of ``comparisons`` under ``out_dir``.

    Parameters
    ----------
    out_dir : Path
        Output folder (created). EXR originals named in ``SceneComparison.files``
        are expected in ``out_dir / scene_folder(name)`` and linked relatively.
    comparisons : sequence of SceneComparison
        One per scene and method, in the order of the summary table (each scene's
        methods next to each other).
    self_contained : bool
        Embed images, plots, JavaScript and CSS in each HTML file (one file per
        page, nothing else written); the EXR links stay relative.
    preview_size : int
        Largest side of an image preview in pixels (box-filtered down by an
        integer factor beyond it; the page states the factor).

    Returns
    -------
    Path
        ``out_dir / "index.html"``.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if not self_contained:
        for name in ("report.css", "report.js"):
            atomic_write_bytes(out_dir / "_static" / name, _static(name).encode("utf-8"))
    rows, taken = [], []
    for comparison in comparisons:
        folder = scene_folder(comparison.page, taken=taken)
        taken.append(folder)
        _build_scene(comparison, out_dir / folder, self_contained=self_contained,
                     preview_size=preview_size)
        metrics = []
        for view, region, metric in KEY_METRICS:
            try:
                metrics.append(comparison.metric(view, region, metric))
            except KeyError:
                metrics.append(None)
        rows.append({
            "c": comparison, "folder": folder, "href": f"{quote(folder)}/index.html",
            "metrics": metrics, "thresholds": _thresholds_summary(comparison),
            "thumbnails": _thumbnails(comparison, folder, out_dir, self_contained),
        })
    html = _environment().get_template("index.html.j2").render({
        "rows": rows, "key_metrics": KEY_METRICS, "formulas": METRIC_FORMULAS,
        "self_contained": self_contained, "static": "_static/",
        "css": _static("report.css") if self_contained else "",
        "script_hashes": "",
    })
    index = out_dir / "index.html"
    atomic_write_bytes(index, html.encode("utf-8"))
    return index
