"""Plumbing shared by the paper figures: scenes, renders, and what each figure writes.

Every figure ``NAME`` writes ``NAME.png`` and ``NAME.pdf`` (matplotlib), the data it
was drawn from (``NAME.csv`` and/or ``NAME.json``) and ``NAME.txt``, a caption that
states the settings and the measured numbers. Receiver maps are drawn with +v up
(row 0 = vmin at the bottom); images are tone-mapped with the reference's white
point (``scenes.colour.tonemap``) so both sides of a comparison share one curve.

No figure is written with two of its texts over each other: :meth:`FigureContext.save`
first draws it with Agg and compares the boxes of every text the draw puts on the
page (:func:`text_overlaps`: suptitle, titles, axis and colour-bar labels, tick
labels, legends, annotations), every pair, tick labels of one axis included; two
boxes sharing more than :data:`OVERLAP_TOLERANCE_PX` in both directions raise
:class:`FigureTextOverlapError`, which names the figure and both texts.
"""

from __future__ import annotations

import dataclasses
import io
import itertools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.text import Annotation, Text

from harness.compare.evaluate import exposure_for, score_value
from harness.compare.outputs import write_json, write_table
from harness.compare.regions import scene_caustic_region
from renderers.caustics_mapping import create_context, render
from renderers.mitsuba.reference import render_reference
from reports.records import Table
from scenes import Scene, load_scene, with_settings
from scenes.colour import tonemap, white_point
from scenes.errors import HarnessError
from scenes.files import atomic_write_bytes

__all__ = ["OVERLAP_TOLERANCE_PX", "QUICK", "FigureContext", "FigureResult",
           "FigureTextOverlapError", "TextOverlap", "default_scenes_dir", "receiver_scores",
           "text_overlaps"]

#: Settings of a quick run (tests, a first look): small budgets and images. The
#: reference stops at its starting budget (a target noise of 100 %, which every caustic
#: region meets there; a scene's own 1 % would trace on toward its 120 s time cap).
QUICK = {"photons": 300_000, "seeds": 2, "spp": 4, "target_noise": 1.0, "grid": 64,
         "caustic_map": 256, "positions_map": 256, "shadow_map": 256,
         "receiver_map": [96, 96]}


#: Two text boxes overlap when their window extents share more than this many pixels
#: (at the figure's own dpi) in both directions: a pixel of anti-aliased ink, not a
#: collision a reader would see.
OVERLAP_TOLERANCE_PX = 1.0


@dataclass(frozen=True)
class TextOverlap:
    """Two drawn texts of one figure whose boxes overlap.

    ``first`` and ``second`` describe each text (its role, the axes it belongs to, its
    first words); ``width_px`` and ``height_px`` are the size of the shared box in
    pixels at the figure's dpi.
    """

    first: str
    second: str
    width_px: float
    height_px: float

    def __str__(self) -> str:
        return (f"{self.first} overlaps {self.second} "
                f"({self.width_px:.0f} x {self.height_px:.0f} px)")


class FigureTextOverlapError(HarnessError):
    """A figure would be written with two (or more) of its texts over each other."""

    def __init__(self, name: str, overlaps: list[TextOverlap]) -> None:
        self.name = name
        self.overlaps = tuple(overlaps)
        count = ("two texts overlap:" if len(overlaps) == 1
                 else f"{len(overlaps)} pairs of texts overlap, the first:")
        lines = [f"figure {name}: {count} {overlaps[0]}"]
        lines += [f"{name}: {o}" for o in overlaps[1:]]
        super().__init__("\n".join(lines))


def _quote(text: Text, limit: int = 48) -> str:
    """The text's content on one line, shortened to ``limit`` characters."""
    words = " ".join(text.get_text().split())
    return repr(words if len(words) <= limit else words[:limit - 1] + "…")


def _axes_name(figure, ax, *, with_title: bool = True) -> str:
    """``axes N`` (its index in ``figure.axes``; ``colour bar N`` for a colour bar's),
    followed by its title's first words when it has one and ``with_title``."""
    index = figure.axes.index(ax) if ax in figure.axes else "?"
    kind = "colour bar" if hasattr(ax, "_colorbar") else "axes"
    title = " ".join(ax.get_title().split()) if with_title else ""
    return f"{kind} {index}" + (f" ({title[:32]!r})" if title else "")


