"""Glass-sphere figures: 6 (estimators vs reference, and the strong preset beside
them), 7 (their differences), 11 (grid 64 vs 128) and 13b (dispersion)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from harness.figures.camera import camera_row, object_difference_row
from harness.figures.common import FigureContext, receiver_scores, shared_white, show
from harness.metrics import false_colour
from harness.studies.runner import frame_seconds
from renderers.caustics_mapping.presets import resolve_settings
from reports.records import Table

METHODS = (("distance impostors (secant)", "secant"), ("caustics mapping (modified)", "modified"))


def _sphere_runs(ctx: FigureContext, iterations: int = 3):
    """The reference and both estimators' renders of glass_sphere (cached per ctx)."""
    key = ("sphere", iterations)
    cache = ctx.__dict__.setdefault("_runs", {})
    if key not in cache:
        base = ctx.scene("glass_sphere")
        runs = {"reference": ctx.reference(base)}
        for _, estimator in METHODS:
            scene = ctx.scene("glass_sphere", estimator=estimator, iterations=iterations)
            runs[estimator] = ctx.realtime(scene)
        runs["strong"] = ctx.realtime(ctx.scene("glass_sphere", preset="strong"))
        cache[key] = runs
    return cache[key]


def figure_06(ctx: FigureContext):
    """Fig. 6: distance impostors (secant), caustics mapping (modified) and the
    reference on the glass sphere, three iterations each (the paper preset), and the
    strong preset beside them."""

    runs = _sphere_runs(ctx)
    ref = runs["reference"]
    region = ctx.region(ctx.scene("glass_sphere"))
    white = shared_white(ref.camera)
    fig, grid = plt.subplots(2, 4, figsize=(12, 6.6), layout="constrained")
    axes = grid[0]
    rows, parts = [], []
    strong = resolve_settings(ctx.scene("glass_sphere", preset="strong").settings)
    entries = [(label, estimator, "paper", 3) for label, estimator in METHODS]
    entries.append(("caustics mapping, strong preset", "strong", "strong", strong.iterations))
    for ax, (label, key, preset, iterations) in zip(axes[:3], entries, strict=True):
        result = runs[key]
        estimator = result.metadata["estimator"]
        scores = receiver_scores(result.receivers[0].irradiance, ref.receivers[0].irradiance,
                                 region=region)
        ms = frame_seconds(result.timings) * 1e3
        rows.append((label, estimator, preset, iterations, scores["relmse"], scores["ssim"],
                     scores["flip"], scores["flux_ratio"], ms))
        show(ax, result.camera, white=white, receiver=False,
             title=f"{label}\nrelMSE {scores['relmse']:.3g}, {ms:.1f} ms")
        parts.append(f"{label}: receiver relMSE {scores['relmse']:.3g}, SSIM "
                     f"{scores['ssim']:.3f}, FLIP {scores['flip']:.3f}, frame {ms:.1f} ms")
    show(axes[3], ref.camera, white=white, receiver=False,
         title=f"reference ({ref.metadata['camera_integrator']})\n"
               f"{ref.metadata['spp']} spp x {ref.metadata['seeds']}")
    scene = ctx.scene("glass_sphere")
    objects = object_difference_row(grid[1, :3], scene=scene, reference=ref,
                                    methods=[(e[0], runs[e[1]]) for e in entries],
                                    bar_panel=grid[1, 3])
    rows = [(*row, o["object_relmse"], o["object_ssim"], o["object_flip"])
            for row, o in zip(rows, objects, strict=True)]
    table = Table(("method", "estimator", "preset", "iterations", "receiver_relmse",
                   "receiver_ssim", "receiver_flip", "flux_ratio", "frame_ms",
                   "object_relmse", "object_ssim", "object_flip"), tuple(rows))
    s = scene.settings
    caption = (f"Fig. 6 analogue: glass sphere, grid {s.grid}, caustic map {s.caustic_map}, "
               f"3 iterations (paper preset; the strong preset: its safeguarded "
               f"{strong.estimator}, {strong.iterations} iterations). " + "; ".join(parts)
               + ". Over the sphere (camera): " + "; ".join(
                   f"{o['method']} relMSE {o['object_relmse']:.3g}, FLIP {o['object_flip']:.3f}"
                   for o in objects)
               + f". Reference: {ref.metadata['photons']} "
               f"photons x {ref.metadata['seeds']} seeds (relative noise "
               f"{ref.metadata['relative_noise']:.3g}). Times on llvmpipe unless stated.")
    return ctx.save("fig06", fig, caption=caption, table=table)


