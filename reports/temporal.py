"""The report's temporal section: an animation of method | reference | difference
with play/pause, the metrics over time, the Fig. 8 analogue (a frame strip above the
flicker plot), per-pixel flicker and high-frequency maps, and the flicker numbers
with their formulas.

The animation is an animated WebP written by Pillow (lossless, looping, one frame
per rendered frame): each frame is three panels, the method and the reference
tone-mapped with the sequence's white point (``scenes.colour.tonemap``) and their
signed luminance difference in false colour over a range fixed for the whole
sequence, with +v up, each box-filtered down to at most :data:`PANEL_SIZE` pixels,
and under them a progress bar (frame i fills (i + 1) / T of it, so no two frames are
alike and the encoder keeps every one). The page's player (``static/temporal.js``)
decodes the same file with the browser's ``ImageDecoder`` and draws its frames on a
canvas, with play/pause, single steps and a frame slider; the file is also linked,
and shown as a plain image (it plays, without pause) where ``ImageDecoder`` is
missing. The WebP reaches the player as a ``data:`` URI inside the page's script,
since a ``file://`` page may not read files beside it.
"""

from __future__ import annotations

import io
import json
from importlib import resources
from typing import Any

import numpy as np
from PIL import Image

from reports import images
from reports.display import false_colour
from reports.panels import Assets
from reports.plots import figure_bytes
from reports.records import SceneComparison
from reports.temporal_plots import frame_strip_figure, time_series_figure
from reports.temporal_records import TEMPORAL_FORMULAS, TemporalComparison
from scenes.colour import luminance, tonemap

__all__ = ["GAP", "PANEL_SIZE", "PROGRESS_HEIGHT", "animated_webp", "animation_frames",
           "compare_flicker", "flicker_statement", "temporal_index", "temporal_script",
           "temporal_section"]

#: Largest side of one panel of the animation (pixels).
PANEL_SIZE = 256
#: Width (pixels) up to which a small animation is shown enlarged by a whole factor.
DISPLAY_WIDTH = 768
#: Pixels between the panels, and the height of the progress bar under them.
GAP, PROGRESS_HEIGHT = 4, 4
_BACKGROUND, _BAR = (40, 40, 40), (235, 235, 235)
#: Range of the per-pixel energy ratio map: log2 ρ in [-4, 4].
LOG2_RANGE = 4.0
#: Range of the per-pixel flicker maps: log10 F(x) in [-4, 0].
LOG10_FLICKER_RANGE = (-4.0, 0.0)


def _panel(image: np.ndarray) -> np.ndarray:
    """``image`` flipped (+v up) and box-filtered to at most PANEL_SIZE."""
    small, _ = images.downsample(np.asarray(image)[::-1], max_size=PANEL_SIZE)
    return small


def animation_frames(temporal: TemporalComparison) -> list[np.ndarray]:
    """The animation's frames, uint8 (H + GAP + PROGRESS_HEIGHT, 3 W + 2 GAP, 3):
    method | reference | signed difference, and the progress bar."""
    out = []
    count = temporal.frames
    for index in range(count):
        method = _panel(temporal.method[index])
        reference = _panel(temporal.reference[index])
        difference = luminance(method) - luminance(reference)
        tiles = [np.round(tonemap(method, white=temporal.white) * 255),
                 np.round(tonemap(reference, white=temporal.white) * 255),
                 false_colour(difference, vmin=-temporal.diff_range, vmax=temporal.diff_range,
                              colormap=images.COLORMAPS["signed"])]
        h, w = method.shape[:2]
        frame = np.empty((h + GAP + PROGRESS_HEIGHT, 3 * w + 2 * GAP, 3), np.uint8)
        frame[:] = _BACKGROUND
        for i, tile in enumerate(tiles):
            frame[:h, i * (w + GAP): i * (w + GAP) + w] = np.asarray(tile, np.uint8)
        filled = round(frame.shape[1] * (index + 1) / count)
        frame[h + GAP:, :filled] = _BAR
        out.append(frame)
    return out


