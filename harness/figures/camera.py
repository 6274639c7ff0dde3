"""The camera view with the refractive object seen through: Figs. 1 and 9, and the
object difference row that Figs. 6, 10 and 13 add.

Both renderers now draw the object itself (the method with Wyman's image-space
double refraction, the reference with its camera tracer), so every camera figure
shows the object on both sides and the signed luminance difference *over the
object*: the pixels inside its silhouette (``harness.compare.regions.object_region``),
the rest of the frame drawn in grey. The object region's relMSE, SSIM and FLIP go in
the figure's data.
"""

from __future__ import annotations

import textwrap

import matplotlib.pyplot as plt
import numpy as np

from harness.compare.evaluate import exposure_for, score_value
from harness.compare.regions import object_region
from harness.figures.common import FigureContext, shared_white, show
from harness.metrics import false_colour
from harness.studies.runner import frame_seconds
from reports.records import Table
from scenes.colour import luminance, tonemap
from scenes.geometry import build_geometry

__all__ = ["OBJECT_COLUMNS", "camera_row", "figure_01", "figure_09", "object_difference_row",
           "object_scores"]

#: Characters per line of a difference panel's title at 8 pt. The narrowest panel
#: (Fig. 6: four columns in 12 inches, about 2.7 inches each once laid out) holds
#: about 40 characters of DejaVu Sans at 8 pt (4.6 pt a character on average); 36
#: leaves a margin for wide letters.
TITLE_WIDTH = 36

#: Columns of the object-region scores a camera figure tabulates.
OBJECT_COLUMNS = ("scene", "method", "object_relmse", "object_ssim", "object_flip",
                  "object_pixels")


