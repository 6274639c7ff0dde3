"""Plumbing shared by the paper figures: scenes, renders, and what each figure writes.

Every figure ``NAME`` writes ``NAME.png`` and ``NAME.pdf`` (matplotlib), the data it
was drawn from (``NAME.csv`` and/or ``NAME.json``) and ``NAME.txt``, a caption that
states the settings and the measured numbers. Receiver maps are drawn with +v up
(row 0 = vmin at the bottom); images are tone-mapped with the reference's white
point (``reports.display``) so both sides of a comparison share one curve.
"""

from __future__ import annotations

import dataclasses
import io
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from harness.compare.evaluate import exposure_for, score_value
from harness.compare.outputs import write_json, write_table
from harness.compare.regions import caustic_region
from renderers.caustics_mapping import create_context, render
from renderers.mitsuba.reference import render_reference
from reports.display import tonemap, white_point
from reports.records import Table
from scenes import Scene, load_scene, with_settings
from scenes.files import atomic_write_bytes

__all__ = ["QUICK", "FigureContext", "FigureResult", "default_scenes_dir", "receiver_scores"]

#: Settings of a quick run (tests, a first look): small budgets and images.
QUICK = {"photons": 300_000, "seeds": 2, "spp": 4, "grid": 64, "caustic_map": 256,
         "positions_map": 256, "shadow_map": 256, "receiver_map": [96, 96]}


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

    def close(self) -> None:
        if self._gl is not None:
            self._gl.release()
            self._gl = None

    # ------------------------------------------------------------------ writing

    def save(self, name: str, figure, *, caption: str, table: Table | None = None,
             data: dict | None = None) -> FigureResult:
        """Write PNG, PDF, data and caption of one figure (atomically)."""

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


def receiver_scores(method: np.ndarray, reference: np.ndarray) -> dict[str, float]:
    """relMSE, SSIM and FLIP of a receiver map over the reference's caustic region,
    and the total-flux ratio over the whole map."""

    mask = caustic_region(reference)
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
