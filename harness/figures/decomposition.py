"""Where the error comes from, on every paper scene: the decomposition study
(``harness.studies.decomposition``) for both presets, drawn as waterfalls.

Writes ``decomposition.{png,pdf}`` (one waterfall per scene and preset),
``decomposition.csv`` (the study's columns, with ``scene`` and ``preset`` first),
``decomposition.json`` (each record: steps, summary, verdicts, fates, run time) and
the caption: the largest error source per scene, the bunny's in full, the paper's
Fig. 10 attribution with its verdict, the exact step on glass_sphere against the
reference's noise floor, and the study's run time on glass_sphere.

The noise floor here is the expected one (2 var / (ref² + ε) from the reference's
per-texel variance; :func:`~harness.studies.decomposition.expected_noise_floor`), so
the figures need no second reference; ``caustics compare`` uses a measured one.
Step 0 (dense exact paths on a 1024² lattice) runs on :data:`DENSE_SCENES` only,
where it costs about 15 s per preset on this 2-core machine. A quick run (the tests)
takes :data:`QUICK_SCENES` only: each study scores four maps with HDR-FLIP, about a
second each here whatever the map's size, and a quick run of every scene took 150 s.
"""

from __future__ import annotations

import os

import matplotlib.pyplot as plt

from harness.figures.common import FigureContext
from harness.studies.decomposition import (
    FIG10_CLAIM,
    SOURCES,
    DecompositionOptions,
    decomposition_study,
)
from harness.studies.runner import RealtimeRunner
from harness.studies.timing import MIN_REPEATS
from renderers.caustics_mapping.methods import PAPER, STRONG
from reports.decomposition import draw_waterfall
from reports.decomposition_records import DECOMPOSITION_COLUMNS, DecompositionRecord
from reports.records import Table

__all__ = ["DENSE_GRID", "DENSE_SCENES", "PAPER_SCENES", "QUICK_SCENES", "figure_decomposition",
           "run_decompositions"]

#: The scenes of the paper's figures (``scenes/*.toml`` beside the harness).
PAPER_SCENES = ("glass_sphere", "bunny", "colored_bunny", "dispersion_sphere", "water_pool",
                "seabed", "metal_ring")
#: Scenes whose decomposition includes step 0 (not in quick mode).
DENSE_SCENES = ("glass_sphere", "bunny")
#: The scene of a quick run: the paper's Fig. 10 (the tests check the glass sphere's
#: decomposition themselves).
QUICK_SCENES = ("bunny",)
DENSE_GRID = 1024


def run_decompositions(ctx: FigureContext) -> dict[tuple[str, str], DecompositionRecord]:
    """The study on every paper scene and preset (cached on ``ctx``)."""
    cache = ctx.__dict__.setdefault("_decompositions", {})
    if cache:
        return cache
    repeats = 1 if ctx.quick else MIN_REPEATS
    for name in QUICK_SCENES if ctx.quick else PAPER_SCENES:
        for method in (PAPER, STRONG):
            scene = method.configure(ctx.scene(name))
            reference = ctx.reference(scene)
            dense = DENSE_GRID if name in DENSE_SCENES and not ctx.quick else None
            with RealtimeRunner(scene, repeats=repeats) as runner:
                cache[(name, method.name)] = decomposition_study(
                    runner, reference.receivers[0],
                    options=DecompositionOptions(dense_grid=dense, repeats=repeats))
    return cache


def figure_decomposition(ctx: FigureContext):
    """Waterfalls of the relMSE each approximation adds, every paper scene, both
    presets; the data and a caption with the numbers (module docstring)."""
    records = run_decompositions(ctx)
    scenes = [n for n in PAPER_SCENES if (n, "paper") in records]
    fig, axes = plt.subplots(len(scenes), 2, figsize=(10.0, 2.6 * len(scenes)), squeeze=False)
    rows, data = [], {}
    for i, name in enumerate(scenes):
        for j, preset in enumerate(("paper", "strong")):
            record = records[(name, preset)]
            draw_waterfall(axes[i, j], record, title=f"{name}: {preset}")
            rows += [{"scene": name, "preset": preset, **r} for r in record.table.records()]
            data[f"{name}/{preset}"] = record.as_dict()
    fig.tight_layout()
    table = Table.from_records(("scene", "preset", *DECOMPOSITION_COLUMNS), rows)
    return ctx.save("decomposition", fig, caption=_caption(ctx, records), table=table,
                    data={"records": data, "cpus": os.cpu_count()})


def _step(record: DecompositionRecord, name: str) -> dict | None:
    return next((r for r in record.table.records() if r["step"] == name), None)


def _caption(ctx: FigureContext, records) -> str:
    parts = ["Fig. 10's attribution tested, and where each paper scene's error comes "
             "from: exact light paths (Mitsuba ray casts, the reference's event chains) on "
             "the method's grid, then the method's approximations one at a time, every step "
             "through the method's own splat passes; bars are the caustic-region relMSE "
             "each step adds (receiver 0)."]
    largest = "; ".join(
        f"{name} {preset}: {SOURCES[records[(name, preset)].largest]}"
        for name in PAPER_SCENES for preset in ("paper", "strong") if (name, preset) in records)
    parts.append(f"Largest source: {largest}.")
    for preset in ("paper", "strong"):
        if ("bunny", preset) in records:
            parts.append(records[("bunny", preset)].summary)
    verdicts = [f"{r.claims[FIG10_CLAIM]}" for key, r in sorted(records.items())
                if key[0] == "bunny" and FIG10_CLAIM in r.claims]
    if verdicts:
        parts.append(f"Paper's attribution ({FIG10_CLAIM}) on the bunny: "
                     + "; ".join(verdicts) + ".")
    for preset in ("paper", "strong"):
        record = records.get(("glass_sphere", preset))
        if record is None:
            continue
        exact, dense = _step(record, "exact"), _step(record, "dense exact")
        floor = record.noise_floor
        text = (f"glass_sphere {preset}: exact step relMSE {exact['relmse']:.3g} at grid "
                f"{record.notes['grid']} (expected noise floor {floor or float('nan'):.3g})")
        if dense is not None and floor:
            text += (f"; dense {record.notes['dense']['grid']}² lattice {dense['relmse']:.3g} "
                     f"= {dense['relmse'] / floor:.2f} × the floor")
        dense_s = record.notes.get("dense", {}).get("wall_s", 0.0)
        text += (f"; study run time {record.run_time_s - dense_s:.1f} s"
                 + (f" (+ {dense_s:.1f} s for step 0)" if dense_s else "") + ".")
        parts.append(text)
    renderers = sorted({r.notes.get("gl_renderer", "?") for r in records.values()})
    parts.append(f"Times: time.perf_counter on this machine ({os.cpu_count()} CPUs; GL: "
                 f"{', '.join(renderers)}).")
    if ctx.quick:
        parts.append(f"Quick settings ({', '.join(QUICK_SCENES)} only): not for reporting.")
    return " ".join(parts)