def object_scores(method: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> dict:
    """relMSE, SSIM and FLIP of the camera image over the object region ``mask``,
    at the reference's exposure over the whole frame (as ``compare`` scores it)."""
    exposure = exposure_for(reference)
    out = {f"object_{m}": score_value(m, method, reference, mask=mask, exposure=exposure)
           for m in ("relmse", "ssim", "flip")}
    out["object_pixels"] = int(mask.sum())
    return out


def _difference_title(label: str, scores: dict) -> str:
    """``label − reference`` (on one line when it fits :data:`TITLE_WIDTH`, else the
    label wrapped and ``− reference`` below it) over the object's relMSE and FLIP."""
    head = f"{label} − reference"
    if len(head) > TITLE_WIDTH:
        head = textwrap.fill(label, TITLE_WIDTH) + "\n− reference"
    return (f"{head}\nobject relMSE {scores['object_relmse']:.3g}, "
            f"FLIP {scores['object_flip']:.3f}")


def object_difference_row(axes, *, scene, reference, methods, bar_panel=None) -> list[dict]:
    """Draw, on ``axes`` (one per method), the signed luminance difference method −
    reference over the object (W m^-2 sr^-1, one symmetric scale shared by the row);
    return one row of :data:`OBJECT_COLUMNS` per method.

    The colour bar goes at the left edge of ``bar_panel`` (an otherwise empty panel of
    the figure's grid) when given, else beside the row; a bar beside the row widens
    the margin of its grid column in every row of a constrained layout.
    """
    mask = object_region(scene.camera, build_geometry(scene))
    ref_lum = luminance(reference.camera)
    diffs = [luminance(result.camera) - ref_lum for _, result in methods]
    limit = max((float(np.percentile(np.abs(d[mask]), 99.5)) for d in diffs if mask.any()),
                default=0.0) or 1.0
    grey = tonemap(reference.camera, white=shared_white(reference.camera)).mean(axis=-1)
    rows = []
    for ax, (label, result), diff in zip(axes, methods, diffs, strict=True):
        rgb = np.repeat(0.35 * grey[..., None], 3, axis=-1)
        rgb[mask] = false_colour(diff, vmin=-limit, vmax=limit)[mask] / 255.0
        ax.imshow(rgb, interpolation="nearest")
        scores = object_scores(result.camera, reference.camera, mask)
        # The panel says what is subtracted and the scores; "over the object" goes on
        # the colour bar, once per row, which keeps each title within its panel.
        ax.set_title(_difference_title(label, scores), fontsize=8)
        ax.set_axis_off()
        rows.append({"scene": scene.name, "method": label, **scores})
    mappable = plt.cm.ScalarMappable(cmap="RdBu_r", norm=plt.Normalize(-limit, limit))
    figure = axes[0].figure
    if bar_panel is not None:
        bar_panel.set_axis_off()
        bar = figure.colorbar(mappable, cax=bar_panel.inset_axes((0.0, 0.1, 0.06, 0.8)))
    else:
        bar = figure.colorbar(mappable, ax=list(axes), shrink=0.8)
    bar.set_label("luminance difference over the object, W m⁻² sr⁻¹", fontsize=7)
    bar.ax.tick_params(labelsize=7)
    return rows


def camera_row(axes, *, scene, reference, method) -> list[dict]:
    """Method and reference camera images on ``axes[0]`` and ``axes[1]`` (one tone
    curve, the reference's), and the difference over the object on ``axes[2]``;
    returns the object scores (:data:`OBJECT_COLUMNS`)."""
    white = shared_white(reference.camera)
    show(axes[0], method.camera, white=white, receiver=False, title="caustics mapping camera")
    show(axes[1], reference.camera, white=white, receiver=False, title="reference camera")
    return object_difference_row(axes[2:3], scene=scene, reference=reference,
                                 methods=[("caustics mapping", method)])


def _camera_pair(ctx: FigureContext, name: str):
    """Reference, paper-preset and strong-preset renders of a committed scene."""
    scene = ctx.scene(name)
    return (scene, ctx.reference(scene), ctx.realtime(scene),
            ctx.realtime(ctx.scene(name, preset="strong")))


def _caption_scores(rows: list[dict]) -> str:
    return "; ".join(f"{r['scene']} {r['method']}: object relMSE {r['object_relmse']:.3g}, "
                     f"SSIM {r['object_ssim']:.3f}, FLIP {r['object_flip']:.3f}"
                     for r in rows)


def figure_01(ctx: FigureContext):
    """Fig. 1: the coloured bunny seen through double refraction, caustics mapping
    (both presets) and the reference, with their differences over the bunny."""

    scene, ref, paper, strong = _camera_pair(ctx, "colored_bunny")
    fig, axes = plt.subplots(2, 3, figsize=(9.6, 6.4), layout="constrained")
    white = shared_white(ref.camera)
    methods = [("paper preset", paper), ("strong preset", strong)]
    for ax, (label, result) in zip(axes[0], [*methods, ("reference", ref)], strict=True):
        ms = "" if result is ref else f", {frame_seconds(result.timings) * 1e3:.0f} ms"
        show(ax, result.camera, white=white, receiver=False, title=f"{label}{ms}")
    rows = object_difference_row(axes[1, :2], scene=scene, reference=ref, methods=methods,
                                 bar_panel=axes[1, 2])
    caption = ("Fig. 1 analogue: the absorbing bunny seen through double refraction "
               "(the method's camera pass after Wyman 2005; the reference's camera "
               "tracer). " + _caption_scores(rows) + ".")
    return ctx.save("fig01", fig, caption=caption, table=Table.from_records(OBJECT_COLUMNS,
                                                                          rows))


def figure_09(ctx: FigureContext):
    """Fig. 9: a sphere and the bunny with double refraction: caustics mapping (paper
    preset) against the reference, and the difference over each object."""

    fig, axes = plt.subplots(2, 3, figsize=(9.6, 6.4), layout="constrained")
    rows = []
    for row, name in zip(axes, ("glass_sphere", "bunny"), strict=True):
        scene = ctx.scene(name)
        ref, paper = ctx.reference(scene), ctx.realtime(scene)
        white = shared_white(ref.camera)
        show(row[0], paper.camera, white=white, receiver=False,
             title=f"{name}: caustics mapping, "
                   f"{frame_seconds(paper.timings) * 1e3:.0f} ms")
        show(row[1], ref.camera, white=white, receiver=False, title=f"{name}: reference")
        rows += object_difference_row(row[2:], scene=scene, reference=ref,
                                      methods=[("paper preset", paper)])
    caption = ("Fig. 9 analogue: double refraction for appearance and caustics, sphere "
               "and bunny. " + _caption_scores(rows) + ".")
    return ctx.save("fig09", fig, caption=caption, table=Table.from_records(OBJECT_COLUMNS,
                                                                          rows))