def animated_webp(frames: list[np.ndarray], *, fps: float) -> bytes:
    """Lossless animated WebP of ``frames`` (uint8 RGB), looping, each frame shown
    round(1000 / fps) ms (WebP stores whole milliseconds)."""
    pictures = [Image.fromarray(np.ascontiguousarray(f, np.uint8), "RGB") for f in frames]
    buffer = io.BytesIO()
    pictures[0].save(buffer, format="WEBP", save_all=True, append_images=pictures[1:],
                     duration=max(1, round(1000.0 / fps)), loop=0, lossless=True,
                     quality=80, method=4)
    return buffer.getvalue()


def _number(value) -> str:
    if value is None or not np.isfinite(value):
        return "n/a"
    return f"{value:.3g}"


def flicker_statement(summary: dict[str, Any]) -> str:
    """Two sentences: the flicker of the caustic region (the full map without one),
    how much of it the reference's noise explains, and the method's share."""
    region = "caustic" if "caustic" in summary["flicker"] else "full"
    f = summary["flicker"][region]
    if not np.isfinite(f["value"]):
        return "Flicker undefined (no frame pair to score)."
    noise = f["noise_floor"] / 2
    text = (f"Flicker F = {_number(f['value'])} over the {region} region. Two reference "
            f"sequences of disjoint seeds differ by {_number(f['noise_floor'])} (the noise "
            f"floor), so about {_number(noise)} of F is the reference's noise; ")
    if f["excess"] > 0:
        return text + (f"the excess, {_number(f['excess'])}, is the method's flicker "
                       "against a noise-free reference.")
    return text + (f"the excess, {_number(f['excess'])}, is within it: no flicker of the "
                   "method is measurable at this reference budget.")


def _maps(temporal: TemporalComparison, assets: Assets) -> list[dict[str, Any]]:
    """The per-pixel maps on fixed scales (comparable across scenes, presets and runs):
    log10 of the flicker over [:data:`LOG10_FLICKER_RANGE`] (dark pixels, where ε alone
    bounds the normaliser, saturate), log2 of the energy ratio over ±:data:`LOG2_RANGE`."""
    out = []
    low, high = LOG10_FLICKER_RANGE
    for key, title in (("flicker", "Per-pixel flicker, method"),
                       ("flicker_floor", "Per-pixel flicker, independent reference (noise)")):
        if key in temporal.maps:
            values = np.log10(np.maximum(temporal.maps[key], 10.0 ** (low - 1)))
            out.append(_map(assets, f"temporal_{key}", values, kind="flip", vmin=low,
                            vmax=high, title=title,
                            label="log10 of the mean over pairs of (ΔM − ΔR)² / (R̄² + ε)"))
    if "hf_ratio" in temporal.maps:
        log_ratio = np.log2(np.maximum(temporal.maps["hf_ratio"], 1e-30))
        out.append(_map(assets, "temporal_hf_ratio", log_ratio, kind="signed",
                        vmin=-LOG2_RANGE, vmax=LOG2_RANGE,
                        title="Temporal high-frequency energy, method / reference",
                        label="log2 ρ(x): red, more than the reference; blue, less"))
    return out


def _map(assets: Assets, name: str, values: np.ndarray, *, kind: str, vmin: float,
         vmax: float, title: str, label: str) -> dict[str, Any]:
    shown, _ = images.downsample(np.asarray(values)[::-1], max_size=PANEL_SIZE)
    return {"title": title, "label": label, "vmin": vmin, "vmax": vmax,
            "src": assets.add(f"{name}.png", images.false_colour_png(shown, kind=kind,
                                                                     vmin=vmin, vmax=vmax)),
            "bar": assets.add(f"colourbar_{name}.png",
                              images.colour_bar_png(kind=kind, vmin=vmin, vmax=vmax))}


