"""Build the HTML comparison report from :class:`~reports.records.SceneComparison`.

Layout written under ``out_dir``::

    index.html              all scenes: key metrics, accuracy checks, thumbnails
    _static/report.css      (not with self_contained)
    _static/report.js       (not with self_contained)
    <folder>/index.html     one scene; <folder> = scene_folder(name)
    <folder>/*.png, *.svg   previews and plots (not with self_contained)
    <folder>/hdr.js         HDR previews as data: URIs (not with self_contained)
    <folder>/data_<view>.js sizes and blobs of each view's float data (not with
                            self_contained)
    _data/<hash>.js         the float data's blobs, each written once, shared by
                            the pages of a scene (not with self_contained)
    <folder>/profile_<view>.csv  default profile of each receiver map (not with
                            self_contained: a data: URI link there)

Templates are jinja2 with autoescaping on, so every text from a scene file (name,
description, settings, provenance) renders inert. HDR previews always reach the
page as ``data:`` URIs, because Chromium taints a canvas drawn from a ``file://``
image and the exposure control must read pixels back. The views' float data
(:mod:`reports.page_data`) come as scripts for the same reason (no fetch on
``file://``), loaded before the page script.

The page script ``report.js`` is one file made of the readable sources in
``reports/static`` (:data:`SCRIPT_PARTS`, in order), so every page, the sweep's
included, loads one vendored script.
"""

from __future__ import annotations

import base64
import hashlib
import math
import re
import unicodedata
from collections.abc import Sequence
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any
from urllib.parse import quote

import jinja2
import numpy as np
from markupsafe import Markup

from reports import plots
from reports.decomposition import decomposition_section
from reports.page_data import page_scripts
from reports.panels import Assets, hdr_script, thumbnails, view_panels, views
from reports.records import (
    CHECK_KIND_MEANING,
    CHECK_KINDS,
    METRIC_FORMULAS,
    EqualErrorSpeedup,
    MetricValue,
    SceneComparison,
    SceneFailure,
    Table,
    slower,
)
from reports.temporal import temporal_index, temporal_script, temporal_section
from scenes.effects import EFFECTS
from scenes.files import atomic_write_bytes, jsonable

__all__ = ["DEFAULT_PREVIEW_SIZE", "FLUX_RATIO_RANGE", "KEY_METRICS", "SOFTWARE_GL",
           "build_report", "hardware", "page_number", "scene_folder", "speedup_text",
           "write_index", "write_page"]

#: Largest side (pixels) of a preview; larger images are box-filtered down by an
#: integer factor, and the page says so.
DEFAULT_PREVIEW_SIZE = 512
#: Metrics of the summary table, as (view, region, metric), when computed.
KEY_METRICS = (
    ("receiver0", "caustic", "relmse"),
    ("receiver0", "caustic", "ssim"),
    ("receiver0", "caustic", "flip"),
    ("receiver0", "full", "flux_ratio"),
    ("receiver0", "outside", "stray_flux"),
    ("camera", "object", "relmse"),
)
REGION_ORDER = ("full", "caustic", "outside", "object", "object_masked")
#: A page shows its flux budget when the method's flux ratio (receiver 0, whole map)
#: is outside this range, or not a number.
FLUX_RATIO_RANGE = (0.5, 2.0)
_RESERVED = {"index.html"}
#: Sources of the page script ``report.js``, concatenated in this order: shared data
#: helpers, zoom and pan, the probe, profiles, then the page's main part.
SCRIPT_PARTS = ("view_data.js", "zoom.js", "probe.js", "profile.js", "report.js")


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


def page_number(value: Any) -> str:
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


#: GL renderers that rasterise in software on the CPU (lower case, matched in the
#: renderer string): with one of these no GPU rendered the method.
SOFTWARE_GL = ("llvmpipe", "softpipe", "swrast", "swiftshader", "lavapipe",
               "software rasterizer")