def _describe(figure, text: Text) -> str:
    """What ``text`` is (suptitle, a title, a label, a tick label, a legend's text, an
    annotation), where it is, and what it says."""
    if text is getattr(figure, "_suptitle", None):
        return f"suptitle {_quote(text)}"
    for ax in figure.axes:
        where = _axes_name(figure, ax)
        roles = {id(ax.title): "title", id(ax._left_title): "left title",
                 id(ax._right_title): "right title",
                 id(ax.xaxis.label): "x label", id(ax.yaxis.label): "y label",
                 id(ax.xaxis.offsetText): "x offset text",
                 id(ax.yaxis.offsetText): "y offset text"}
        for axis_name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            for tick in (*axis.majorTicks, *axis.minorTicks):
                roles[id(tick.label1)] = roles[id(tick.label2)] = f"{axis_name} tick label"
        legend = ax.get_legend()
        if legend is not None:
            roles[id(legend.get_title())] = "legend title"
            roles.update((id(t), "legend text") for t in legend.get_texts())
        if text is ax.title:
            return f"title of {_axes_name(figure, ax, with_title=False)} {_quote(text)}"
        if id(text) in roles:
            return f"{roles[id(text)]} of {where} {_quote(text)}"
        if text.axes is ax:
            kind = "annotation" if isinstance(text, Annotation) else "text"
            return f"{kind} in {where} {_quote(text)}"
    for legend in figure.legends:
        if text is legend.get_title() or text in legend.get_texts():
            return f"figure legend text {_quote(text)}"
    return f"figure text {_quote(text)}"


def _drawn_texts(figure) -> tuple[list[Text], Any]:
    """Every Text artist that an Agg draw of ``figure`` actually draws, and the
    renderer.

    Visible, non-empty texts are not enough: an axes with its axis switched off keeps
    visible tick labels that are never drawn, and a locator proposes ticks beyond the
    view limits that are dropped at draw time. So each text's ``draw`` is wrapped (on
    the instance, nothing global), the figure drawn, and the texts that reached
    ``Text.draw`` with something to draw are kept. A first draw lays the figure out and
    creates its tick labels; the recording draw is the second.
    """
    canvas = figure.canvas if isinstance(figure.canvas, FigureCanvasAgg) else \
        FigureCanvasAgg(figure)
    canvas.draw()
    drawn: dict[int, Text] = {}
    texts = figure.findobj(match=Text)

    def recording(text: Text):
        original = text.draw

        def draw(renderer, *args, **kwargs):
            if text.get_visible() and text.get_text().strip():
                drawn[id(text)] = text
            return original(renderer, *args, **kwargs)
        return draw

    try:
        for text in texts:
            text.draw = recording(text)
        canvas.draw()
    finally:
        for text in texts:
            vars(text).pop("draw", None)
    # Annotation.draw returns early (before Text.draw) when its point is outside the
    # axes; its box is then not on the page.
    kept = [t for t in drawn.values()
            if not isinstance(t, Annotation) or t._check_xy(canvas.get_renderer())]
    return kept, canvas.get_renderer()


def text_overlaps(figure, *, tolerance_px: float = OVERLAP_TOLERANCE_PX) -> list[TextOverlap]:
    """Pairs of drawn texts of ``figure`` whose boxes overlap.

    The figure is drawn with the Agg renderer at its own dpi; every text it draws is
    collected (suptitle, axes titles, axis labels, tick labels, colour-bar labels,
    legend titles and texts, annotations, free texts) with its window extent, the
    axis-aligned box of its ink and line spacing, rotated texts included. Two boxes
    overlap when their intersection is wider *and* taller than ``tolerance_px``. Every
    pair is checked, tick labels of one axis with each other too.

    Returns
    -------
    list of TextOverlap
        Empty when no two texts overlap; otherwise one entry per overlapping pair, in
        drawing order.
    """
    texts, renderer = _drawn_texts(figure)
    boxes = [(t, t.get_window_extent(renderer)) for t in texts]
    overlaps = []
    for (a, box_a), (b, box_b) in itertools.combinations(boxes, 2):
        width = min(box_a.x1, box_b.x1) - max(box_a.x0, box_b.x0)
        height = min(box_a.y1, box_b.y1) - max(box_a.y0, box_b.y0)
        if width > tolerance_px and height > tolerance_px:
            overlaps.append(TextOverlap(_describe(figure, a), _describe(figure, b),
                                        float(width), float(height)))
    return overlaps


def default_scenes_dir() -> Path:
    """The repository's ``scenes/`` folder (beside the ``harness`` package)."""
    return Path(__file__).resolve().parents[2] / "scenes"


