"""Underwater figures: 5 (non-planar receivers) and 8 (the water animation)."""

from __future__ import annotations

import dataclasses

from harness.compare.records import Table
from harness.figures.common import FigureContext, receiver_scores, shared_white, show
from harness.studies.runner import frame_seconds

FRAME_TIMES = (0.4, 0.9, 1.4)


def figure_05(ctx: FigureContext):
    """Fig. 5: caustics on non-planar receivers (rugged seabed and a rock mesh)."""
    import matplotlib.pyplot as plt  # noqa: PLC0415

    scene = ctx.scene("seabed")
    ref, test = ctx.reference(scene), ctx.realtime(scene)
    fig, axes = plt.subplots(2, 2, figsize=(6.4, 6.4))
    rows = []
    for i, name in enumerate(("seabed (heightfield)", "rock (mesh)")):
        reference = ref.receivers[i].irradiance
        white = shared_white(reference)
        show(axes[i, 0], test.receivers[i].irradiance, white=white, receiver=True,
             title=f"{name}: caustics mapping")
        show(axes[i, 1], reference, white=white, receiver=True, title=f"{name}: reference")
        scores = receiver_scores(test.receivers[i].irradiance, reference)
        rows.append((name, scores["relmse"], scores["ssim"], scores["flip"],
                     scores["flux_ratio"]))
    table = Table(("receiver", "relmse", "ssim", "flip", "flux_ratio"), tuple(rows))
    caption = ("Fig. 5 analogue: underwater caustics on a rugged heightfield and a rock "
               f"mesh ({frame_seconds(test.timings) * 1e3:.1f} ms per frame). " + "; ".join(
                   f"{r[0]}: relMSE {r[1]:.3g}, SSIM {r[2]:.3f}, flux ratio {r[4]:.3f}"
                   for r in rows))
    return ctx.save("fig05", fig, caption=caption, table=table)


def figure_08(ctx: FigureContext):
    """Fig. 8: frames of the water animation: a plop spreads over the waves."""
    import matplotlib.pyplot as plt  # noqa: PLC0415

    base = ctx.scene("water_pool")
    fig, axes = plt.subplots(2, len(FRAME_TIMES), figsize=(3 * len(FRAME_TIMES), 6.2))
    rows = []
    for j, t in enumerate(FRAME_TIMES):
        water = dataclasses.replace(base.objects[0], time=t)
        scene = dataclasses.replace(base, objects=(water,))
        ref, test = ctx.reference(scene), ctx.realtime(scene)
        reference = ref.receivers[0].irradiance
        white = shared_white(reference)
        scores = receiver_scores(test.receivers[0].irradiance, reference)
        ms = frame_seconds(test.timings) * 1e3
        show(axes[0, j], test.receivers[0].irradiance, white=white, receiver=True,
             title=f"t = {t:g} s: caustics mapping ({ms:.1f} ms)")
        show(axes[1, j], reference, white=white, receiver=True,
             title=f"reference, relMSE {scores['relmse']:.3g}")
        rows.append((t, scores["relmse"], scores["ssim"], scores["flip"],
                     scores["flux_ratio"], ms))
    table = Table(("time_s", "relmse", "ssim", "flip", "flux_ratio", "frame_ms"), tuple(rows))
    caption = ("Fig. 8 analogue: pool floor under an animated surface (100x100 vertices, "
               "single refraction, sun). " + "; ".join(
                   f"t={r[0]:g} s: relMSE {r[1]:.3g}, flux ratio {r[4]:.3f}, {r[5]:.1f} ms"
                   for r in rows))
    return ctx.save("fig08", fig, caption=caption, table=table)