def speedup_text(speedup: EqualErrorSpeedup | None) -> str:
    """An equal-error speedup as the report shows it: ``12.3× (95 % interval 8.1×–19×)``,
    ``1.6× slower (speedup 0.625×, 95 % interval 0.5×–0.8×)`` below 1,
    ``at least 40×`` (the method is not measurably off the truth: no upper end),
    ``at most 2×`` (the reference's cheapest budget is already as accurate), or the
    bare estimate where no interval was computed (or it rounds to one number); ``—`` for
    None."""
    if speedup is None:
        return "—"
    value = f"{page_number(speedup.speedup)}×"
    if speedup.bound_kind == "lower bound":
        return f"at least {value} (95 % confidence)"
    if speedup.bound_kind == "upper bound":
        return f"at most {value}"
    low, high = float(speedup.low), float(speedup.high)
    # An interval that rounds to one number at the shown digits (no uncertainty was
    # propagated, e.g. an exact fit) says nothing: omitted.
    interval = ""
    if math.isfinite(low) and math.isfinite(high) and page_number(low) != page_number(high):
        interval = f"95 % interval {page_number(low)}×–{page_number(high)}×"
    elif math.isfinite(low) and high == math.inf:
        interval = f"95 % interval from {page_number(low)}×"
    if slower(speedup.speedup):
        # Below 1 the method is slower than the reference at its own error.
        inside = ", ".join(p for p in (f"speedup {value}", interval) if p)
        return f"{page_number(1 / speedup.speedup)}× slower ({inside})"
    return f"{value} ({interval})" if interval else value


def hardware(comparison: SceneComparison) -> dict[str, Any]:
    """Where a comparison's times were measured: the method's GL renderer and the GPU
    it names (None for a software rasteriser, :data:`SOFTWARE_GL`, or none recorded),
    the machine's CPU count and processor, the reference's Mitsuba variant and the
    device it runs on (``cuda_*``: a GPU), and all of it as one ``text``."""
    prov = comparison.provenance
    gl = prov.method.gl_renderer
    machine = prov.machine or {}
    cpus, processor = machine.get("cpus"), machine.get("processor") or None
    software = gl is not None and any(name in gl.lower() for name in SOFTWARE_GL)
    # A hardware renderer string is "<GPU>/<bus>/<instruction set>" (NVIDIA) or the
    # GPU's name: its first part names the GPU.
    gpu = gl.split("/", 1)[0].strip() if gl and not software else None
    variant = prov.reference.get("variant") or (prov.reference.get("versions") or {}).get(
        "variant")
    device = None if not variant else ("a GPU (CUDA)" if str(variant).startswith("cuda")
                                       else "the CPU")
    if gl is None:
        method = "GL renderer not recorded"
    elif software:
        method = f"GL renderer {gl} (software rasterisation on the CPU, no GPU)"
    else:
        method = f"GL renderer {gl} (GPU: {gpu})"
    cpu = (f"{cpus} CPUs" if cpus else "CPU count not recorded") + (
        f", processor {processor}" if processor else ", processor not recorded")
    reference = (f"reference: Mitsuba {variant} on {device}" if variant
                 else "reference: Mitsuba variant not recorded")
    return {"gl_renderer": gl, "gpu": gpu, "cpus": cpus, "processor": processor,
            "variant": variant, "reference_device": device,
            "text": f"Measured on: method {method}; {cpu}; {reference}."}


def _speedup_missing(comparison: SceneComparison) -> tuple[str, str] | None:
    """Why the index shows no speedup, as (a few words, the full reason); None when it
    shows one."""
    if comparison.speedup is not None:
        return None
    withheld = comparison.speedup_withheld
    if withheld is not None:
        return f"withheld: {withheld.short or 'see its page'}", f"Withheld: {withheld.reason}"
    if comparison.section("cost") is None:
        return "cost study not run", ("The cost-versus-accuracy study did not run for this "
                                      "comparison, so no equal-error speedup was computed.")
    return "not computed", ("The cost study ran but gave no equal-error speedup (see the "
                            "page's cost section).")


