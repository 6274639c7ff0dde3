"""Bunny figures: 10 (reference vs caustics mapping) and 13a (absorption colours)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from harness.figures.camera import camera_row, object_difference_row
from harness.figures.common import FigureContext, receiver_scores, shared_white, show
from harness.studies.runner import frame_seconds
from reports.records import Table
from scenes.geometry import build_geometry


def figure_10(ctx: FigureContext):
    """Fig. 10: photon-traced reference (a) and caustics mapping (b) of the bunny,
    with the paper preset and, beside it, the strong preset (c)."""

    scene = ctx.scene("bunny")
    ref, method = ctx.reference(scene), ctx.realtime(scene)
    strong = ctx.realtime(ctx.scene("bunny", preset="strong"))
    white = shared_white(ref.camera)
    rwhite = shared_white(ref.receivers[0].irradiance)
    fig, axes = plt.subplots(3, 3, figsize=(9.6, 9.6), layout="constrained")
    show(axes[0, 0], ref.camera, white=white, receiver=False, title="(a) reference camera")
    show(axes[0, 1], method.camera, white=white, receiver=False,
         title="(b) caustics mapping (paper)")
    show(axes[0, 2], strong.camera, white=white, receiver=False,
         title="(c) caustics mapping (strong)")
    show(axes[1, 0], ref.receivers[0].irradiance, white=rwhite, receiver=True,
         title="reference receiver irradiance")
    show(axes[1, 1], method.receivers[0].irradiance, white=rwhite, receiver=True,
         title="paper preset receiver irradiance")
    show(axes[1, 2], strong.receivers[0].irradiance, white=rwhite, receiver=True,
         title="strong preset receiver irradiance")
    objects = object_difference_row(axes[2, 1:], scene=scene, reference=ref,
                                    methods=[("paper preset", method),
                                             ("strong preset", strong)])
    axes[2, 0].set_axis_off()
    region = ctx.region(scene)
    scores = receiver_scores(method.receivers[0].irradiance, ref.receivers[0].irradiance,
                             region=region)
    strong_scores = receiver_scores(strong.receivers[0].irradiance,
                                    ref.receivers[0].irradiance, region=region)
    ms = frame_seconds(method.timings) * 1e3
    strong_ms = frame_seconds(strong.timings) * 1e3
    data = {"scene": scene.name, "grid": scene.settings.grid, "frame_ms": ms,
            "triangles": None, **{f"receiver_{k}": v for k, v in scores.items()},
            "strong_frame_ms": strong_ms,
            **{f"strong_receiver_{k}": v for k, v in strong_scores.items()},
            "reference_photons": ref.metadata["photons"],
            "reference_relative_noise": ref.metadata["relative_noise"],
            "object": objects}

    data["triangles"] = len(build_geometry(scene).objects[0].mesh.faces)
    caption = (f"Fig. 10 analogue: Stanford bunny ({data['triangles']} triangles), double "
               f"refraction. Paper preset: receiver relMSE {scores['relmse']:.3g}, "
               f"SSIM {scores['ssim']:.3f}, "
               f"FLIP {scores['flip']:.3f}, flux ratio {scores['flux_ratio']:.3f}; "
               f"caustics mapping {ms:.1f} ms per frame (grid {scene.settings.grid}). "
               f"Strong preset: relMSE {strong_scores['relmse']:.3g}, flux ratio "
               f"{strong_scores['flux_ratio']:.3f}, {strong_ms:.1f} ms per frame. Over the "
               "bunny (camera): " + "; ".join(
                   f"{o['method']} relMSE {o['object_relmse']:.3g}, SSIM "
                   f"{o['object_ssim']:.3f}, FLIP {o['object_flip']:.3f}" for o in objects)
               + ".")
    return ctx.save("fig10", fig, caption=caption, data=data)


def figure_13a(ctx: FigureContext):
    """Fig. 13a: coloured caustics from absorption: per-channel flux of the absorbing
    bunny relative to the clear one, for both renderers (Beer-Lambert, Eq. 7)."""

    clear, coloured = ctx.scene("bunny"), ctx.scene("colored_bunny")
    results = {(r, s.name): (ctx.reference(s) if r == "reference" else ctx.realtime(s))
               for r in ("reference", "caustics mapping") for s in (clear, coloured)}
    rows = []
    for renderer in ("reference", "caustics mapping"):
        a = results[(renderer, "bunny")].receivers[0].total_flux()
        b = results[(renderer, "colored_bunny")].receivers[0].total_flux()
        ratio = np.where(a > 0, b / np.maximum(a, 1e-30), np.nan)
        rows.append({"renderer": renderer, "transmitted_r": float(ratio[0]),
                     "transmitted_g": float(ratio[1]), "transmitted_b": float(ratio[2])})
    fig, grid = plt.subplots(2, 3, figsize=(9.6, 6.4), layout="constrained")
    ref_img = results[("reference", "colored_bunny")].receivers[0].irradiance
    white = shared_white(ref_img)
    show(grid[0, 0], results[("caustics mapping", "colored_bunny")].receivers[0].irradiance,
         white=white, receiver=True, title="caustics mapping")
    show(grid[0, 1], ref_img, white=white, receiver=True, title="reference")
    grid[0, 2].set_axis_off()
    objects = camera_row(grid[1], scene=coloured,
                         reference=results[("reference", "colored_bunny")],
                         method=results[("caustics mapping", "colored_bunny")])
    table = Table.from_records(("renderer", "transmitted_r", "transmitted_g", "transmitted_b"),
                               rows)
    k = coloured.objects[0].material.absorption
    caption = (f"Fig. 13a analogue: absorbing bunny (K_a = {k[0]:g}, {k[1]:g}, {k[2]:g} 1/m). "
               "Caustic flux relative to the clear bunny (R, G, B): " + "; ".join(
                   f"{r['renderer']} {r['transmitted_r']:.3f}, {r['transmitted_g']:.3f}, "
                   f"{r['transmitted_b']:.3f}" for r in rows)
               + ". Over the bunny (camera): " + "; ".join(
                   f"{o['method']} relMSE {o['object_relmse']:.3g}, FLIP {o['object_flip']:.3f}"
                   for o in objects) + ".")
    return ctx.save("fig13a", fig, caption=caption, table=table, data={"object": objects})