def temporal_section(comparison: SceneComparison, assets: Assets) -> dict[str, Any] | None:
    """The template context of the temporal section, or None when the study did not
    run. Writes (or embeds) the animation, the plots and the maps through ``assets``."""
    temporal = getattr(comparison, "temporal", None)
    if temporal is None:
        return None
    frames = animation_frames(temporal)
    webp = animated_webp(frames, fps=temporal.fps)
    name = f"temporal_{temporal.view}.webp"
    strip_png = figure_bytes(frame_strip_figure(
        temporal, title=f"{comparison.name} ({comparison.method}): Fig. 8 analogue"), fmt="png")
    return {
        "view": temporal.view,
        "frames": temporal.frames,
        "fps": temporal.fps,
        "times": json.dumps([round(t, 6) for t in temporal.times]),
        "width": frames[0].shape[1], "height": frames[0].shape[0],
        # Small frames are shown enlarged by a whole factor (pixelated), up to 768 px.
        "zoom": max(1, DISPLAY_WIDTH // frames[0].shape[1]),
        "panel_width": (frames[0].shape[1] - 2 * GAP) // 3,
        "animation": assets.add(name, webp, mime="image/webp"),
        "animation_file": name,
        "animation_uri": images.data_uri(webp, mime="image/webp"),
        "animation_bytes": len(webp),
        "diff_range": temporal.diff_range,
        "white": temporal.white,
        "series": assets.add("temporal_series.svg", figure_bytes(time_series_figure(temporal)),
                             mime="image/svg+xml"),
        "strip": assets.add("temporal_strip.png", strip_png),
        "maps": _maps(temporal, assets),
        "summary": temporal.summary,
        "statement": flicker_statement(temporal.summary),
        "formulas": TEMPORAL_FORMULAS,
        "files": temporal.files,
        "table": {"columns": list(temporal.table.columns),
                  "rows": [list(r) for r in temporal.table.rows]},
    }


def temporal_script(section: dict[str, Any] | None) -> str:
    """The page's temporal script: the animation's data: URI, then the player
    (``static/temporal.js``). Empty without a temporal section."""
    if section is None:
        return ""
    player = resources.files("reports").joinpath("static", "temporal.js").read_text("utf-8")
    data = (f"window.causticsTemporal = window.causticsTemporal || {{}};\n"
            f"window.causticsTemporal[{json.dumps(section['view'])}] = "
            f"{json.dumps(section['animation_uri'])};\n")
    return data + player


def _flicker_of(comparison) -> dict[str, Any] | None:
    temporal = getattr(comparison, "temporal", None)
    if temporal is None:
        return None
    region = "caustic" if "caustic" in temporal.summary["flicker"] else "full"
    energy = temporal.summary["hf_energy_ratio"].get(region, {})
    return {"region": region, **temporal.summary["flicker"][region],
            "hf": energy.get("value"), "hf_corrected": energy.get("noise_corrected")}


def _ratio_text(a: float, b: float) -> str:
    if not (np.isfinite(a) and np.isfinite(b)) or a <= 0:
        return "n/a"
    return f"{b / a:.2f}×"


def compare_flicker(scene: str, entries: list[dict[str, Any]]) -> str:
    """One sentence naming the method that flickers least on ``scene`` and by how
    much, from ``entries`` ({"method", "value", "excess", ...} per method)."""
    usable = [e for e in entries if np.isfinite(e["value"])]
    if len(usable) < 2:
        return ""
    best = min(usable, key=lambda e: e["value"])
    others = [e for e in usable if e is not best]
    parts = [f"{o['method']}'s flicker is {_ratio_text(best['value'], o['value'])} "
             f"{best['method']}'s (F {_number(o['value'])} vs {_number(best['value'])}; "
             f"excess over the reference noise {_number(o['excess'])} vs "
             f"{_number(best['excess'])}, {_ratio_text(best['excess'], o['excess'])})"
             for o in others]
    return (f"{scene}: {best['method']} flickers least over the {best['region']} region; "
            + "; ".join(parts) + ".")


def temporal_index(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The index's temporal table: per scene, each method's flicker and energy ratio
    (rows of :func:`reports.build.write_page`), and :func:`compare_flicker`."""
    scenes: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        if row.get("failure"):
            continue
        flicker = _flicker_of(row["c"])
        if flicker is not None:
            scenes.setdefault(row["c"].name, []).append(
                {"method": row["c"].method, "href": row["href"], **flicker})
    return [{"scene": scene, "rows": entries, "statement": compare_flicker(scene, entries)}
            for scene, entries in scenes.items()]