def _metric_cell(comparison: SceneComparison, view: str, region: str,
                 metric: str) -> dict[str, Any]:
    """One metric cell of the index: the value, or why there is none, and why its noise
    floor or excess (the method's own error) is missing where they are."""
    try:
        mv: MetricValue | None = comparison.metric(view, region, metric)
    except KeyError:
        mv = None
    cell: dict[str, Any] = {"mv": mv, "why": None, "floor_why": None, "excess_why": None}
    if mv is None:
        if not any(key.startswith(f"{view}/") for key in comparison.images):
            notes = [n for n in comparison.provenance.notes if n.startswith(view)]
            cell["why"] = (f"no {view}", notes[0] if notes else
                           f"This comparison has no {view} view.")
        else:
            cell["why"] = ("not computed", f"{metric} is not computed over the region "
                           f"{region} of {view} in this comparison.")
        return cell
    if mv.noise_floor is None:
        cell["floor_why"] = ("no noise floor", "No independent reference was scored "
                             "against the reference.")
    if mv.excess is None:
        if f"{view}/reference_variance" not in comparison.images:
            cell["excess_why"] = ("no variance", f"The reference records no per-pixel "
                                  f"variance for {view}, so the method's own error is not "
                                  "estimated.")
        elif view == "camera":
            cell["excess_why"] = ("no interval", "The camera's pixels read the caustic from "
                                  "shared lookup texels, so their noise is not independent "
                                  "and no interval is given for this view: see the receiver "
                                  "maps' verdicts.")
        else:
            cell["excess_why"] = ("not estimated", f"The comparison carries no estimate of "
                                  f"the method's own {metric} error.")
    return cell


@cache
def page_environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("reports", "templates"),
        autoescape=jinja2.select_autoescape(
            enabled_extensions=("html", "j2"), default_for_string=True, default=True),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["num"] = page_number
    env.filters["speedup"] = speedup_text
    env.globals["effect_notes"] = EFFECTS
    env.tests["mapping"] = lambda value: isinstance(value, dict)
    env.tests["sequence_value"] = lambda value: isinstance(value, (list, tuple))
    return env


@cache
def static_text(name: str) -> str:
    """A vendored static file; ``report.js`` is the bundle of :data:`SCRIPT_PARTS`."""
    folder = resources.files("reports").joinpath("static")
    if name == "report.js":
        return "\n".join(f"/* ---- {part} ---- */\n" + folder.joinpath(part).read_text("utf-8")
                         for part in SCRIPT_PARTS)
    return folder.joinpath(name).read_text("utf-8")


def _inline_script(text: str) -> Markup:
    """Script text safe to place between ``<script>`` tags (no ``</`` inside)."""
    return Markup(text.replace("</", "<\\/"))


def _script_hashes(*scripts: str) -> Markup:
    """CSP ``'sha256-…'`` sources of the inline scripts: only these may run."""
    return Markup(" ".join(
        f"'sha256-{base64.b64encode(hashlib.sha256(s.encode()).digest()).decode()}'"
        for s in scripts))


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


def _plot_panels(comparison: SceneComparison, assets: Assets) -> dict[str, str | None]:
    out: dict[str, str | None] = {"convergence": None, "cost": None}
    if comparison.convergence is not None and comparison.convergence.rows:
        svg = plots.figure_bytes(plots.convergence_figure(comparison.convergence))
        out["convergence"] = assets.add("convergence.svg", svg, mime="image/svg+xml")
    if comparison.cost is not None and comparison.cost.rows:
        svg = plots.figure_bytes(plots.cost_figure(
            comparison.cost, speedup=comparison.speedup, point=comparison.speedup_point,
            cold=comparison.speedup_cold))
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


def _checks_summary(comparison: SceneComparison) -> dict[str, Any]:
    """Counts over all checks (``failed`` excludes known gaps) and per kind:
    ``kinds`` lists (kind, meaning, checks of that kind, counts) in
    :data:`CHECK_KINDS` order."""
    checks = comparison.checks
    failed = sum(1 for t in checks if t.outcome == "FAIL")
    kinds = []
    for kind in CHECK_KINDS:
        mine = [t for t in checks if t.kind == kind]
        counts = {o: sum(1 for t in mine if t.outcome == o)
                  for o in ("pass", "FAIL", "undecided", "known gap", "gap closed")}
        kinds.append({"kind": kind, "meaning": CHECK_KIND_MEANING[kind], "checks": mine,
                      "total": len(mine), **counts})
    return {"passed": sum(1 for t in checks if t.outcome in ("pass", "gap closed")),
            "failed": failed,
            "undecided": sum(1 for t in checks if t.outcome == "undecided"),
            "gaps": sum(1 for t in checks if t.outcome == "known gap"),
            "total": len(checks), "kinds": kinds}