def figure_07(ctx: FigureContext):
    """Fig. 7: difference images of Fig. 6's two methods against the reference
    (receiver irradiance, signed, one shared symmetric colour scale)."""

    runs = _sphere_runs(ctx)
    ref = runs["reference"].receivers[0].irradiance
    diffs = {e: runs[e].receivers[0].irradiance - ref for _, e in METHODS}
    limit = float(max(np.percentile(np.abs(d.mean(axis=-1)), 99.5) for d in diffs.values()))
    limit = limit or 1.0
    fig, axes = plt.subplots(1, 2, figsize=(6.4, 3.4), layout="constrained")
    rows = []
    for ax, (label, estimator) in zip(axes, METHODS, strict=True):
        d = diffs[estimator].mean(axis=-1)
        ax.imshow(false_colour(d, vmin=-limit, vmax=limit), origin="lower")
        ax.set_title(label, fontsize=8)
        ax.set_axis_off()
        rows.append({"method": label, "mean_abs_w_m2": float(np.abs(d).mean()),
                     "p99_abs_w_m2": float(np.percentile(np.abs(d), 99)),
                     "min_w_m2": float(d.min()), "max_w_m2": float(d.max())})
    mappable = plt.cm.ScalarMappable(cmap="RdBu_r", norm=plt.Normalize(-limit, limit))
    bar = fig.colorbar(mappable, ax=axes, shrink=0.8)
    bar.set_label("method − reference, W/m²", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    table = Table.from_records(("method", "mean_abs_w_m2", "p99_abs_w_m2", "min_w_m2",
                                "max_w_m2"), rows)
    caption = ("Fig. 7 analogue: signed difference of receiver irradiance against the "
               "reference. " + "; ".join(f"{r['method']}: mean |d| {r['mean_abs_w_m2']:.3g} "
                                           f"W/m², p99 {r['p99_abs_w_m2']:.3g}" for r in rows))
    return ctx.save("fig07", fig, caption=caption, table=table)


def figure_11(ctx: FigureContext):
    """Fig. 11: refractive grid 64x64 vs 128x128: gaps between splats."""

    ref = ctx.reference(ctx.scene("glass_sphere"))
    reference = ref.receivers[0].irradiance
    white = shared_white(reference)
    fig, axes = plt.subplots(1, 3, figsize=(9, 3.2))
    rows = []
    mask = ctx.region(ctx.scene("glass_sphere"))
    # Fixed-size splats (1 texel of a fine 1024² map, 512² in quick mode), like the
    # paper's point sprites, make the spacing between splats of a coarse grid visible;
    # the grid-relative default splat width would hide it.
    fine = 512 if ctx.quick else 1024
    for ax, grid in zip(axes[:2], (64, 128), strict=True):
        result = ctx.realtime(ctx.scene("glass_sphere", grid=grid, caustic_map=fine,
                                        splat_sigma=1.0))
        image = result.receivers[0].irradiance
        scores = receiver_scores(image, reference, region=mask)
        # A gap: a texel of the reference's caustic with under 10 % of its light.
        gaps = float(np.mean(image.mean(axis=-1)[mask] < 0.1 * reference.mean(axis=-1)[mask]))
        rows.append({"grid": grid, "receiver_relmse": scores["relmse"], "gap_fraction": gaps,
                     "frame_ms": frame_seconds(result.timings) * 1e3})
        show(ax, image, white=white, receiver=True,
             title=f"grid {grid}: relMSE {scores['relmse']:.3g}, gaps {gaps:.1%}")
    show(axes[2], reference, white=white, receiver=True, title="reference")
    table = Table.from_records(("grid", "receiver_relmse", "gap_fraction", "frame_ms"), rows)
    caption = (f"Fig. 11 analogue: receiver irradiance with a 64² and a 128² refractive grid, "
               f"{fine}² caustic map, fixed 1-texel splats. "
               + "; ".join(f"grid {r['grid']}: relMSE {r['receiver_relmse']:.3g}, "
                           f"{r['gap_fraction']:.1%} of caustic texels below 10 % of the "
                           f"reference (gaps), {r['frame_ms']:.1f} ms" for r in rows))
    return ctx.save("fig11", fig, caption=caption, table=table)


def figure_13b(ctx: FigureContext):
    """Fig. 13b: dispersion: one IOR per RGB channel; the channels' caustic centroids
    separate, and both renderers must separate them the same way."""

    scene = ctx.scene("dispersion_sphere")
    ref, method = ctx.reference(scene), ctx.realtime(scene)
    extent = ref.receivers[0].extent
    fig, grid = plt.subplots(2, 3, figsize=(9.6, 6.4), layout="constrained")
    axes = grid[0, :2]
    grid[0, 2].set_axis_off()
    objects = camera_row(grid[1], scene=scene, reference=ref, method=method)
    rows = []
    white = shared_white(ref.receivers[0].irradiance)
    for ax, (label, result) in zip(axes, (("caustics mapping", method), ("reference", ref)),
                                   strict=True):
        image = result.receivers[0].irradiance
        show(ax, image, white=white, receiver=True, title=label)
        rows.extend(dict(zip(("centroid_u_m", "centroid_v_m", "radius_m"),
                             _centroid(image[..., c], extent), strict=True),
                         renderer=label, channel=channel)
                    for c, channel in enumerate("RGB"))
    table = Table.from_records(("renderer", "channel", "centroid_u_m", "centroid_v_m",
                                "radius_m"), rows)
    radii = {r["renderer"]: [x["radius_m"] for x in rows if x["renderer"] == r["renderer"]]
             for r in rows}
    spread = {name: max(values) - min(values) for name, values in radii.items()}
    caption = ("Fig. 13b analogue: dispersion (IOR " + ", ".join(
        f"{n:g}" for n in scene.objects[0].material.iors) + "). Spread of the channels' "
        "caustic radii: " + "; ".join(f"{k} {v * 1e3:.1f} mm" for k, v in spread.items())
        + ". Over the sphere (camera): " + "; ".join(
            f"{o['method']} relMSE {o['object_relmse']:.3g}, FLIP {o['object_flip']:.3f}"
            for o in objects) + ".")
    return ctx.save("fig13b", fig, caption=caption, table=table, data={"object": objects})


def _centroid(channel: np.ndarray, extent) -> tuple[float, float, float]:
    """Irradiance-weighted centroid (u, v) and RMS radius of one channel, metres."""
    umin, umax, vmin, vmax = extent
    h, w = channel.shape
    u = umin + (np.arange(w) + 0.5) * (umax - umin) / w
    v = vmin + (np.arange(h) + 0.5) * (vmax - vmin) / h
    uu, vv = np.meshgrid(u, v)
    total = float(channel.sum()) or 1.0
    cu, cv = float((channel * uu).sum() / total), float((channel * vv).sum() / total)
    radius = float(np.sqrt((channel * ((uu - cu) ** 2 + (vv - cv) ** 2)).sum() / total))
    return cu, cv, radius
