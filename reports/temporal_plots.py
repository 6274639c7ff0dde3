"""Matplotlib plots of the temporal section: the per-frame metrics over time, and
the Fig. 8 analogue (a frame strip of the method over the reference, above the
flicker of every frame pair).

Each figure is returned unsaved; :func:`reports.plots.figure_bytes` serialises it
(SVG for the time series; the strip holds images and is written as PNG).
"""

from __future__ import annotations

import numpy as np

from reports.temporal_records import TemporalComparison
from scenes.colour import tonemap

__all__ = ["STRIP_FRAMES", "frame_strip_figure", "strip_indices", "time_series_figure"]

#: Frames shown in the strip (fewer when the sequence is shorter).
STRIP_FRAMES = 6
_METHOD, _FLOOR = "#1f5fa8", "#8a8f96"


def _pyplot():
    import matplotlib  # noqa: PLC0415 - heavy, only when a plot is drawn

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt  # noqa: PLC0415 - heavy, only when a plot is drawn

    return plt


def _float(values) -> np.ndarray:
    """Floats, with None (a pair frame 0 does not have) as NaN."""
    return np.array([np.nan if v is None else float(v) for v in values], float)


def _no_data(ax, text: str) -> None:
    """Say in the panel why it is empty."""
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, color="0.35")
    ax.set_xticks([])
    ax.set_yticks([])


def strip_indices(frames: int, count: int = STRIP_FRAMES) -> list[int]:
    """``count`` frame indices spread evenly over ``frames`` frames, first and last
    included (every frame when there are fewer)."""
    if frames <= count:
        return list(range(frames))
    return sorted({int(np.rint(i)) for i in np.linspace(0, frames - 1, count)})


def _series(ax, times, values, floors, *, label: str, log: bool) -> None:
    values, floors = _float(values), _float(floors)
    if log:
        values = np.where(values > 0, values, np.nan)
        floors = np.where(floors > 0, floors, np.nan)
    if not (np.isfinite(values).any() or np.isfinite(floors).any()):
        _no_data(ax, f"{label}: no finite value")
        return
    ax.plot(times, values, "-o", color=_METHOD, ms=2.5, lw=1.2, label="method vs reference")
    ax.plot(times, floors, "--", color=_FLOOR, lw=1.0, label="noise floor (independent ref.)")
    if log:
        ax.set_yscale("log")
    ax.set_ylabel(label)
    ax.grid(True, alpha=0.3)


def time_series_figure(temporal: TemporalComparison):
    """Four stacked panels over τ: relMSE, SSIM and FLIP of every frame (caustic
    region) and the flicker F_t of every frame pair (plotted at the later frame),
    each with its noise floor."""
    plt = _pyplot()
    records = temporal.table.records()
    times = [r["time_s"] for r in records]
    figure, axes = plt.subplots(4, 1, figsize=(6.4, 7.2), sharex=True)
    _series(axes[0], times, [r["relmse_caustic"] for r in records],
            [r["relmse_caustic_floor"] for r in records], label="relMSE (caustic)", log=True)
    _series(axes[1], times, [r["ssim_caustic"] for r in records],
            [r["ssim_caustic_floor"] for r in records], label="SSIM (caustic)", log=False)
    _series(axes[2], times, [r["flip_caustic"] for r in records],
            [r["flip_caustic_floor"] for r in records], label="FLIP (caustic)", log=False)
    _series(axes[3], times[1:], [r["flicker_caustic"] for r in records[1:]],
            [r["flicker_caustic_floor"] for r in records[1:]],
            label="flicker F_t (caustic)", log=True)
    axes[0].legend(loc="best", fontsize=7)
    axes[-1].set_xlabel("τ (s since the scene as written)")
    figure.suptitle(f"{temporal.view}: {temporal.frames} frames at {temporal.fps:g} fps",
                    fontsize=9)
    figure.tight_layout()
    return figure


def frame_strip_figure(temporal: TemporalComparison, *, title: str = ""):
    """The Fig. 8 analogue: :func:`strip_indices` frames of the method (top row) and
    the reference (bottom row), tone-mapped with the sequence's white point and
    shown with +v up, over the flicker of every frame pair with its noise floor."""
    plt = _pyplot()
    picks = strip_indices(temporal.frames)
    figure = plt.figure(figsize=(1.7 * max(len(picks), 3), 5.6))
    grid = figure.add_gridspec(3, len(picks), height_ratios=(1, 1, 0.9))
    for column, index in enumerate(picks):
        for row, (name, sequence) in enumerate((("caustics mapping", temporal.method),
                                                ("reference", temporal.reference))):
            ax = figure.add_subplot(grid[row, column])
            ax.imshow(tonemap(sequence[index][::-1], white=temporal.white),
                      interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if row == 0:
                ax.set_title(f"τ = {temporal.times[index]:.3f} s", fontsize=7)
            if column == 0:
                ax.set_ylabel(name, fontsize=7)
    ax = figure.add_subplot(grid[2, :])
    records = temporal.table.records()
    _series(ax, [r["time_s"] for r in records[1:]], [r["flicker_caustic"] for r in records[1:]],
            [r["flicker_caustic_floor"] for r in records[1:]], label="flicker F_t", log=True)
    ax.set_xlabel("τ (s)")
    ax.legend(loc="best", fontsize=7)
    if title:
        figure.suptitle(title, fontsize=9)
    figure.tight_layout()
    return figure