#: Studies whose sections have a panel of their own on the page.
OWN_PANELS = ("convergence", "cost", "temporal", "decomposition")


def _study_sections(comparison: SceneComparison) -> list[dict[str, Any]]:
    """Every other study's section, shown generically: its title, its summary (a
    ``summary`` in its JSON form), its other values and its tables."""
    out = []
    for section in comparison.sections:
        if section.name in OWN_PANELS:
            continue
        data = jsonable(section.as_dict())
        summary = data.pop("summary", "") if isinstance(data, dict) else ""
        data.pop("tables", None)
        out.append({"name": section.name, "title": section.title, "summary": summary,
                    "values": data.get("values", data),
                    "tables": [(name, _table(t)) for name, t in section.tables().items()]})
    return out


def _flux_budget(comparison: SceneComparison | SceneFailure) -> dict[str, Any] | None:
    """The flux-budget panel: shown for a failure that got that far, and for a
    comparison whose flux ratio is far from 1 (:data:`FLUX_RATIO_RANGE`) or NaN."""
    if comparison.flux_budget is None:
        return None
    ratio = None
    if isinstance(comparison, SceneComparison):
        try:
            ratio = comparison.metric("receiver0", "full", "flux_ratio").value
        except KeyError:
            return None
        low, high = FLUX_RATIO_RANGE
        if ratio is not None and math.isfinite(ratio) and low <= ratio <= high:
            return None
    return {"table": _table(comparison.flux_budget), "ratio": ratio,
            "finite": ratio is not None and math.isfinite(ratio), "range": FLUX_RATIO_RANGE}


def _page_context(self_contained: bool, *scripts: str) -> dict[str, Any]:
    """What every page template gets: static assets, inline or linked, and the CSP."""
    context = {
        "self_contained": self_contained,
        "static": "../_static/",
        "css": static_text("report.css") if self_contained else "",
        "js": _inline_script(static_text("report.js")) if self_contained else "",
    }
    context["script_hashes"] = (_script_hashes(*scripts, context["js"])
                                if self_contained else "")
    return context


def _build_scene(comparison: SceneComparison, folder: Path, *, self_contained: bool,
                 preview_size: int) -> None:
    assets = Assets(folder, self_contained)
    folder.mkdir(parents=True, exist_ok=True)
    panels = [view_panels(comparison, view, assets, preview_size)
              for view in views(comparison)]
    script = hdr_script(panels)
    hdr_inline = _inline_script(script) if self_contained else ""
    data = page_scripts(panels, folder, self_contained=self_contained)
    data_inline = [_inline_script(text) for text in data.inline]
    temporal = temporal_section(comparison, assets)
    temporal_js = temporal_script(temporal)
    temporal_inline = _inline_script(temporal_js) if self_contained and temporal_js else ""
    context = {
        "c": comparison,
        "panels": panels,
        "metric_tables": _metric_tables(comparison),
        "formulas": METRIC_FORMULAS,
        "convergence": _table(comparison.convergence),
        "cost": _table(comparison.cost),
        "crosscheck": _table(comparison.crosscheck),
        "flux_budget": _flux_budget(comparison),
        "plots": _plot_panels(comparison, assets),
        "files": _file_links(comparison, folder),
        "checks": _checks_summary(comparison),
        "provenance": jsonable(comparison.provenance.as_dict()),
        "sections": _study_sections(comparison),
        "settings": jsonable(comparison.settings),
        "stability": jsonable(comparison.stability),
        "hdr_inline": hdr_inline,
        "data_inline": data_inline,
        "data_files": list(data.sources),
        "preview_size": preview_size,
        "temporal": temporal,
        "temporal_inline": temporal_inline,
        "decomposition": decomposition_section(comparison, assets),
        "hardware": hardware(comparison),
        **_page_context(self_contained, hdr_inline, *data_inline,
                        *filter(None, [temporal_inline])),
    }
    if not self_contained:
        atomic_write_bytes(folder / "hdr.js", script.encode("utf-8"))
        if temporal_js:
            atomic_write_bytes(folder / "temporal.js", temporal_js.encode("utf-8"))
    html = page_environment().get_template("scene.html.j2").render(context)
    atomic_write_bytes(folder / "index.html", html.encode("utf-8"))