@dataclass(frozen=True)
class FigureResult:
    """What one figure produced: its name, caption and the files written."""

    name: str
    caption: str
    files: tuple[str, ...]


@dataclass
class FigureContext:
    """Renders and output for the figures; one GL context shared by all."""

    out_dir: Path
    scenes_dir: Path = field(default_factory=default_scenes_dir)
    quick: bool = False
    cache: str | None = None
    progress: bool = False
    _gl: Any = None

    def scene(self, name: str, **settings: Any) -> Scene:
        """A committed scene with quick-mode settings (if quick) and ``settings``."""
        scene = load_scene(self.scenes_dir / f"{name}.toml")
        overrides = {**(QUICK if self.quick else {}), **settings}
        scene = with_settings(scene, overrides) if overrides else scene
        if self.quick:
            camera = dataclasses.replace(scene.camera, resolution=(128, 128))
            scene = dataclasses.replace(scene, camera=camera)
        return scene

    def realtime(self, scene: Scene):
        """Caustics-mapping render (``RenderResult``) on the shared context."""

        if self._gl is None:
            self._gl = create_context()
        render(scene, ctx=self._gl)  # warm-up: shader compilation is not frame time
        return render(scene, ctx=self._gl)

    def reference(self, scene: Scene):
        """Mitsuba reference (``RenderResult``), from the cache when present."""

        return render_reference(scene, cache=self.cache, progress=self.progress)

    def region(self, scene: Scene, receiver: int = 0) -> np.ndarray:
        """The scene's caustic region of ``receiver`` (H, W) bool, as ``compare`` has it:
        thresholded on the independent reference (the disjoint seeds ``seed + K`` to
        ``seed + 2K − 1``, cached like the reference), never on the scored one."""

        s = scene.settings
        independent = self.reference(with_settings(scene, {"seed": s.seed + s.seeds}))
        return scene_caustic_region(np.asarray(independent.receivers[receiver].irradiance))

    def close(self) -> None:
        if self._gl is not None:
            self._gl.release()
            self._gl = None

    # ------------------------------------------------------------------ writing

    def save(self, name: str, figure, *, caption: str, table: Table | None = None,
             data: dict | None = None) -> FigureResult:
        """Write PNG, PDF, data and caption of one figure (atomically).

        Raises
        ------
        FigureTextOverlapError
            When two texts of ``figure`` overlap (:func:`text_overlaps`); nothing is
            written then.
        """

        overlaps = text_overlaps(figure)
        if overlaps:
            plt.close(figure)
            raise FigureTextOverlapError(name, overlaps)
        files = []
        for fmt, dpi in (("png", 150), ("pdf", None)):
            buffer = io.BytesIO()
            figure.savefig(buffer, format=fmt, dpi=dpi, bbox_inches="tight")
            atomic_write_bytes(self.out_dir / f"{name}.{fmt}", buffer.getvalue())
            files.append(f"{name}.{fmt}")
        plt.close(figure)
        if table is not None:
            write_table(self.out_dir / f"{name}.csv", table)
            files.append(f"{name}.csv")
        if data is not None:
            write_json(self.out_dir / f"{name}.json", data)
            files.append(f"{name}.json")
        atomic_write_bytes(self.out_dir / f"{name}.txt", (caption + "\n").encode("utf-8"))
        files.append(f"{name}.txt")
        return FigureResult(name, caption, tuple(files))


def receiver_scores(method: np.ndarray, reference: np.ndarray, *, region: np.ndarray
                    ) -> dict[str, float]:
    """relMSE, SSIM and FLIP of a receiver map over the scene's caustic ``region``
    (:meth:`FigureContext.region`), and the total-flux ratio over the whole map."""

    mask = np.asarray(region, bool)
    exposure = exposure_for(reference)
    out = {m: score_value(m, method, reference, mask=mask, exposure=exposure)
           for m in ("relmse", "ssim", "flip")}
    out["flux_ratio"] = score_value("flux_ratio", method, reference,
                                    mask=np.ones(mask.shape, bool), exposure=exposure)
    return out


def show(ax, image: np.ndarray, *, white: float, title: str, receiver: bool) -> None:
    """Tone-mapped image on ``ax``; receiver maps with +v up."""
    ax.imshow(tonemap(image, white=white), origin="lower" if receiver else "upper",
              interpolation="nearest")
    ax.set_title(title, fontsize=8)
    ax.set_axis_off()


def shared_white(reference: np.ndarray) -> float:
    """The reference's white point (99th-percentile luminance)."""
    return white_point(reference)
