"""Underwater figures: 5 (non-planar receivers) and 8 (the water animation)."""

from __future__ import annotations

import dataclasses

import matplotlib.pyplot as plt

from harness.figures.common import FigureContext, receiver_scores, shared_white, show
from harness.studies.runner import frame_seconds
from reports.records import Table

FRAME_TIMES = (0.4, 0.9, 1.4)


#: Receiver scores tabulated per row, in column order.
_SCORES = ("relmse", "ssim", "flip", "flux_ratio")


def figure_05(ctx: FigureContext):
    """Fig. 5: caustics on non-planar receivers (rugged seabed and a rock mesh)."""

    scene = ctx.scene("seabed")
    ref, method = ctx.reference(scene), ctx.realtime(scene)
    fig, axes = plt.subplots(2, 2, figsize=(6.4, 6.4))
    rows = []
    for i, name in enumerate(("seabed (heightfield)", "rock (mesh)")):
        reference = ref.receivers[i].irradiance
        white = shared_white(reference)
        show(axes[i, 0], method.receivers[i].irradiance, white=white, receiver=True,
             title=f"{name}: caustics mapping")
        show(axes[i, 1], reference, white=white, receiver=True, title=f"{name}: reference")
        scores = receiver_scores(method.receivers[i].irradiance, reference)
        rows.append({"receiver": name, **{k: scores[k] for k in _SCORES}})
    table = Table.from_records(("receiver", *_SCORES), rows)
    caption = ("Fig. 5 analogue: underwater caustics on a rugged heightfield and a rock "
               f"mesh ({frame_seconds(method.timings) * 1e3:.1f} ms per frame). " + "; ".join(
                   f"{r['receiver']}: relMSE {r['relmse']:.3g}, SSIM {r['ssim']:.3f}, "
                   f"flux ratio {r['flux_ratio']:.3f}" for r in rows))
    return ctx.save("fig05", fig, caption=caption, table=table)


def figure_08(ctx: FigureContext):
    """Fig. 8: frames of the water animation: a plop spreads over the waves."""

    base = ctx.scene("water_pool")
    fig, axes = plt.subplots(2, len(FRAME_TIMES), figsize=(3 * len(FRAME_TIMES), 6.2))
    rows = []
    for j, t in enumerate(FRAME_TIMES):
        water = dataclasses.replace(base.objects[0], time=t)
        scene = dataclasses.replace(base, objects=(water,))
        ref, method = ctx.reference(scene), ctx.realtime(scene)
        reference = ref.receivers[0].irradiance
        white = shared_white(reference)
        scores = receiver_scores(method.receivers[0].irradiance, reference)
        ms = frame_seconds(method.timings) * 1e3
        show(axes[0, j], method.receivers[0].irradiance, white=white, receiver=True,
             title=f"t = {t:g} s: caustics mapping ({ms:.1f} ms)")
        show(axes[1, j], reference, white=white, receiver=True,
             title=f"reference, relMSE {scores['relmse']:.3g}")
        rows.append({"time_s": t, **{k: scores[k] for k in _SCORES}, "frame_ms": ms})
    table = Table.from_records(("time_s", *_SCORES, "frame_ms"), rows)
    caption = ("Fig. 8 analogue: pool floor under an animated surface (100x100 vertices, "
               "single refraction, sun). " + "; ".join(
                   f"t={r['time_s']:g} s: relMSE {r['relmse']:.3g}, flux ratio "
                   f"{r['flux_ratio']:.3f}, {r['frame_ms']:.1f} ms" for r in rows))
    return ctx.save("fig08", fig, caption=caption, table=table)