def _build_failure(failure: SceneFailure, folder: Path, *, self_contained: bool) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    html = page_environment().get_template("failure.html.j2").render({
        "f": failure, "flux_budget": _flux_budget(failure),
        **_page_context(self_contained)})
    atomic_write_bytes(folder / "index.html", html.encode("utf-8"))


def write_page(out_dir: Path, item: SceneComparison | SceneFailure, *, folder: str,
               self_contained: bool = False,
               preview_size: int = DEFAULT_PREVIEW_SIZE) -> dict[str, Any]:
    """Write one page, ``out_dir/folder/index.html``, and return its row of the index
    (for :func:`write_index`).

    A :class:`SceneComparison` gets the full page; a :class:`SceneFailure` a page
    with its one-line error (and its flux budget, when known) and a failure row.
    """
    out_dir = Path(out_dir)
    href = f"{quote(folder)}/index.html"
    if isinstance(item, SceneFailure):
        _build_failure(item, out_dir / folder, self_contained=self_contained)
        return {"c": item, "failure": True, "folder": folder, "href": href}
    _build_scene(item, out_dir / folder, self_contained=self_contained,
                 preview_size=preview_size)
    cells = [_metric_cell(item, *key) for key in KEY_METRICS]
    return {"c": item, "failure": False, "folder": folder, "href": href,
            "metrics": [cell["mv"] for cell in cells], "cells": cells,
            "speedup_why": _speedup_missing(item), "hardware": hardware(item),
            "checks": _checks_summary(item),
            "thumbnails": thumbnails(item, folder, out_dir, self_contained)}


def _scene_cost_plots(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """One cost plot per scene holding every method that ran the cost study, as inline
    SVG markup (no file, so linked and self-contained indexes are alike)."""
    scenes: dict[str, dict[str, Table]] = {}
    for row in rows:
        comparison = row["c"]
        if not row["failure"] and comparison.cost is not None and comparison.cost.rows:
            scenes.setdefault(comparison.name, {})[comparison.method] = comparison.cost
    out = []
    for scene, tables in scenes.items():
        svg = plots.figure_bytes(plots.scene_cost_figure(scene, tables)).decode("utf-8")
        out.append({"scene": scene, "methods": list(tables),
                    "svg": Markup(svg[svg.index("<svg"):])})
    return out


def write_index(out_dir: Path, rows: Sequence[dict[str, Any]], *,
                self_contained: bool = False) -> Path:
    """Write ``out_dir/index.html`` (one row per page, :func:`write_page`) and, unless
    ``self_contained``, the shared ``_static`` files; returns the index's path."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if not self_contained:
        for name in ("report.css", "report.js"):
            atomic_write_bytes(out_dir / "_static" / name, static_text(name).encode("utf-8"))
    html = page_environment().get_template("index.html.j2").render({
        "rows": rows, "key_metrics": KEY_METRICS, "formulas": METRIC_FORMULAS,
        "cost_plots": _scene_cost_plots(rows),
        "temporal": temporal_index(rows),
        "failed": sum(1 for r in rows if r["failure"]),
        "self_contained": self_contained, "static": "_static/",
        "css": static_text("report.css") if self_contained else "",
        "script_hashes": "",
    })
    index = out_dir / "index.html"
    atomic_write_bytes(index, html.encode("utf-8"))
    return index


def build_report(out_dir: Path, comparisons: Sequence[SceneComparison | SceneFailure], *,
                 self_contained: bool = False,
                 preview_size: int = DEFAULT_PREVIEW_SIZE) -> Path:
    """Write the HTML report of ``comparisons`` under ``out_dir``.

    Parameters
    ----------
    out_dir : Path
        Output folder (created). EXR originals named in ``SceneComparison.files``
        are expected in ``out_dir / scene_folder(name)`` and linked relatively.
    comparisons : sequence of SceneComparison or SceneFailure
        One per scene and method, in the order of the summary table (each scene's
        methods next to each other); a failure gets its row and its page too.
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
    rows, taken = [], []
    for comparison in comparisons:
        folder = scene_folder(comparison.page, taken=taken)
        taken.append(folder)
        rows.append(write_page(out_dir, comparison, folder=folder,
                               self_contained=self_contained, preview_size=preview_size))
    return write_index(out_dir, rows, self_contained=self_contained)
