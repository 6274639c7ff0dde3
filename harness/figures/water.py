"""Underwater figures: 5 (non-planar receivers) and 8 (the water animation)."""

from __future__ import annotations

import matplotlib.pyplot as plt

from harness.figures.common import FigureContext, receiver_scores, shared_white, show
from harness.studies.runner import frame_seconds
from harness.studies.temporal import TemporalOptions, temporal_study
from renderers.caustics_mapping import create_context
from renderers.methods import load_method
from reports.records import Table
from reports.temporal_plots import strip_indices

#: Presets compared in the animation, and the frames of a quick run.
PRESETS = ("paper", "strong")
QUICK_FRAMES = 6
#: Per-frame columns of fig08.csv (from ``temporal.csv``).
_TEMPORAL = ("relmse_caustic", "relmse_caustic_floor", "flicker_caustic",
             "flicker_caustic_floor", "method_ms")


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
        scores = receiver_scores(method.receivers[i].irradiance, reference,
                                 region=ctx.region(scene, i))
        rows.append({"receiver": name, **{k: scores[k] for k in _SCORES}})
    table = Table.from_records(("receiver", *_SCORES), rows)
    caption = ("Fig. 5 analogue: underwater caustics on a rugged heightfield and a rock "
               f"mesh ({frame_seconds(method.timings) * 1e3:.1f} ms per frame). " + "; ".join(
                   f"{r['receiver']}: relMSE {r['relmse']:.3g}, SSIM {r['ssim']:.3f}, "
                   f"flux ratio {r['flux_ratio']:.3f}" for r in rows))
    return ctx.save("fig05", fig, caption=caption, table=table)


def figure_08(ctx: FigureContext):
    """Fig. 8: the water animation as a frame strip (each preset over the reference)
    above the flicker of every frame pair (``harness.studies.temporal``: the reference
    with common random numbers, its independent twin the noise floor)."""

    base = ctx.scene("water_pool")
    frames = QUICK_FRAMES if ctx.quick else base.animation.frames
    results = {}
    gl = create_context()
    try:
        for preset in PRESETS:
            method = load_method(preset)
            scene = method.configure(base)
            results[preset] = temporal_study(scene, method, ctx=gl, options=TemporalOptions(
                frames=frames, cache=ctx.cache))
    finally:
        gl.release()
    reference = results[PRESETS[0]]
    picks = strip_indices(reference.frames, 4)
    fig = plt.figure(figsize=(2.1 * len(picks), 8.4))
    grid = fig.add_gridspec(4, len(picks), height_ratios=(1, 1, 1, 1.1))
    rows_shown = [(f"{p} preset", results[p].method) for p in PRESETS]
    rows_shown.append(("reference", reference.reference))
    for column, index in enumerate(picks):
        for row, (name, sequence) in enumerate(rows_shown):
            ax = fig.add_subplot(grid[row, column])
            show(ax, sequence[index], white=reference.white, receiver=True,
                 title=f"τ = {reference.times[index]:.3f} s\n{name}" if row == 0 else name)
    ax = fig.add_subplot(grid[3, :])
    rows = []
    for preset in PRESETS:
        records = results[preset].table.records()
        ax.plot([r["time_s"] for r in records[1:]], [r["flicker_caustic"] for r in records[1:]],
                "-o", ms=2.5, label=f"{preset}")
        for r in records:
            rows.append({"preset": preset, "frame": r["frame"], "time_s": r["time_s"],
                         **{k: r[k] for k in _TEMPORAL}})
    floor = reference.table.records()
    ax.plot([r["time_s"] for r in floor[1:]], [r["flicker_caustic_floor"] for r in floor[1:]],
            "--", color="0.5", label="noise floor (independent reference)")
    ax.set_yscale("log")
    ax.set_xlabel("τ (s)")
    ax.set_ylabel("flicker F_t (caustic region)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    summary = {p: {"flicker": results[p].summary["flicker"],
                   "hf_energy_ratio": results[p].summary["hf_energy_ratio"],
                   "method_frame_time_ms": results[p].summary["method"]["frame_time_ms"],
                   "run_time_s": results[p].summary["run_time_s"]} for p in PRESETS}
    flicker = {p: summary[p]["flicker"]["caustic"] for p in PRESETS}
    steadier = min(PRESETS, key=lambda p: flicker[p]["value"])
    other = next(p for p in PRESETS if p != steadier)
    ratio = flicker[other]["value"] / flicker[steadier]["value"]
    caption = (f"Fig. 8 analogue: {reference.frames} frames of the pool floor under the "
               f"animated surface at {reference.fps:g} fps (100x100 vertices, single "
               "refraction, sun), caustics mapping over the reference, and the flicker F of "
               "every frame pair (relMSE of the frame-to-frame differences). " + "; ".join(
                   f"{p}: F {flicker[p]['value']:.3g} (noise floor "
                   f"{flicker[p]['noise_floor']:.3g}, excess {flicker[p]['excess']:.3g})"
                   for p in PRESETS)
               + f". {steadier} flickers least: {other}'s flicker is {ratio:.2f}x its own.")
    table = Table.from_records(("preset", "frame", "time_s", *_TEMPORAL), rows)
    return ctx.save("fig08", fig, caption=caption, table=table,
                    data={"presets": summary, "steadier": steadier,
                          "frames": reference.frames, "fps": reference.fps})
